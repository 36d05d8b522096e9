// The events of a replay or a worker run that a test looks at: those of one kind, and the
// internal_leakage raises.
#pragma once

#include <algorithm>
#include <iterator>
#include <vector>

#include "io/event.hpp"

namespace leakmon::test {

inline std::vector<io::Event> of_kind(const std::vector<io::Event>& events, io::EventKind kind) {
  std::vector<io::Event> out;
  std::copy_if(events.begin(), events.end(), std::back_inserter(out),
               [kind](const io::Event& e) { return e.kind == kind; });
  return out;
}

inline std::vector<io::Event> leak_alarms(const std::vector<io::Event>& events) {
  std::vector<io::Event> out;
  std::copy_if(events.begin(), events.end(), std::back_inserter(out), [](const io::Event& e) {
    return e.kind == io::EventKind::alarm_raised && e.alarm == "internal_leakage";
  });
  return out;
}

}  // namespace leakmon::test
