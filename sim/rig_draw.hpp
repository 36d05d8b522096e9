// Rigs other than the paper's, for evaluations (MODEL.md "Other rigs"): drawn from the ranges
// real servo rigs span, kept only when the paper's controllers run them (the rig's own
// controller would; ours must close the loop for a capture to mean anything), with a step
// amplitude the rig can track within its stroke and force, and transducers ranged for its
// supply. Also the mis-stated descriptions that the model check must see through.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "sim/controller.hpp"
#include "sim/reference.hpp"
#include "sim/rig_description.hpp"
#include "sim/scenario.hpp"
#include "sim/sensors.hpp"

namespace leakmon::sim {

struct OtherRig {
  RigDescription rig;           // the true rig, every key of rig_keys() stated but the rating
  ReferenceSettings reference;  // the paper's steps, amplitudes scaled to what the rig can do
  SensorSettings sensors;       // MODEL.md's chain, pressure range chosen for the supply
  int attempts = 1;             // draws made until this one ran (rejected ones included)
};

// Draws a rig from MODEL.md's "Other rigs" ranges (bore 25-100 mm, rod 0.4-0.7 D, stroke
// 0.1-1 m, volumes, supply 7-28 MPa, tank 0-1 MPa, beta 0.5-1.5 GPa, mass 2-500 kg, viscous
// friction 50-5000 N s/m, spring 0-500 kN/m, spool 1-20 ms, null leakage 1e-13-2e-12, VG
// 32/46/68), the valve sized for the cylinder (no-load speed Kv sqrt(ps / 2) / A of 0.4-4
// m/s, within Kv's 5e-8-3e-6), until one passes check_viability() under `controller` on two
// references of its own; a rig whose valve saturates on the largest steps gets smaller ones
// (as its user's test would), down to 5 mm.
// Deterministic in `seed`. Throws std::runtime_error when 500 draws in a row fail.
OtherRig draw_other_rig(std::uint64_t seed, ControllerKind controller);

// A scenario running `rig` (description, plant, oil, reference and sensors) for `seconds`.
Scenario other_rig_scenario(const OtherRig& rig, ControllerKind controller, double seconds,
                            std::uint64_t seed);

// The hydraulic mode at mid-stroke, sqrt(beta A^2 (1/V1 + 1/V2) / m) / 2 pi [Hz] (with the
// spring's sqrt(K_s / m) added in quadrature): the paper's rig has it near 75 Hz, inside the
// 62.5-125 Hz band of the level-2 details the index reads.
double hydraulic_mode_hz(const Parameters& params);

// The largest step amplitude [m] the paper's reference may use on this rig: the paper's
// 0.05 m, at most 0.35 of the stroke (the end stops are at L / 2), and at most what 0.45 of
// the force A (ps - pt) holds against the spring (MODEL.md: a load needing more than about
// half of it cannot be tracked).
double max_step_amplitude(const Parameters& params);

struct Viability {
  bool ok = false;
  bool saturated = false;  // refused for the command's saturation (a smaller step may pass)
  std::string reason;      // why not, for logs and tests
};
struct ViabilityLimits {
  double max_saturated = 0.03;   // share of samples with the command at full scale
  double max_pinned = 0.05;      // share with a chamber within 1 % of tank or supply
  double min_correlation = 0.9;  // of position and reference, after the first second
  // Position about its 50 ms moving average, of the step amplitude: 1-3 % on rigs that run
  // well (1.4 % on the paper's), 20 % on one that rings (a limit cycle near the mode).
  double max_ringing = 0.06;
};
// Runs `scenario` for `seconds` (healthy: its effects and faults are ignored) and says whether
// the loop holds within `limits`: finite states and the piston off its end stops, tracking
// without ringing, and only then the chambers and the command's saturation (so that a loop
// that rings is not refused as merely saturated).
Viability check_viability(const Scenario& scenario, double seconds = 12.0,
                          const ViabilityLimits& limits = {});

// `stated` with the value behind `key` (a rig_keys() key with a MODEL.md symbol) multiplied
// by `factor`, as a user who re-adjusted the supply or fitted a stiffer specimen would state
// it. Throws std::invalid_argument for a key without a symbol.
RigDescription misstate(const RigDescription& stated, std::string_view key, double factor);

}  // namespace leakmon::sim
