// Drifting operating conditions (MODEL.md "Drifting operating conditions"): the oil's
// temperature profile and the supply set-point schedule of a scenario. Both change slowly
// against the plant's dynamics, so Rig evaluates them once per sample (at the sample's time)
// and hands them to Plant::set_conditions(), which holds them over the sample.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/oil.hpp"

namespace leakmon::sim {

// Oil temperature T(t) [degC].
//   constant:        T = T_work
//   warm_up:         T = T0 before start_s, then T_work + (T0 - T_work) exp(-(t - start_s)/tau_s)
//   cooler:          T = T_work + amplitude sin(2 pi (t - cooler_start_s) / period_s) from
//                    cooler_start_s on (T_work before): the thermostat's cycle as a sinusoid,
//                    smooth and starting at T_work with no jump
//   warm_up_cooler:  the warm-up plus the cooler's sinusoid; scenario files default
//                    cooler_start_s to start_s + 3 tau_s (the oil within 5 % of T_work), code
//                    that builds a profile sets it explicitly
struct TemperatureProfile {
  enum class Kind { constant, warm_up, cooler, warm_up_cooler };
  Kind kind = Kind::constant;
  double T0 = 20.0;        // degC, warm-up start
  double T_work = 40.0;    // degC, working (or constant) temperature
  double tau_s = 600.0;    // warm-up time constant
  double start_s = 0.0;    // warm-up start (the pump starts)
  double amplitude = 2.0;  // K, cooler cycle
  double period_s = 600.0;
  double cooler_start_s = 0.0;

  double at(double t) const noexcept;
  double minimum() const;  // lowest temperature the profile reaches
  std::string describe() const;
};
std::string_view to_string(TemperatureProfile::Kind kind);

// One change of the supply set-point ps0: from t_s on it moves linearly (over ramp_s; 0 = a
// step) from the value in force to ps [Pa].
struct SupplyChange {
  double t_s = 0.0;
  double ps = 17.2e6;
  double ramp_s = 0.0;
};

// ps0(t) from the nominal ps and the changes, in time order and not overlapping (a change
// starts after the previous ramp has ended; scenarios check this).
double supply_setpoint(double ps_nominal, const std::vector<SupplyChange>& changes,
                       double t) noexcept;

struct OperatingConditions {
  Oil oil = Oil::standard();
  std::optional<TemperatureProfile> temperature;  // none: 40 degC throughout
  std::vector<SupplyChange> supply;               // sorted by t_s

  bool any() const { return temperature.has_value() || !supply.empty(); }
  double temperature_at(double t) const noexcept {
    return temperature ? temperature->at(t) : kReferenceTemperature;
  }
};

}  // namespace leakmon::sim
