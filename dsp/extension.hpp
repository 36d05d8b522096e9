// Signal extension beyond the ends of a finite signal a[0..n), exactly as PyWavelets'
// downsampling convolution reads it (pywt/_extensions/c/convolution.template.c): the same
// values by the same arithmetic, including repeated reflections when the filter is longer
// than the signal. `at(i)` returns a[i]; only the indices the mode needs are read, so a caller
// that holds just the signal's two edges can pass an accessor over those.
#pragma once

#include <cstddef>

#include "dsp/mode.hpp"

namespace leakmon::dsp {

// Value at index -m (m >= 1) left of a[0]. For the right end, pass a mirrored accessor.
template <class At>
double extend_before_start(Mode mode, std::size_t n, std::size_t m, const At& at) {
  const std::size_t q = m - 1;  // distance from the edge sample, 0 = adjacent
  switch (mode) {
    case Mode::zero:
      return 0.0;
    case Mode::constant:
      return at(0);
    case Mode::smooth:
      if (n < 2) return at(0);
      return at(0) + static_cast<double>(m) * (at(0) - at(1));
    case Mode::symmetric: {
      const std::size_t r = q % (2 * n);
      return r < n ? at(r) : at(2 * n - 1 - r);
    }
    case Mode::reflect: {
      if (n < 2) return at(0);
      const std::size_t r = q % (2 * n - 2);
      return r < n - 1 ? at(r + 1) : at(2 * n - 3 - r);
    }
    case Mode::antisymmetric: {
      const std::size_t r = q % (2 * n);
      return r < n ? -at(r) : at(2 * n - 1 - r);
    }
    case Mode::antireflect: {
      if (n < 2) return at(0);
      // pywt walks outwards, carrying the running edge value `le` through each reflection;
      // repeat that walk so that the rounding is the same.
      double le = at(0);
      double value = le;
      std::size_t walked = 0;
      while (true) {
        for (std::size_t k = 1; k < n; ++k) {
          value = le - (at(k) - at(0));
          if (++walked == m) return value;
        }
        le = value;
        for (std::size_t k = 1; k < n; ++k) {
          value = le + (at(n - 1 - k) - at(n - 1));
          if (++walked == m) return value;
        }
        le = value;
      }
    }
    case Mode::periodic:
      return at(n - 1 - q % n);
    case Mode::periodization: {
      // An odd-length signal is first padded with a copy of its last sample.
      const std::size_t period = n + n % 2;
      const std::size_t r = (period - m % period) % period;
      return r < n ? at(r) : at(n - 1);
    }
  }
  return 0.0;
}

// Value at index n - 1 + m (m >= 1) right of a[n-1].
template <class At>
double extend_after_end(Mode mode, std::size_t n, std::size_t m, const At& at) {
  switch (mode) {
    case Mode::periodic:
      return at((m - 1) % n);
    case Mode::periodization: {
      const std::size_t period = n + n % 2;
      const std::size_t r = (n - 1 + m) % period;
      return r < n ? at(r) : at(n - 1);
    }
    default: {
      auto mirrored = [&](std::size_t i) { return at(n - 1 - i); };
      return extend_before_start(mode, n, m, mirrored);
    }
  }
}

}  // namespace leakmon::dsp
