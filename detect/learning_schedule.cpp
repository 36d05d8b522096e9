#include "detect/learning_schedule.hpp"

namespace leakmon::detect {

void LearningClock::save(DetectorState& state, std::string_view prefix) const {
  state.put_count(state_key(prefix, "hops_seen"), hops_seen_);
  state.put(state_key(prefix, "learned"), learned_ ? 1.0 : 0.0);
}

void LearningClock::restore(const DetectorState& state, std::string_view prefix) {
  hops_seen_ = state.get_count(state_key(prefix, "hops_seen"));
  learned_ = state.get(state_key(prefix, "learned")) != 0.0;
}

}  // namespace leakmon::detect
