// A simulation run: controller, duration, seed, reference, parameters, effects, sensors.
// Read from YAML (sim/scenarios/*.yaml) through config::ConfigNode, so that unknown keys and
// out-of-range values fail with file:line:column and the field's path; or built from a preset.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/conditions.hpp"
#include "sim/controller.hpp"
#include "sim/effects.hpp"
#include "sim/parameters.hpp"
#include "sim/plant.hpp"
#include "sim/reference.hpp"
#include "sim/rig_description.hpp"
#include "sim/sensor_faults.hpp"
#include "sim/sensors.hpp"

namespace leakmon::sim {

// Effects that appear inside a run (a friction changing, a transducer shifting, a bias
// appearing): from t_s on the rig runs with `effects`, those present from the start included.
// (A leak alone has its own onset_s.)
struct EffectChange {
  double t_s = 0.0;
  Effects effects;
};

struct Scenario {
  std::string name = "healthy";
  std::string origin;  // "preset paper-fig13" or "scenario path/to/file.yaml", for metadata
  ControllerKind controller = ControllerKind::basic;
  double duration_s = 60.0;
  std::uint64_t seed = 1;
  ReferenceSettings reference;
  // The rig as described (`rig:`, MODEL.md "Other rigs"); the paper's when the scenario names
  // none. `params` starts from it; a `params:` override changes the simulated plant only, so
  // a scenario can run a rig that differs from its description.
  RigDescription rig;
  Parameters params;
  Effects effects;
  std::optional<EffectChange> change;  // effects that appear inside the run
  SensorSettings sensors;
  // Oil temperature and supply set-point over time (MODEL.md "Drifting operating conditions");
  // empty: the stationary rig at 40 degC and ps.
  OperatingConditions conditions;
  // Sensor faults in the recorded channels (MODEL.md "Sensor faults").
  std::vector<SensorFault> faults;
  // Optional capture columns beyond t,xref,u,x,p1,p2,q_int.
  struct Record {
    bool ps = false;    // supply pressure transducer
    bool temp = false;  // oil temperature (RTD)
  } record;
  double sample_rate_hz = 500.0;
  // RK4 step; 0 chooses automatic_integration_step(). Must divide the sample period.
  double integration_step_s = 0.0;

  std::uint64_t samples() const;  // rows of the capture: duration * rate, rounded
};

double integration_step(const Scenario& scenario);  // explicit value or the automatic one

// Throws config::ConfigError ("file:line:column: path: message") on any bad input.
Scenario load_scenario(const std::string& path);
Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name);

// paper-fig10, paper-fig13, paper-fig16 (MODEL.md "Paper experiments"), healthy (60 s, basic,
// no leak), healthy-ft. Throws std::invalid_argument naming the presets on an unknown name.
Scenario preset(std::string_view name, std::uint64_t seed);
std::vector<std::string> preset_names();

}  // namespace leakmon::sim
