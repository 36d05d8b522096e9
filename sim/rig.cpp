#include "sim/rig.hpp"

namespace leakmon::sim {

Rig::Rig(const Scenario& scenario)
    : scenario_(scenario),
      period_(1.0 / scenario.sample_rate_hz),
      reference_(scenario.program, scenario.reference,
                 stream_seed(scenario.seed, RandomStream::reference), scenario.duration_s),
      controller_(scenario.controller, scenario.sample_rate_hz, scenario.params.u_max),
      plant_(scenario.params, scenario.effects,
             stream_seed(scenario.seed, RandomStream::flow_noise), integration_step(scenario)),
      sensors_(scenario.sensors, scenario.effects,
               stream_seed(scenario.seed, RandomStream::sensors)),
      faults_(scenario.faults, scenario.sensors, 0.5 * scenario.params.L,
              stream_seed(scenario.seed, RandomStream::sensor_faults)) {
  plant_.set_oil(scenario.conditions.oil);
}

void Rig::use_effects(const Effects& effects) noexcept {
  plant_.set_effects(effects);
  sensors_.set_effects(effects);
  if (scenario_.integration_step_s <= 0.0) {
    plant_.set_integration_step(
        automatic_integration_step(scenario_.params, effects, scenario_.sample_rate_hz));
  }
}

void Rig::reset() {
  if (changed_) use_effects(scenario_.effects);
  changed_ = false;
  reference_.reset();
  controller_.reset();
  plant_.reset();
  sensors_.reset();
  faults_.reset();
  index_ = 0;
}

void Rig::set_internal_leak(double C_L, double onset_s, double ramp_s) noexcept {
  plant_.set_internal_leak(C_L, onset_s, ramp_s);
}

RigSample Rig::step() noexcept {
  // MODEL.md "Simulation conventions": measure, compute u from the measured position, record,
  // then integrate the next sample with u held.
  const double t = static_cast<double>(index_) * period_;
  // Effects that appear inside the run: from the first sample at or after their time on.
  if (scenario_.change && !changed_ && t >= scenario_.change->t_s) {
    use_effects(scenario_.change->effects);
    changed_ = true;
  }
  // Conditions drift slowly: read at the sample's time, held over the sample.
  const OperatingConditions& conditions = scenario_.conditions;
  if (conditions.any()) {
    plant_.set_conditions(conditions.temperature_at(t),
                          supply_setpoint(scenario_.params.ps, conditions.supply, t));
  }
  const PlantState& s = plant_.state();
  RigSample sample{};
  sample.t = t;
  sample.xref = reference_.at(t);
  const Measurement measured = sensors_.measure(s.x, s.p1_transducer, s.p2_transducer);
  // The servo loop closes on its own healthy feedback; faults live in the recorded channels.
  sample.u = controller_.update(sample.xref, measured.x);
  sample.ps_true = plant_.flows().ps;
  sample.temp_true = plant_.oil_temperature();
  Readings recorded{measured.p1, measured.p2, measured.x, sensors_.supply_pressure(sample.ps_true),
                    sensors_.temperature(sample.temp_true)};
  faults_.apply(t, period_, recorded);
  sample.x = recorded.x;
  sample.p1 = recorded.p1;
  sample.p2 = recorded.p2;
  sample.ps = recorded.ps;
  sample.temp = recorded.temp;
  sample.q_int = plant_.leak_flow();
  sample.x_true = s.x;
  sample.v_true = s.v;
  sample.p1_true = s.p1;
  sample.p2_true = s.p2;
  sample.xs_true = s.xs;
  plant_.advance(sample.u, t, period_);
  ++index_;
  return sample;
}

}  // namespace leakmon::sim
