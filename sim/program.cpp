#include "sim/program.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace leakmon::sim {

std::string_view to_string(PhaseKind kind) {
  switch (kind) {
    case PhaseKind::steps:
      return "steps";
    case PhaseKind::hold:
      return "hold";
    case PhaseKind::sine:
      return "sine";
    case PhaseKind::sweep:
      return "sweep";
    case PhaseKind::triangle:
      return "triangle";
  }
  return "steps";
}

std::optional<PhaseKind> phase_kind_from_string(std::string_view name) {
  for (const PhaseKind kind : kPhaseKinds) {
    if (to_string(kind) == name) return kind;
  }
  return std::nullopt;
}

std::string Phase::notation() const {
  switch (kind) {
    case PhaseKind::steps:
      return "steps";
    case PhaseKind::hold:
      return fmt::format("hold {:.10g}", X);
    case PhaseKind::sine:
      return fmt::format("sine {:.10g} {:.10g}", F, A);
    case PhaseKind::sweep:
      return fmt::format("sweep {:.10g} {:.10g} {:.10g}", F0, F1, A);
    case PhaseKind::triangle:
      return fmt::format("triangle {:.10g} {:.10g}", P, A);
  }
  return "steps";
}

double phase_reference(const Phase& phase, double t_in_phase, double length) noexcept {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const double t = t_in_phase;
  switch (phase.kind) {
    case PhaseKind::steps:
      return 0.0;
    case PhaseKind::hold:
      return phase.X;
    case PhaseKind::sine:
      return phase.A * std::sin(two_pi * phase.F * t);
    case PhaseKind::sweep:
      return phase.A *
             std::sin(two_pi * (phase.F0 * t + (phase.F1 - phase.F0) * t * t / (2.0 * length)));
    case PhaseKind::triangle: {
      // Fraction of the period: up from 0 to +A in the first quarter, down to -A by three
      // quarters, back up to 0 at the period's end.
      const double cycles = t / phase.P;
      const double f = cycles - std::floor(cycles);
      const double shape = f < 0.25 ? 4.0 * f : f < 0.75 ? 2.0 - 4.0 * f : 4.0 * f - 4.0;
      return phase.A * shape;
    }
  }
  return 0.0;
}

std::vector<PhaseSpan> phase_spans(const std::vector<Phase>& program, double run_seconds) {
  std::vector<PhaseSpan> spans;
  double start = 0.0;
  for (std::size_t i = 0; i < program.size(); ++i) {
    const bool last = i + 1 == program.size();
    const double clipped = std::min(start, run_seconds);
    const double end = last ? run_seconds : std::min(start + program[i].duration_s, run_seconds);
    spans.push_back({program[i].kind, clipped, std::max(clipped, end)});
    start += program[i].duration_s;
  }
  return spans;
}

ProgramReference::ProgramReference(const std::vector<Phase>& program,
                                   const ReferenceSettings& steps, std::uint64_t seed,
                                   double run_seconds)
    : program_(program), steps_(steps, seed) {
  double start = 0.0;
  for (std::size_t i = 0; i < program_.size(); ++i) {
    const bool last = i + 1 == program_.size();
    starts_.push_back(start);
    const double given = program_[i].duration_s;
    // The last phase's T defaults to what is left of the run (a sweep then ends at F1 with it).
    lengths_.push_back(last && given <= 0.0 ? std::max(run_seconds - start, 1e-9) : given);
    start += given;
  }
  reset();
}

void ProgramReference::reset() {
  steps_.reset();
  current_ = 0;
  entered_ = false;
}

double ProgramReference::at(double t) noexcept {
  if (program_.empty()) return steps_.at(t);
  while (current_ + 1 < program_.size() && t >= starts_[current_ + 1]) {
    ++current_;
    entered_ = false;
  }
  const Phase& phase = program_[current_];
  if (!entered_) {
    entered_ = true;
    if (phase.kind == PhaseKind::steps) steps_.start_at(starts_[current_]);
  }
  if (phase.kind == PhaseKind::steps) return steps_.at(t);
  return phase_reference(phase, t - starts_[current_], lengths_[current_]);
}

namespace {

double uniform_in(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

}  // namespace

Phase draw_phase(std::mt19937_64& rng, PhaseKind kind, double time_scale) {
  Phase phase;
  phase.kind = kind;
  double minutes_lo = 2.0, minutes_hi = 10.0;
  switch (kind) {
    case PhaseKind::steps:
      break;
    case PhaseKind::hold:
      phase.X = uniform_in(rng, -0.05, 0.05);
      minutes_lo = 1.0;
      break;
    case PhaseKind::sine:
      phase.F = uniform_in(rng, 0.2, 3.0);
      phase.A = uniform_in(rng, 0.005, 0.04);
      break;
    case PhaseKind::sweep:
      phase.F0 = uniform_in(rng, 0.1, 0.5);
      phase.F1 = uniform_in(rng, 1.5, 4.0);
      phase.A = uniform_in(rng, 0.005, 0.03);
      minutes_lo = 1.0;
      minutes_hi = 5.0;
      break;
    case PhaseKind::triangle:
      phase.P = uniform_in(rng, 1.0, 8.0);
      phase.A = uniform_in(rng, 0.01, 0.045);
      break;
  }
  phase.duration_s = 60.0 * uniform_in(rng, minutes_lo, minutes_hi) * time_scale;
  return phase;
}

std::vector<Phase> draw_program(std::mt19937_64& rng, double time_scale,
                                std::optional<PhaseKind> leak_kind, int& leak_phase) {
  auto any_kind = [&] {
    return kPhaseKinds[std::uniform_int_distribution<std::size_t>(0, 4)(rng)];
  };
  const int n = std::uniform_int_distribution<int>(3, 8)(rng);
  std::vector<PhaseKind> kinds;
  for (int i = 0; i < n; ++i) kinds.push_back(any_kind());
  const PhaseKind not_hold[] = {PhaseKind::steps, PhaseKind::sine, PhaseKind::sweep,
                                PhaseKind::triangle};
  kinds[0] =
      rng() % 2 == 0 ? PhaseKind::hold : not_hold[std::uniform_int_distribution<int>(0, 3)(rng)];
  leak_phase = -1;
  if (leak_kind) {
    leak_phase = std::uniform_int_distribution<int>(1, n - 2)(rng);
    kinds[static_cast<std::size_t>(leak_phase)] = *leak_kind;
  }
  std::vector<Phase> program;
  for (const PhaseKind kind : kinds) program.push_back(draw_phase(rng, kind, time_scale));
  return program;
}

double program_seconds(const std::vector<Phase>& program) {
  double total = 0.0;
  for (const Phase& phase : program) total += phase.duration_s;
  return total;
}

}  // namespace leakmon::sim
