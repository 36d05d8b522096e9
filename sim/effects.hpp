// The effect library of MODEL.md ("Effect library"): physics the nominal model leaves out.
// Each effect is an optional struct whose member names are the parameter names of MODEL.md,
// so that the model check and the capture metadata use the same vocabulary. Several effects
// may be active at once.
#pragma once

#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace leakmon::sim {

enum class PressureChannel { p1, p2 };
std::string_view to_string(PressureChannel channel);

// Cross-port flow q_int = C_L (p1 - p2). C_L steps (ramp_s = 0) or ramps linearly over ramp_s
// from 0 at onset_s to its value, as the paper's hand-opened needle valve does.
struct InternalLeakage {
  double C_L = 2.0e-12;  // m^3/(s Pa)
  double onset_s = 0.0;
  double ramp_s = 0.0;
};
// Flow from one chamber to tank q_ext,i = C_E (p_i - pt), from onset_s on (a step, or a linear
// ramp over ramp_s, like the internal leak's).
struct ExternalLeakage {
  double C_E = 5e-13;  // m^3/(s Pa)
  int chamber = 1;     // 1 or 2
  double onset_s = 0.0;
  double ramp_s = 0.0;
};
// F_fric = F_C tanh(v / 1e-3).
struct CoulombFriction {
  double F_C = 100.0;  // N
};
// Pressure-dependent bulk modulus (Simscape Fluids form) replacing the constant beta.
struct EntrainedAir {
  double alpha = 0.05;  // free-air volume fraction at atmospheric pressure
};
// Spool dead band: opening sign(o) max(|o| - d, 0), not rescaled.
struct ValveOverlap {
  double d = 0.02;  // fraction of full spool travel
};
// The valve sees u + u0 (before its saturation); the capture records the commanded u.
struct ValveBias {
  double u0 = 0.1;  // V
};
// The true spool time constant, replacing the nominal tau.
struct SpoolLag {
  double tau = 0.01;  // s
};
// ps(t) = ps0 + dP sin(2 pi f t).
struct SupplyRipple {
  double dP = 5e5;  // Pa
  double f = 50.0;  // Hz
};
// ps = ps0 - R_s q_s with q_s the flow out of the supply port (an algebraic loop, solved).
struct SupplyDroop {
  double R_s = 1e10;  // Pa s/m^3
};
// A pressure transducer reads p + offset.
struct SensorOffset {
  double offset = 1e5;  // Pa
  PressureChannel channel = PressureChannel::p1;
};
// A pressure transducer reads p through a first-order lag.
struct SensorLag {
  double tau_s = 0.005;  // s
  PressureChannel channel = PressureChannel::p1;
};

// One parameter of an effect as named in MODEL.md; `channel` is text, everything else numeric.
struct EffectParameter {
  std::string name;
  std::variant<double, std::string> value;
};
struct EffectDescription {
  std::string name;  // MODEL.md's effect name, e.g. "internal_leakage"
  std::vector<EffectParameter> params;
};

class EffectError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct Effects {
  std::optional<InternalLeakage> internal_leakage;
  std::optional<ExternalLeakage> external_leakage;
  std::optional<CoulombFriction> coulomb_friction;
  std::optional<EntrainedAir> entrained_air;
  std::optional<ValveOverlap> valve_overlap;
  std::optional<ValveBias> valve_bias;
  std::optional<SpoolLag> spool_lag;
  std::optional<SupplyRipple> supply_ripple;
  std::optional<SupplyDroop> supply_droop;
  std::optional<SensorOffset> sensor_offset;
  std::optional<SensorLag> sensor_lag;

  // The active effects with their parameters, in the order of MODEL.md's table.
  std::vector<EffectDescription> describe() const;
  bool any() const { return !describe().empty(); }

  // Switches on effect `name` with the given parameters (names as in MODEL.md; missing ones keep
  // the defaults above; internal_leakage and external_leakage also take onset_s and ramp_s). Throws
  // EffectError for an unknown effect or parameter name or a wrongly typed value.
  void enable(std::string_view name, std::span<const EffectParameter> params = {});
  void disable(std::string_view name);

  // The eleven effect names of MODEL.md, in its order.
  static std::span<const std::string_view> names();

 private:
  void enable_unchecked(std::string_view name, std::span<const EffectParameter> params);
};

}  // namespace leakmon::sim
