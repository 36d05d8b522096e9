// The closed-loop rig of MODEL.md's simulation conventions, one 500 Hz sample per step():
// reference -> prefilter + controller (on the *measured* position) -> plant, sensors between.
// Each step measures, computes u, returns the row, then integrates the plant over the next
// sample with u held. Allocation happens only in the constructor.
#pragma once

#include <cstdint>

#include "sim/controller.hpp"
#include "sim/plant.hpp"
#include "sim/program.hpp"
#include "sim/scenario.hpp"
#include "sim/sensor_faults.hpp"
#include "sim/sensors.hpp"

namespace leakmon::sim {

struct RigSample {
  double t;          // s
  double xref;       // m (the program's reference, before the controller's prefilter)
  double u;          // V, as commanded (before valve_bias)
  double x, p1, p2;  // recorded (sensor chain and any sensor fault applied)
  double ps, temp;   // recorded supply pressure [Pa] and oil temperature [degC]
  double q_int;      // true cross-port leak flow [m^3/s]
  double x_true, v_true, p1_true, p2_true, xs_true;
  double ps_true;    // supply pressure (set-point, ripple, droop) [Pa]
  double temp_true;  // oil temperature [degC]
};

class Rig {
 public:
  explicit Rig(const Scenario& scenario);

  RigSample step() noexcept;
  void reset();

  // Injects (or changes) the internal leak at run time; C_L = 0 heals it.
  void set_internal_leak(double C_L, double onset_s, double ramp_s = 0.0) noexcept;

  std::uint64_t index() const { return index_; }  // samples produced so far
  double sample_period() const { return period_; }
  const Scenario& scenario() const { return scenario_; }
  const Plant& plant() const { return plant_; }

 private:
  // The plant's and transducers' effects, with the integration step they need.
  void use_effects(const Effects& effects) noexcept;

  Scenario scenario_;
  double period_;
  ProgramReference reference_;
  Controller controller_;
  Plant plant_;
  Sensors sensors_;
  SensorFaults faults_;
  std::uint64_t index_ = 0;
  bool changed_ = false;  // Scenario::change applied
};

}  // namespace leakmon::sim
