#!/usr/bin/python3
"""How much a cross-port leak can be seen in p1 and p2 at all (docs/detection.md, "How far the two
pressures can go"): an upper bound on what any pressure-only detector can extract, set beside the
targets of issue 13.

For each rig and controller it simulates a healthy capture and captures with a leak from the start,
all with the same seed (same reference steps and noise: the pairs differ by the leak alone), cuts
them into the index's 0.8 s blocks (400 samples, Hann window) and takes the 2x2 periodogram matrix
of (p1, p2) per 1.25 Hz bin over 40-125 Hz, where the hydraulic mode (~75 Hz) carries the leak.

Three numbers per case, each an upper bound under a stated idealisation:
  * stationary KL: the Whittle divergence rate between the healthy and the leaky spectra averaged
    over the whole run, the information of a detector that knew the rig's spectrum exactly and
    saw a stationary Gaussian process. The rig is not stationary (every reference step moves the
    operating point), so this overstates what a detector can reach;
  * per block, level known: the Fisher information per 0.8 s block of a hold (p_L = p1 - p2
    within 0.3 MPa over the block), the healthy and leaky spectra of the holds known exactly;
  * per block, level unknown: the same with each block's excitation level as a free parameter —
    every hold sits at another load pressure and so another spool flow gain, which scales the
    mode's excitation; a detector must not read that as damping.
Hann bins overlap: 1.5 bins count as one independent bin (the window's noise bandwidth).

From the per-block bound (level unknown), an ideal CUSUM of the exact log-likelihood ratio
(Gaussian increments, threshold for <= 0.1 false alarms per hour by Siegmund's approximation)
gives the share of leaks found within 60 s and the median delay (Monte Carlo). Steps add a little
more (docs/detection.md: the step integral, 0.4-1.7 spreads per step with integral action only).

Usage: pressure_information_bound.py LEAKMON [WORKDIR] [--friction F_C]   (LEAKMON: build/bin/leakmon)
  --friction F_C: the nominal rig only, with MODEL.md's coulomb_friction of F_C newtons, leaks
  up to 5e-12 (docs/detection.md, "A rig the pressures cannot see a leak on")
"""
import io
import math
import os
import subprocess
import sys

import numpy as np

FS = 500.0
BLOCK = 400  # the index's window, 0.8 s
LO, HI = 32, 101  # bins of 1.25 Hz: 40-125 Hz
HANN_BINS_PER_INDEPENDENT = 1.5
HOLD_PL_RANGE = 3e5  # Pa
SECONDS = 1200
SEED = 5
FALSE_ALARMS_PER_HOUR = 0.1

RIGS = {  # MODEL.md's nominal rig and corners of its calibration spread
    "nominal": {},
    "b +30 %": {"b": 390.0},
    "b -30 %": {"b": 210.0},
    "beta -25 %": {"beta": 5.25e8},
    "spring 120 kN/m": {"K_s": 1.2e5},
}
LEAKS = (5e-13, 1e-12, 2e-12)


def simulate(leakmon, workdir, rig, params, controller, leak, friction=0.0):
    name = f"{rig.replace(' ', '').replace('%', 'pc').replace('/', '')}_{controller}_{leak:g}"
    if friction:
        name += f"_F{friction:g}"
    scenario = os.path.join(workdir, name + ".yaml")
    capture = os.path.join(workdir, name + ".csv")
    if not os.path.exists(capture):
        with open(scenario, "w") as out:
            out.write(f"name: bound\ncontroller: {controller}\nduration_s: {SECONDS}\nseed: {SEED}\n")
            if params:
                out.write("params: {" + ", ".join(f"{k}: {v}" for k, v in params.items()) + "}\n")
            effects = []
            if friction:
                effects.append(f"  coulomb_friction: {{F_C: {friction}}}")
            if leak > 0:
                effects.append(f"  internal_leakage: {{C_L: {leak}, onset_s: 0.002, ramp_s: 0}}")
            if effects:
                out.write("effects:\n" + "\n".join(effects) + "\n")
        subprocess.run([leakmon, "sim", "--scenario", scenario, "--out", capture], check=True,
                       stdout=subprocess.DEVNULL)
    lines = [line for line in open(capture) if not line.startswith("#")]
    names = lines[0].strip().split(",")
    values = np.genfromtxt(io.StringIO("".join(lines[1:])), delimiter=",",
                           usecols=(names.index("p1"), names.index("p2")))
    return values


def periodograms(pressures):
    n = len(pressures) // BLOCK
    x = pressures[: n * BLOCK].reshape(n, BLOCK, 2)
    p_l = x[:, :, 0] - x[:, :, 1]
    hold = (p_l.max(1) - p_l.min(1)) < HOLD_PL_RANGE
    x = x - x.mean(1, keepdims=True)
    spectra = np.fft.rfft(x * np.hanning(BLOCK)[None, :, None], axis=1)[:, LO:HI, :]
    return np.einsum("bki,bkj->bkij", spectra, spectra.conj()), hold


