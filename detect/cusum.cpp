#include "detect/cusum.hpp"

namespace leakmon::detect {

void BlockCusum::take_back_after(double t) {
  // In slot order (not by age): the oldest is found by its time.
  const Entry* first = nullptr;
  for (const Entry& e : history_.stored()) {
    if (e.t > t && (first == nullptr || e.t < first->t)) first = &e;
  }
  if (first != nullptr) set(first->before);
}

void BlockCusum::save(DetectorState& state, std::string_view prefix) const {
  state.put(state_key(prefix, "value"), sum_);
  if (history_.capacity() > 0)
    save_ring(state, state_key(prefix, "history"), history_, kEntryFields);
}

void BlockCusum::restore(const DetectorState& state, std::string_view prefix) {
  const double sum = state.get(state_key(prefix, "value"));
  if (!std::isfinite(sum)) throw StateError("'" + state_key(prefix, "value") + "' is not finite");
  set(sum);
  history_.clear();
  if (history_.capacity() > 0) {
    restore_ring(state, state_key(prefix, "history"), history_, kEntryFields);
  }
}

}  // namespace leakmon::detect
