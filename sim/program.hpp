// Test programs (MODEL.md "Test programs"): what a test rig's reference does besides the paper's
// pseudorandom steps. A program is a list of phases run in order, the last one to the end of the
// run: `steps` (the paper's steps, sim/reference.hpp), `hold X`, `sine F A`, `sweep F0 F1 A` and
// `triangle P A`, each over its own time t' from the phase's start. The controllers track the
// program's reference through their prefilter F(s) as they track the steps.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "sim/reference.hpp"

namespace leakmon::sim {

enum class PhaseKind { steps, hold, sine, sweep, triangle };
inline constexpr std::array<PhaseKind, 5> kPhaseKinds = {
    PhaseKind::steps, PhaseKind::hold, PhaseKind::sine, PhaseKind::sweep, PhaseKind::triangle};
std::string_view to_string(PhaseKind kind);
std::optional<PhaseKind> phase_kind_from_string(std::string_view name);

// One phase with MODEL.md's symbols; only the kind's own values are read.
struct Phase {
  PhaseKind kind = PhaseKind::steps;
  double X = 0.0;             // hold: position [m]
  double F = 0.0;             // sine: frequency [Hz]
  double F0 = 0.0, F1 = 0.0;  // sweep: frequency at t' = 0 and at t' = T [Hz]
  double P = 0.0;             // triangle: period [s]
  double A = 0.0;             // sine, sweep, triangle: amplitude [m]
  // The phase's length T [s]. 0 only for the last phase: it then lasts to the end of the run.
  // The last phase runs to the end of the run in any case; a length given for it is its sweep's
  // T (a sweep goes on along the same chirp past T).
  double duration_s = 0.0;

  // MODEL.md's notation with the values: "steps", "hold 0.02", "sine 0.5 0.02", ...
  std::string notation() const;
};

// The reference of `phase` at t' = `t_in_phase` seconds from its start, for the kinds that are a
// formula of t' (all but steps, which draws its levels: 0 here). `length` is the phase's T.
//   hold:     X
//   sine:     A sin(2 pi F t')
//   sweep:    A sin(2 pi (F0 t' + (F1 - F0) t'^2 / (2 T)))
//   triangle: constant-speed ramps between +-A with period P, rising from 0 at t' = 0
double phase_reference(const Phase& phase, double t_in_phase, double length) noexcept;

// MODEL.md "Test programs": a phase of `kind` with the table's typical values and length (times
// `time_scale`), each drawn uniformly in its range.
Phase draw_phase(std::mt19937_64& rng, PhaseKind kind, double time_scale);
// 3-8 phases of any kind; half of the programs start with a hold (a set-up, a leak-down test),
// the others with another kind. With `leak_kind` one phase after the first and before the last
// (learning happens in the first; a leak in a hold is judged in the next) takes that kind; its
// index goes to `leak_phase` (-1 without).
std::vector<Phase> draw_program(std::mt19937_64& rng, double time_scale,
                                std::optional<PhaseKind> leak_kind, int& leak_phase);
double program_seconds(const std::vector<Phase>& program);

// Where the phases of a program sit in a run of `run_seconds`: phase i covers
// [start(i), end(i)); the last one ends with the run. Phases that start at or after the run's end
// are never reached (they still have a start and an end: both the run's end).
struct PhaseSpan {
  PhaseKind kind;
  double start, end;  // [s]
};
std::vector<PhaseSpan> phase_spans(const std::vector<Phase>& program, double run_seconds);

// The reference a scenario's controllers track: the program's phases in turn, or with an empty
// program the paper's steps from t = 0 (then exactly sim::Reference, so every run without a
// program is what it was). Each steps phase starts a new level at its start and draws its levels
// from the one seeded stream, continuing where the previous steps phase stopped. Allocates only
// in the constructor.
class ProgramReference {
 public:
  ProgramReference(const std::vector<Phase>& program, const ReferenceSettings& steps,
                   std::uint64_t seed, double run_seconds);
  void reset();
  // The reference at time t; t must not decrease between calls (until reset()).
  double at(double t) noexcept;
  // Index of the phase the last at() fell in (0 without a program).
  std::size_t phase() const { return current_; }

 private:
  std::vector<Phase> program_;
  std::vector<double> starts_, lengths_;
  Reference steps_;
  std::size_t current_ = 0;
  bool entered_ = false;  // whether at() has entered phase current_ yet
};

}  // namespace leakmon::sim
