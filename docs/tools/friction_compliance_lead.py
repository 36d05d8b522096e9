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
is estimated from two halves of the blocks and multiplied (pressure_information_bound.py's
block_information, which also simulates the captures).

A second table gives the mean shift, in healthy standard deviations of one quiet block, of two
simple features of the detrended p_L. The first is the high-frequency share,
ln(var(diff p_L) / var p_L), which is level-free. The second is ln var p_L, which follows the
excitation level.

Usage: friction_compliance_lead.py LEAKMON [WORKDIR]   (LEAKMON: build/bin/leakmon)
"""
import os
import sys

import numpy as np

import pressure_information_bound as bound  # the simulation and the Fisher distance

BLOCK = bound.BLOCK
FS = bound.FS
LEAK = 1e-12
FRICTIONS = (0, 50, 120, 400)


def detrended_p_l(pressures):
    """Per 0.8 s block: p_L with its linear trend removed, and p_L's range (max - min)."""
    n = len(pressures) // BLOCK
    x = pressures[: n * BLOCK].reshape(n, BLOCK, 2)
    p_l = x[:, :, 0] - x[:, :, 1]
    design = np.vstack([np.ones(BLOCK), np.arange(BLOCK)]).T
    residual = p_l - (design @ np.linalg.lstsq(design, p_l.T, rcond=None)[0]).T
    return residual, p_l.max(1) - p_l.min(1)


def block_features(residual):
    """Per block: ln(var of the first difference / var) and ln var of the detrended p_L."""
    variance = (residual * residual).mean(1)
    step = np.diff(residual, axis=1)
    return np.log((step * step).mean(1) / variance), np.log(variance)


def block_spectra(residual):
    """Per block: the Hann-windowed periodogram of the detrended p_L, as 1x1 matrices."""
    spectra = np.abs(np.fft.rfft(residual * np.hanning(BLOCK)[None, :], axis=1)) ** 2
    return spectra[:, :, None, None]


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
            healthy, spread_h = detrended_p_l(
                bound.simulate(leakmon, workdir, "nominal", {}, controller, 0.0, friction))
            leaky, spread_l = detrended_p_l(
                bound.simulate(leakmon, workdir, "nominal", {}, controller, LEAK, friction))
            threshold = np.median(spread_h)
            quiet_h, quiet_l = spread_h < threshold, spread_l < threshold
            row.append(bound.block_information(block_spectra(healthy[quiet_h])[:, band],
                                               block_spectra(leaky[quiet_l])[:, band])[1])
            for name, h, l in zip(("high-frequency share", "ln var"),
                                  block_features(healthy[quiet_h]), block_features(leaky[quiet_l])):
                shifts.setdefault((name, controller), []).append((l.mean() - h.mean()) / h.std())
        print(f"| {controller} | " + " | ".join(f"{d:.2f}" for d in row) + " |", flush=True)
    print()
    print("| feature | controller | " + " | ".join(f"{F} N" if F else "no friction" for F in FRICTIONS)
          + " |")
    print("|---|---" + "|---" * len(FRICTIONS) + "|")
    for (name, controller), values in shifts.items():
        print(f"| {name} | {controller} | " + " | ".join(f"{v:+.2f}" for v in values) + " |")


if __name__ == "__main__":
    main()
