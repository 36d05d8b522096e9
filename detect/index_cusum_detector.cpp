#include "detect/index_cusum_detector.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "detect/legacy_state.hpp"

namespace leakmon::detect {

namespace {

// d ln(index) / d ln(ps): the spool noise's flow scales with the root of the valve's drop.
constexpr double kSupplyExponent = 0.5;

FeaturePhysics index_physics(const IndexCusumOptions& o) {
  FeaturePhysics physics;
  physics.design_shift = std::log1p(-o.design_drop);
  physics.null_shift = std::log1p(-o.min_drop);
  physics.supply_exponent = kSupplyExponent;
  physics.uses_temperature = true;
  physics.temperature_prior = o.temperature_prior;
  physics.temperature_prior_sigma = o.temperature_prior_sigma;
  physics.oil = o.oil;
  return physics;
}

}  // namespace

IndexCusumDetector::IndexCusumDetector(const IndexCusumOptions& options, double hop_seconds)
    : use_p1_(options.use_p1),
      use_p2_(options.use_p2),
      no_excitation_share_(options.no_excitation_share),
      test_(options, index_physics(options), hop_seconds) {}

// The mean log index of the configured chambers; NaN when one of them has a gap.
double IndexCusumDetector::log_index_of(const Observation& o) const {
  double sum = 0.0;
  int used = 0;
  for (const auto& [use, index] :
       {std::pair{use_p1_, o.index_p1}, std::pair{use_p2_, o.index_p2}}) {
    if (!use) continue;
    if (!(index > 0.0)) return kMissing;  // a configured chamber with a gap: judge nothing
    sum += std::log(index);
    ++used;
  }
  return used > 0 ? sum / used : kMissing;
}

Decision IndexCusumDetector::update(const Observation& observation) {
  const double log_index = log_index_of(observation);
  const FeatureTest::Verdict verdict = test_.update(observation, log_index);
  Decision decision;
  decision.index = std::isnan(log_index) ? kMissing : std::exp(log_index);
  decision.learning = verdict.learning;
  decision.learning_hops_left = verdict.learning_hops_left;
  decision.score = verdict.score;
  decision.baseline = std::isnan(verdict.expected) ? kMissing : std::exp(verdict.expected);
  decision.judge_by_score();
  verdict.apply_to(decision);
  if (decision.judged && decision.index < no_excitation_share_ * decision.baseline) {
    decision.judged = false;
    decision.not_judged_reason = NotJudgedReason::no_excitation;
  }
  return decision;
}

DetectorState IndexCusumDetector::export_state() const {
  DetectorState state(std::string(name()), kStateVersion);
  test_.save(state, "");
  return state;
}

void IndexCusumDetector::import_state(const DetectorState& saved) {
  import_detector_state(*this, saved, kStateVersion,
                        [this](const DetectorState& state) { test_.restore(state, ""); });
}

}  // namespace leakmon::detect
