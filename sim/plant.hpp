// The continuous actuator of MODEL.md (spool, valve, chambers, piston, end stops) with the
// effect library (the rates of sim/actuator.hpp, shared with the model check), integrated by
// fixed-step RK4 over one sample with the command held. Usable
// open-loop (the model check drives it with a measured u) or inside Rig.
//
// The spool flow noise is an Ornstein-Uhlenbeck process drawn by its exact discretisation on a
// fixed grid (kNoiseGridStep = 0.25 ms) and interpolated linearly, so the noise input does not
// depend on the integration step and trajectories converge as the step shrinks.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "sim/actuator.hpp"
#include "sim/effects.hpp"
#include "sim/flow_noise.hpp"
#include "sim/leakage.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::sim {

struct PlantState {
  double xs = 0.0;  // spool position, normalised -1..1
  double x = 0.0;   // piston position [m], 0 at mid-stroke
  double v = 0.0;   // piston velocity [m/s]
  double p1 = 0.0;  // chamber pressures [Pa gauge]
  double p2 = 0.0;
  // Pressures at the transducer outputs: equal to p1, p2 unless sensor_lag delays one.
  double p1_transducer = 0.0;
  double p2_transducer = 0.0;
  // Fluid ledger, integrated with the states (for the mass-balance check): the integral of
  // rho(p_i)/rho(0) times the net port flow into chamber i, with rho(p) = exp(p / beta) the
  // density law implied by the continuity equation at constant beta; and the plain volume of
  // cross-port leakage [m^3].
  double mass_in1 = 0.0;
  double mass_in2 = 0.0;
  double leaked_volume = 0.0;
};

// Every flow and the supply pressure at one instant (the terms of MODEL.md's equations).
struct PlantFlows {
  double ps;              // supply pressure after ripple and droop [Pa]
  double w;               // spool flow noise (fraction of travel)
  double opening;         // effective opening after noise and overlap
  double q1, q2;          // valve flows into chambers 1 and 2, null leakage included [m^3/s]
  double q_supply;        // flow out of the supply port [m^3/s]
  double q_int;           // cross-port leakage 1 -> 2 [m^3/s]
  double q_ext1, q_ext2;  // external leakage to tank [m^3/s]
  double C_L;             // internal leakage coefficient in force now (r C_L: at the oil's
                          // temperature, MODEL.md "Drifting operating conditions")
};

// The RK4 step used when a scenario leaves it at 0: chosen by accuracy (the step-halving test
// in tests/sim judges it) and shortened where an effect makes the plant stiffer (Coulomb
// friction's tanh, light masses); always an integer fraction of the sample period.
double automatic_integration_step(const Parameters& params, const Effects& effects,
                                  double sample_rate_hz);

class Plant {
 public:
  // Allocates nothing after construction. integration_step_s = 0 chooses
  // automatic_integration_step() for 500 Hz samples.
  Plant(const Parameters& params, const Effects& effects, std::uint64_t noise_seed,
        double integration_step_s = 0.0);

  // Rest state of MODEL.md's simulation conventions: x = v = xs = 0, p1 = p2 = (ps + pt)/2,
  // noise restarted from its seed, time 0.
  void reset();
  // Sets an explicit initial state (e.g. a measured one); transducer states follow p1, p2.
  void set_state(const PlantState& state);

  // Integrates from t0 to t0 + dt with the valve command u [V] held. t0 must continue from the
  // previous call's end (the noise grid is indexed by absolute time). Allocation-free.
  void advance(double u, double t0, double dt) noexcept;

  const PlantState& state() const { return state_; }
  double time() const { return time_; }
  double leak_flow() const;  // q_int at state() and time()
  PlantFlows flows() const;  // every flow at state() and time()

  // Replaces the effects at run time (Scenario::change), the state and the operating
  // conditions kept; the leaks' schedules restart from the new effects. Allocation-free.
  void set_effects(const Effects& effects) noexcept;
  // Runtime leak injection (the daemon's sim driver): C_L from onset_s on, ramped over ramp_s.
  void set_internal_leak(double C_L, double onset_s, double ramp_s = 0.0) noexcept;
  // Operating conditions (MODEL.md "Drifting operating conditions"), held until the next call:
  // the oil temperature T [degC] and the supply set-point ps0 [Pa] (ripple and droop act on
  // top). Recomputes the coefficients that follow T through the oil's viscosity ratio
  // r = nu(40)/nu(T): C_n and C_L scale with r, b -> b (0.5 + 0.5/r), beta (and entrained
  // air's E_l) -> beta (1 - 0.003 (T - 40)). At T = 40 and ps0 = ps every coefficient is
  // exactly the nominal one. Allocation-free; Rig calls it once per sample.
  void set_conditions(double oil_temperature_C, double ps0) noexcept;
  // The oil whose viscosity T acts through (ISO VG 46 unless set); re-applies the conditions.
  void set_oil(const Oil& oil);
  double oil_temperature() const { return temperature_; }
  double viscosity_ratio() const { return c_.r; }
  double supply_setpoint() const { return c_.ps; }

  // Turns the mass ledger of PlantState on (costs two exp() per derivative evaluation).
  void enable_ledger(bool on) { ledger_ = on; }

  void set_integration_step(double h);
  double integration_step() const { return step_; }
  const Parameters& parameters() const { return params_; }
  const Effects& effects() const { return effects_; }

 private:
  // The integrated state: PlantState's members in declaration order.
  using Vector = Eigen::Matrix<double, 10, 1>;
  // step_midpoint: where a stepped leak schedule is read (see advance()).
  PlantFlows evaluate(double t, double step_midpoint, double xs, double p1, double p2,
                      double w) const noexcept;
  void rates(double t, double spool_in, const Vector& y, Vector& dy) noexcept;
  void store(const Vector& y);

  Parameters params_;
  Effects effects_;
  ActuatorCoefficients c_;
  FlowNoise noise_;
  LeakSchedule leak_;
  LeakSchedule external_leak_;  // C_L holds C_E; empty when external_leakage is off
  Oil oil_ = Oil::standard();
  double temperature_ = kReferenceTemperature;
  Vector y_;
  PlantState state_;
  double time_ = 0.0;
  double step_midpoint_ = 0.0;
  double step_;
  bool ledger_ = false;
};

}  // namespace leakmon::sim
