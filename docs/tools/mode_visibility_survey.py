#!/usr/bin/python3
"""The rigs behind docs/detection.md's table "A rig the pressures cannot see a leak on": for each,
`leakmon sim` (1200 s, seed 23) and the p1 index over the noise floor the daemon's
detection_blind check uses (pipeline/mode_visibility.hpp: 5 kPa noise and a 12-bit LSB over
20.7 MPa, 5.2 kPa). The index is the paper's, with PyWavelets (db8, level 2, symmetric, 400
samples every 200). It prints the range of its 300 s medians over the run, and whether
`leakmon replay` with p1 and p2 only wrote detection_blind.

Usage: mode_visibility_survey.py LEAKMON [WORKDIR]   (LEAKMON: build/bin/leakmon)
"""
import io
import json
import os
import subprocess
import sys

import numpy as np
import pywt

NOISE_FLOOR = np.sqrt(5000.0**2 + (20.7e6 / 4096) ** 2 / 12)
ONLY_PRESSURES = """\
drivers:
  - {name: rig, type: replay, path: unused.csv}
actuators:
  - name: cylinder
    channels: {p1: p1, p2: p2}
    detector: default
state: {directory: ""}
"""
RIGS = {  # name: (controller, scenario lines)
    "nominal": ("basic", ""),
    "nominal, fault tolerant": ("fault_tolerant", ""),
    "m +20 %": ("basic", "params: {m: 12}"),
    "spring 40 kN/m": ("basic", "params: {K_s: 4.0e4}"),
    "b +30 %": ("basic", "params: {b: 390}"),
    "Kv -10 %": ("basic", "params: {Kv: 3.05e-7}"),
    "spring 120 kN/m, fault tolerant": ("fault_tolerant", "params: {K_s: 1.2e5}"),
    "beta -25 %": ("basic", "params: {beta: 5.25e8}"),
    "beta -25 %, fault tolerant": ("fault_tolerant", "params: {beta: 5.25e8}"),
    "oil at 15 degC (VG 68)": (
        "basic", "conditions:\n  oil: {grade: 68}\n  temperature: {profile: constant, T: 15}"),
    "oil at 55 degC": ("basic", "conditions:\n  temperature: {profile: constant, T: 55}"),
    "valve overlap 0.05": ("basic", "effects:\n  valve_overlap: {d: 0.05}"),
    "valve overlap 0.05, fault tolerant": ("fault_tolerant", "effects:\n  valve_overlap: {d: 0.05}"),
    "spool lag 15 ms": ("basic", "effects:\n  spool_lag: {tau: 0.015}"),
    "supply ripple 1 MPa at 90 Hz": ("basic", "effects:\n  supply_ripple: {dP: 1.0e6, f: 90}"),
    "supply droop 3e10": ("basic", "effects:\n  supply_droop: {R_s: 3.0e10}"),
    "valve bias 0.3 V": ("basic", "effects:\n  valve_bias: {u0: 0.3}"),
    "external leak 2e-12": ("basic", "effects:\n  external_leakage: {C_E: 2.0e-12, chamber: 1}"),
    "sensor lag 2 ms on p1": ("basic", "effects:\n  sensor_lag: {tau_s: 0.002, channel: p1}"),
    "entrained air 0.2": ("basic", "effects:\n  entrained_air: {alpha: 0.2}"),
    "leak 5e-12 while learning": (
        "basic", "effects:\n  internal_leakage: {C_L: 5.0e-12, onset_s: 0.002, ramp_s: 0}"),
    "friction 50 N": ("basic", "effects:\n  coulomb_friction: {F_C: 50}"),
    "friction 120 N": ("basic", "effects:\n  coulomb_friction: {F_C: 120}"),
    "friction 400 N": ("basic", "effects:\n  coulomb_friction: {F_C: 400}"),
    "friction 50 N, fault tolerant": ("fault_tolerant", "effects:\n  coulomb_friction: {F_C: 50}"),
    "friction 120 N, fault tolerant": ("fault_tolerant", "effects:\n  coulomb_friction: {F_C: 120}"),
    "friction 400 N, fault tolerant": ("fault_tolerant", "effects:\n  coulomb_friction: {F_C: 400}"),
    "beta -25 %, b +30 %, air 0.2": (
        "basic", "params: {beta: 5.25e8, b: 390}\neffects:\n  entrained_air: {alpha: 0.2}"),
    "beta -25 %, b +30 %, air 0.2, fault tolerant": (
        "fault_tolerant", "params: {beta: 5.25e8, b: 390}\neffects:\n  entrained_air: {alpha: 0.2}"),
    "beta -25 %, b +30 %, air 0.2, 15 degC": (
        "basic", "params: {beta: 5.25e8, b: 390}\neffects:\n  entrained_air: {alpha: 0.2}\n"
        "conditions:\n  oil: {grade: 68}\n  temperature: {profile: constant, T: 15}"),
    "sensor lag 10 ms on p1": ("basic", "effects:\n  sensor_lag: {tau_s: 0.01, channel: p1}"),
}


def median_ratios(capture):
    lines = [line for line in open(capture) if not line.startswith("#")]
    names = lines[0].strip().split(",")
    p1 = np.genfromtxt(io.StringIO("".join(lines[1:])), delimiter=",", usecols=(names.index("p1"),))
    index = np.array([
        np.sqrt(np.mean(pywt.wavedec(p1[i:i + 400], "db8", mode="symmetric", level=2)[1] ** 2))
        for i in range(0, len(p1) - 400, 200)])
    window = int(300 / 0.4)
    medians = [np.median(index[k:k + window]) for k in range(0, len(index) - window, 25)]
    return min(medians) / NOISE_FLOOR, max(medians) / NOISE_FLOOR


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    leakmon = sys.argv[1]
    workdir = sys.argv[2] if len(sys.argv) > 2 else "/tmp/mode_visibility_survey"
    os.makedirs(workdir, exist_ok=True)
    config = os.path.join(workdir, "pressures.yaml")
    with open(config, "w") as out:
        out.write(ONLY_PRESSURES)
    print("| rig | ratio (300 s medians) | detection_blind with p1, p2 |")
    print("|---|---|---|")
    for k, (rig, (controller, lines)) in enumerate(RIGS.items()):
        scenario = os.path.join(workdir, f"rig{k}.yaml")
        capture = os.path.join(workdir, f"rig{k}.csv")
        events = os.path.join(workdir, f"rig{k}.jsonl")
        with open(scenario, "w") as out:
            out.write(f"name: rig{k}\ncontroller: {controller}\nduration_s: 1200\nseed: 23\n{lines}\n")
        subprocess.run([leakmon, "sim", "--scenario", scenario, "--out", capture], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run([leakmon, "replay", "--in", capture, "--config", config, "--events", events],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        blind = any(json.loads(line).get("event") == "detection_blind" for line in open(events))
        low, high = median_ratios(capture)
        os.remove(capture)
        print(f"| {rig} | {low:.2f}-{high:.2f} | {'blind' if blind else 'sees'} |", flush=True)


if __name__ == "__main__":
    main()
