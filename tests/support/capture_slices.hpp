// Parts of an in-memory capture for replay tests: some of its columns (a rig with fewer
// transducers), or the rows of a stretch of source time (a daemon stopped and restarted).
#pragma once

#include <cstddef>
#include <initializer_list>

#include "capture/capture.hpp"

namespace leakmon::test {

// The named columns, in the order given, with the capture's metadata.
inline capture::Capture columns_of(const capture::Capture& capture,
                                   std::initializer_list<const char*> names) {
  capture::Capture out;
  out.metadata = capture.metadata;
  for (const char* name : names) {
    out.columns.push_back(name);
    out.values.push_back(capture.column(name));
  }
  return out;
}

// Every column's rows with from <= t < to.
inline capture::Capture rows_between(const capture::Capture& capture, double from, double to) {
  capture::Capture out;
  out.metadata = capture.metadata;
  out.columns = capture.columns;
  out.values.resize(capture.columns.size());
  const auto& t = capture.column("t");
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < from || t[i] >= to) continue;
    for (std::size_t c = 0; c < capture.columns.size(); ++c) {
      out.values[c].push_back(capture.values[c][i]);
    }
  }
  return out;
}

}  // namespace leakmon::test
