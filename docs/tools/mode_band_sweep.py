#!/usr/bin/python3
"""The rigs behind docs/detection.md's "Other rigs: where the index reads the mode" table and
daemon::ModeVisibilityCheck::readable_band: a 50 mm bore (rod 28 mm) whose moving mass and stroke
put the hydraulic mode (sim::hydraulic_mode_hz, at mid-stroke) from 35 to 154 Hz, each simulated
by `leakmon sim` (240 s, a 3e-12 leak at 150 s: three times the valve-relative size of
the targets on these rigs, which keep the paper's valve) and replayed with p1 and p2 (detail_xcorr)
and with p1 alone (index_cusum), told the rig. Prints, per rig and seed, the mode, the first
internal_leakage raise after the onset (or '-') and whether detection_blind was announced. It
also prints the level-2 db8 equivalent filter's gain at each mode, the skirt the band is set by.

Usage: mode_band_sweep.py LEAKMON [WORKDIR]   (LEAKMON: build/bin/leakmon; about 1 CPU minute)
"""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pywt

# name: (moving mass [kg], stroke [m]); bore 50 mm, rod 28 mm, every other value MODEL.md's.
RIGS = [(130, 0.5), (100, 0.5), (90, 0.5), (80, 0.5), (68.8, 0.5), (63.4, 0.5), (58.6, 0.5),
        (54.3, 0.5), (47.1, 0.5), (20, 0.3), (15, 0.3), (14, 0.3), (12.07, 0.3), (11.25, 0.3),
        (10, 0.3)]
SEEDS = (10, 17, 24)


def mode_hz(mass, stroke, bore=0.05, rod=0.028):
    area = math.pi / 4 * (bore**2 - rod**2)
    volume = area * stroke / 2 + 1e-5 + 6e-5
    return math.sqrt(2 * 7e8 * area**2 / (volume * mass) + 80e3 / mass) / (2 * math.pi)


def level2_gain_db(frequency):
    wavelet = pywt.Wavelet("db8")
    high = np.array(wavelet.dec_hi)
    upsampled = np.zeros(2 * len(high) - 1)
    upsampled[::2] = high
    filt = np.convolve(np.array(wavelet.dec_lo), upsampled)
    response = np.abs(np.fft.rfft(filt, 8000))
    freqs = np.fft.rfftfreq(8000, 1 / 500)
    return 20 * np.log10(response[np.argmin(abs(freqs - frequency))] / response.max())


def main():
    leakmon = sys.argv[1]
    work = sys.argv[2] if len(sys.argv) > 2 else "mode_band_sweep"
    os.makedirs(work, exist_ok=True)
    print("mass_kg stroke_m mode_hz gain_db seed | p1,p2: raise blind | p1: raise blind")
    for mass, stroke in RIGS:
        rig = f"{{bore: 0.05, rod: 0.028, stroke: {stroke}, moving_mass: {mass}}}"
        for seed in SEEDS:
            name = os.path.join(work, f"m{mass}-s{seed}")
            with open(name + ".yaml", "w") as f:
                f.write(f"name: sweep\ncontroller: basic\nduration_s: 240\nseed: {seed}\n"
                        f"rig: {rig}\neffects:\n  internal_leakage: {{C_L: 3.0e-12, onset_s: 150}}\n")
            with open(name + "-config.yaml", "w") as f:
                f.write("drivers:\n  - {name: c, type: replay, path: unused.csv}\n"
                        "metrics: {port: 0}\nstate: {directory: \"\"}\nactuators:\n"
                        f"  - {{name: pressures, channels: {{p1: c.p1, p2: c.p2}}, rig: {rig}}}\n"
                        f"  - {{name: p1only, channels: {{p1: c.p1}}, rig: {rig}}}\n")
            subprocess.run([leakmon, "sim", "--scenario", name + ".yaml", "--out", name + ".csv"],
                           check=True, capture_output=True)
            subprocess.run([leakmon, "replay", "--in", name + ".csv", "--config",
                            name + "-config.yaml", "--events", name + ".jsonl"],
                           check=True, capture_output=True)
            found = {"pressures": "-", "p1only": "-"}
            blind = {"pressures": "", "p1only": ""}
            with open(name + ".jsonl") as events:
                for line in events:
                    e = json.loads(line)
                    if e["event"] == "detection_blind":
                        blind[e["actuator"]] = "blind"
                    if (e["event"] == "alarm_raised" and e.get("alarm") == "internal_leakage"
                            and found[e["actuator"]] == "-"):
                        found[e["actuator"]] = (f"{e['t'] - 150:.0f} s" if e["t"] >= 150
                                                else f"false alarm at {e['t']:.0f} s")
            os.remove(name + ".csv")
            f_mode = mode_hz(mass, stroke)
            print(f"{mass} {stroke} {f_mode:.1f} {level2_gain_db(f_mode):.1f} {seed} | "
                  f"{found['pressures']} {blind['pressures']} | {found['p1only']} {blind['p1only']}")


if __name__ == "__main__":
    main()
