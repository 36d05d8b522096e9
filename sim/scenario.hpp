// A simulation run: controller, duration, seed, reference (the paper's steps or a test program),
// parameters, effects, sensors.
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
#include "sim/program.hpp"
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
  ReferenceSettings reference;  // the paper's steps (the whole run, or a program's steps phases)
  // The test program (MODEL.md "Test programs"): phases in order, the last to the end of the run.
  // Empty: the paper's steps from t = 0.
  std::vector<Phase> program;
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
  // What a scenario file asks for that the rig may not manage (reference_reach()), for
  // `leakmon sim` to print; each "file:line:column: message".
  std::vector<std::string> warnings;

  std::uint64_t samples() const;  // rows of the capture: duration * rate, rounded
};

double integration_step(const Scenario& scenario);  // explicit value or the automatic one

// How far the rig can follow the steps' largest amplitude (MODEL.md "Other rigs"): that
// amplitude as a share of half the stroke (1 or more: beyond the end stops), and the spring's
// force there, K_s amp_max, as a share of the force A (ps - pt) the rig can make (a load that
// needs more than about half of it cannot track the reference).
struct ReferenceReach {
  double stroke_share = 0.0;
  double force_share = 0.0;
};
ReferenceReach reference_reach(const Parameters& params, const ReferenceSettings& reference);
// Beyond these a scenario file is an error; above the warning shares `leakmon sim` warns.
inline constexpr double kStrokeShareError = 1.0, kStrokeShareWarning = 0.8;
inline constexpr double kForceShareError = 0.9, kForceShareWarning = 0.5;

// Throws config::ConfigError ("file:line:column: path: message") on any bad input.
Scenario load_scenario(const std::string& path);
Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name);

// paper-fig10, paper-fig13, paper-fig16 (MODEL.md "Paper experiments"), healthy (60 s, basic,
// no leak), healthy-ft. Throws std::invalid_argument naming the presets on an unknown name.
Scenario preset(std::string_view name, std::uint64_t seed);
std::vector<std::string> preset_names();

}  // namespace leakmon::sim
