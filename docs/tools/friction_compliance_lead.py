#!/usr/bin/python3
"""What is left of a leak in p1 - p2 on a rig that seal friction holds at rest (docs/detection.md,
"A rig the pressures cannot see a leak on", the lead under "Not done").

The hydraulic mode is gone there, so the level-2 detectors see nothing. A leak still shows in
the chambers' slow compliance response: the spool noise drives p_L through the chamber
compliance, and the cross-port conductance sets the corner. That conductance is the seal creep
A^2 / (F_C / 1 mm/s), the null leakage and the leak.

For each controller and friction the tool simulates a healthy capture and one with a 1e-12 leak
from the start, with the same seed. It takes the p_L spectrum over 1-40 Hz in the quieter half of
the 0.8 s blocks (p_L range below the median, linear trend removed, Hann window). It then computes
the Fisher distance per block along the leak's change, with the block's level unknown. The change
is estimated from two halves of the blocks and multiplied, as in pressure_information_bound.py.

A second table gives the mean shift, in healthy standard deviations of one quiet block, of two
simple features of the detrended p_L. The first is the high-frequency share,
ln(var(diff p_L) / var p_L), which is level-free. The second is ln var p_L, which follows the
excitation level.

Usage: friction_compliance_lead.py LEAKMON [WORKDIR]   (LEAKMON: build/bin/leakmon)
"""
import io
import math
import os
import subprocess
import sys

import numpy as np

BLOCK = 400
FS = 500.0
SECONDS = 1200
SEED = 5
LEAK = 1e-12
FRICTIONS = (0, 50, 120, 400)
HANN_BINS_PER_INDEPENDENT = 1.5


def capture(leakmon, workdir, controller, friction, leak):
    name = f"{controller}_F{friction}_L{leak:g}"
    path = os.path.join(workdir, name + ".csv")
    if not os.path.exists(path):
        scenario = os.path.join(workdir, name + ".yaml")
        effects = []
        if friction:
            effects.append(f"  coulomb_friction: {{F_C: {friction}}}")
        if leak:
            effects.append(f"  internal_leakage: {{C_L: {leak}, onset_s: 0.002, ramp_s: 0}}")
        with open(scenario, "w") as out:
            out.write(f"name: lead\ncontroller: {controller}\nduration_s: {SECONDS}\nseed: {SEED}\n")
            if effects:
                out.write("effects:\n" + "\n".join(effects) + "\n")
        subprocess.run([leakmon, "sim", "--scenario", scenario, "--out", path], check=True,
                       stdout=subprocess.DEVNULL)
    lines = [line for line in open(path) if not line.startswith("#")]
    names = lines[0].strip().split(",")
    return np.genfromtxt(io.StringIO("".join(lines[1:])), delimiter=",",
                         usecols=(names.index("p1"), names.index("p2")))


def block_features(pressures):
    """Per block: ln(var of the first difference / var) and ln var of the detrended p_L."""
    n = len(pressures) // BLOCK
    x = pressures[: n * BLOCK].reshape(n, BLOCK, 2)
    p_l = x[:, :, 0] - x[:, :, 1]
    t = np.arange(BLOCK)
    design = np.vstack([np.ones(BLOCK), t]).T
    residual = p_l - (design @ np.linalg.lstsq(design, p_l.T, rcond=None)[0]).T
    variance = (residual * residual).mean(1)
    step = np.diff(residual, axis=1)
    return np.log((step * step).mean(1) / variance), np.log(variance)


def block_spectra(pressures):
    n = len(pressures) // BLOCK
    x = pressures[: n * BLOCK].reshape(n, BLOCK, 2)
    p_l = x[:, :, 0] - x[:, :, 1]
    spread = p_l.max(1) - p_l.min(1)
    t = np.arange(BLOCK)
    design = np.vstack([np.ones(BLOCK), t]).T
    trend = design @ np.linalg.lstsq(design, p_l.T, rcond=None)[0]
    residual = p_l - trend.T
    spectra = np.abs(np.fft.rfft(residual * np.hanning(BLOCK)[None, :], axis=1)) ** 2
    return spectra, spread


def distance(healthy, leaky, quiet_h, quiet_l, band):
    s0 = healthy[quiet_h].mean(0)
    ih, il = np.where(quiet_h)[0], np.where(quiet_l)[0]
    a = ((leaky[il[: len(il) // 2]].mean(0) - healthy[ih[: len(ih) // 2]].mean(0)) / s0)[band]
    b = ((leaky[il[len(il) // 2:]].mean(0) - healthy[ih[len(ih) // 2:]].mean(0)) / s0)[band]
    d2 = ((a * b).sum() - a.sum() * b.sum() / len(a)) / HANN_BINS_PER_INDEPENDENT
    return math.sqrt(max(d2, 0.0))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    leakmon = sys.argv[1]
    workdir = sys.argv[2] if len(sys.argv) > 2 else "/tmp/friction_compliance_lead"
    os.makedirs(workdir, exist_ok=True)
    f = np.arange(BLOCK // 2 + 1) * FS / BLOCK
    band = (f >= 1.0) & (f <= 40.0)
    print("| controller | " + " | ".join(f"{F} N" if F else "no friction" for F in FRICTIONS) + " |")
    print("|---" * (len(FRICTIONS) + 1) + "|")
    shifts = {}
    for controller in ("basic", "fault_tolerant"):
        row = []
        for friction in FRICTIONS:
            healthy_capture = capture(leakmon, workdir, controller, friction, 0.0)
            leaky_capture = capture(leakmon, workdir, controller, friction, LEAK)
            healthy, spread_h = block_spectra(healthy_capture)
            leaky, spread_l = block_spectra(leaky_capture)
            threshold = np.median(spread_h)
            quiet_h, quiet_l = spread_h < threshold, spread_l < threshold
            row.append(distance(healthy, leaky, quiet_h, quiet_l, band))
            for name, h, l in zip(("high-frequency share", "ln var"),
                                  block_features(healthy_capture), block_features(leaky_capture)):
                a, b = h[quiet_h], l[quiet_l]
                shifts.setdefault((name, controller), []).append((b.mean() - a.mean()) / a.std())
        print(f"| {controller} | " + " | ".join(f"{d:.2f}" for d in row) + " |", flush=True)
    print()
    print("| feature | controller | " + " | ".join(f"{F} N" if F else "no friction" for F in FRICTIONS)
          + " |")
    print("|---|---" + "|---" * len(FRICTIONS) + "|")
    for (name, controller), values in shifts.items():
        print(f"| {name} | {controller} | " + " | ".join(f"{v:+.2f}" for v in values) + " |")


if __name__ == "__main__":
    main()