def kl_rate(s0, s1):
    total = 0.0
    for a, b in zip(s0, s1):
        m = np.linalg.solve(a, b)
        total += (np.trace(m) - np.log(np.linalg.det(m))).real - len(a)
    return total / HANN_BINS_PER_INDEPENDENT / (BLOCK / FS)


def block_information(healthy, leaky):
    """Fisher distance per block along the leak: level known, and with the block's level profiled.

    The leak's spectral change is estimated twice, from the first and from the second half of the
    holds, and the squared distance is their cross product: the two estimates' errors are
    independent, so it is unbiased (one estimate squared would add its own estimation noise)."""
    def change(h_blocks, l_blocks):
        s0 = h_blocks.mean(0)
        return np.array([np.linalg.solve(a, b - a) for a, b in zip(s0, l_blocks.mean(0))])
    nh, nl = len(healthy) // 2, len(leaky) // 2
    m_a = change(healthy[:nh], leaky[:nl])
    m_b = change(healthy[nh:], leaky[nl:])
    d2 = np.einsum("kij,kji->k", m_a, m_b).real.sum()
    trace_product = np.einsum("kii->k", m_a).real.sum() * np.einsum("kii->k", m_b).real.sum()
    channels = healthy.shape[2]
    d2_level_free = d2 - trace_product / (channels * healthy.shape[1])
    return (math.sqrt(max(d2, 0.0) / HANN_BINS_PER_INDEPENDENT),
            math.sqrt(max(d2_level_free, 0.0) / HANN_BINS_PER_INDEPENDENT))


def cusum_threshold(shift):
    """LLR threshold of a Gaussian CUSUM with per-block shift `shift` for the target rate."""
    blocks_per_alarm = 3600.0 / FALSE_ALARMS_PER_HOUR / (BLOCK / FS)
    lo, hi = 0.1, 60.0
    for _ in range(100):
        h = 0.5 * (lo + hi)
        z = h + 1.166 * shift
        arl0 = (math.exp(z) - z - 1.0) / (shift**2 / 2.0)
        lo, hi = (h, hi) if arl0 < blocks_per_alarm else (lo, h)
    return hi


def ideal_detection(shift, rng, runs=4000, horizon_s=60.0):
    if shift <= 0:
        return 0.0, float("nan")
    h = cusum_threshold(shift)
    blocks = int(horizon_s / (BLOCK / FS)) * 4
    steps = rng.normal(shift**2 / 2.0, shift, size=(runs, blocks))
    delays = np.full(runs, np.inf)
    for r in range(runs):
        s = 0.0
        for k, llr in enumerate(steps[r]):
            s = max(0.0, s + llr)
            if s > h:
                delays[r] = (k + 1) * BLOCK / FS
                break
    return float(np.mean(delays <= horizon_s)), float(np.median(delays))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    args = sys.argv[1:]
    friction = 0.0
    if "--friction" in args:
        k = args.index("--friction")
        friction = float(args[k + 1])
        del args[k:k + 2]
    leakmon = args[0]
    workdir = args[1] if len(args) > 1 else "/tmp/pressure_information_bound"
    rigs = {"nominal": {}} if friction else RIGS
    leaks = (1e-12, 2e-12, 5e-12) if friction else LEAKS
    os.makedirs(workdir, exist_ok=True)
    rng = np.random.default_rng(1)
    print("| rig | controller | C_L | chambers | stationary KL (nats/s) | per block, level known "
          "| per block, level unknown | ideal CUSUM: found within 60 s, median |")
    print("|---|---|---|---|---|---|---|---|")
    for rig, params in rigs.items():
        for controller in ("basic", "fault_tolerant"):
            healthy, healthy_hold = periodograms(
                simulate(leakmon, workdir, rig, params, controller, 0.0, friction))
            for leak in leaks:
                leaky, leaky_hold = periodograms(
                    simulate(leakmon, workdir, rig, params, controller, leak, friction))
                for chambers, sel in (("p1, p2", slice(0, 2)), ("p1", slice(0, 1))):
                    h_all = healthy[:, :, sel, sel].mean(0)
                    l_all = leaky[:, :, sel, sel].mean(0)
                    known, free = block_information(healthy[healthy_hold][:, :, sel, sel],
                                                    leaky[leaky_hold][:, :, sel, sel])
                    found, median = ideal_detection(free, rng, runs=1000)
                    print(f"| {rig} | {controller} | {leak:g} | {chambers} | {kl_rate(h_all, l_all):.2f} "
                          f"| {known:.2f} | {free:.2f} | {100 * found:.0f} %, "
                          f"{'-' if math.isinf(median) else f'{median:.0f} s'} |", flush=True)


if __name__ == "__main__":
    main()
