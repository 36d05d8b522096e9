#!/usr/bin/python3
"""Reproduces the paper's experiments on the simulator and plots them (docs/figures/sim_*.png).

Runs `leakmon sim` for the presets paper-fig10, paper-fig13, paper-fig16 and for healthy runs
of several seeds and calibration values (MODEL.md's ranges), computes the wavelet index with
`leakmon features` (db8, level 2, window 400, step 20, mode symmetric, on p1), cross-checks one
index series against PyWavelets, and writes the numbers quoted in docs/simulation.md to
docs/figures/sim_index_summary.md.

Usage: /usr/bin/python3 docs/tools/paper_figures.py [--build build] [--seed 1]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pywt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FIGURES = os.path.join(ROOT, "docs", "figures")
WINDOW, STEP = 400, 20


def load_capture(path):
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    names = lines[0].strip().split(",")
    data = np.genfromtxt(lines[1:], delimiter=",")
    if data.ndim == 1:
        data = data.reshape(1, -1)
    return {name: data[:, i] for i, name in enumerate(names)}


def simulate(binary, out, preset=None, scenario=None, seed=1, duration=None):
    args = [binary, "sim", "--out", out, "--seed", str(seed)]
    args += ["--preset", preset] if preset else ["--scenario", scenario]
    if duration:
        args += ["--duration", str(duration)]
    subprocess.run(args, check=True)
    return load_capture(out)


def index_series(binary, capture_path):
    out = capture_path + ".features.csv"
    subprocess.run([binary, "features", "--in", capture_path, "--channel", "p1", "--out", out],
                   check=True)
    features = load_capture(out)
    return features["t"], features["rms"]


def pywt_index(p1):
    values = []
    for start in range(0, len(p1) - WINDOW + 1, STEP):
        coeffs = pywt.wavedec(p1[start:start + WINDOW], "db8", mode="symmetric", level=2)
        values.append(np.sqrt(np.mean(coeffs[1] ** 2)))
    return np.array(values)


def summarise(t, index, onset):
    # Windows that straddle the onset mix both states: left out of both sides.
    window_s = WINDOW / 500.0
    before = index[t < onset]
    after = index[t - window_s >= onset]
    baseline = np.percentile(before, 10)
    return {
        "median_before": np.median(before),
        "median_after": np.median(after),
        "drop": 1.0 - np.median(after) / np.median(before),
        "baseline": baseline,
        "below_after": np.mean(after < baseline),
        "below_before": np.mean(before < baseline),
        "below_median_after": np.mean(after < np.median(before)),
    }


def plot_experiment(name, capture, t_index, index, onset, summary, title):
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    t = capture["t"]
    axes[0].plot(t, capture["xref"] * 1e3, label="reference", lw=0.8)
    axes[0].plot(t, capture["x"] * 1e3, label="position", lw=0.8)
    axes[0].set_ylabel("mm")
    axes[0].legend(loc="upper right")
    axes[1].plot(t, capture["p1"] / 1e6, label="P1", lw=0.6)
    axes[1].plot(t, capture["p2"] / 1e6, label="P2", lw=0.6)
    axes[1].set_ylabel("MPa")
    axes[1].legend(loc="upper right")
    axes[2].plot(t_index, index / 1e3, lw=0.6, label="d2 RMS index (p1)")
    axes[2].axhline(summary["baseline"] / 1e3, color="k", ls="--", lw=0.8,
                    label="baseline (10th percentile before onset)")
    axes[2].set_ylabel("kPa")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(loc="upper right")
    for ax in axes:
        ax.axvline(onset, color="r", lw=1.0)
    axes[0].set_title(title)
    fig.tight_layout()
    path = os.path.join(FIGURES, f"sim_{name}.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    binary = os.path.join(args.build, "bin", "leakmon")
    os.makedirs(FIGURES, exist_ok=True)
    work = tempfile.mkdtemp(prefix="leakmon-figures-")
    rows = []

    experiments = [
        ("paper-fig10", 15.0, "basic controller, 0.12 l/min/MPa leak at 15 s (paper Fig. 5-10)"),
        ("paper-fig13", 300.0, "basic controller, 0.13 l/min/MPa leak at 300 s (paper Fig. 13)"),
        ("paper-fig16", 300.0, "fault-tolerant controller, 0.149 l/min/MPa leak at 300 s (paper Fig. 16)"),
    ]
    for name, onset, title in experiments:
        path = os.path.join(work, name + ".csv")
        capture = simulate(binary, path, preset=name, seed=args.seed)
        t_index, index = index_series(binary, path)
        if name == "paper-fig10":
            reference = pywt_index(capture["p1"])
            worst = np.max(np.abs(reference - index))
            print(f"leakmon features vs PyWavelets on {name}: max |difference| {worst:.3g} Pa")
            if worst > 1e-6 * np.max(reference):
                sys.exit("leakmon features disagrees with PyWavelets")
        summary = summarise(t_index, index, onset)
        print(name, plot_experiment(name, capture, t_index, index, onset, summary, title))
        rows.append((name, summary))

    # Healthy spread: other seeds, and calibration values at the edges of MODEL.md's ranges.
    healthy = []
    for seed in range(1, 7):
        path = os.path.join(work, f"healthy-{seed}.csv")
        simulate(binary, path, preset="healthy", seed=seed, duration=120)
        healthy.append((f"seed {seed}", np.median(index_series(binary, path)[1])))
    nominal = {"beta": 7e8, "Kv": 3.39e-7, "m": 10.0, "b": 300.0}
    spans = {"beta": 0.25, "Kv": 0.10, "m": 0.20, "b": 0.30}
    for param, span in spans.items():
        for sign in (-1, 1):
            value = nominal[param] * (1 + sign * span)
            scenario = os.path.join(work, f"cal-{param}-{sign}.yaml")
            with open(scenario, "w") as f:
                f.write(f"name: calibration-{param}\nduration_s: 120\nseed: 1\n"
                        f"params: {{{param}: {value:.6g}}}\n")
            path = scenario + ".csv"
            simulate(binary, path, scenario=scenario, seed=1)
            healthy.append((f"{param} {'+' if sign > 0 else '-'}{span:.0%}",
                            np.median(index_series(binary, path)[1])))

    lines = ["| run | median index before | median index after | drop | baseline (p10 before) | "
             "post-onset windows below baseline | pre-onset windows below baseline | "
             "post-onset windows below pre-onset median |", "|---|---|---|---|---|---|---|---|"]
    for name, s in rows:
        lines.append(f"| {name} (seed {args.seed}) | {s['median_before'] / 1e3:.1f} kPa | "
                     f"{s['median_after'] / 1e3:.1f} kPa | {s['drop']:.0%} | "
                     f"{s['baseline'] / 1e3:.1f} kPa | {s['below_after']:.0%} | "
                     f"{s['below_before']:.0%} | {s['below_median_after']:.0%} |")
    medians = np.array([m for _, m in healthy])
    lines += ["", "| healthy run (120 s, basic) | median index |", "|---|---|"]
    lines += [f"| {label} | {m / 1e3:.1f} kPa |" for label, m in healthy]
    lines += ["", f"Healthy medians: min {medians.min() / 1e3:.1f} kPa, max {medians.max() / 1e3:.1f} kPa, "
              f"spread (max/min - 1) {medians.max() / medians.min() - 1:.0%}, "
              f"std/mean {medians.std() / medians.mean():.1%}."]
    summary_path = os.path.join(FIGURES, "sim_index_summary.md")
    with open(summary_path, "w") as f:
        f.write("<!-- written by docs/tools/paper_figures.py; do not edit -->\n")
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))

    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.barh([label for label, _ in healthy], medians / 1e3, color="tab:green", label="healthy runs")
    for name, s in rows:
        ax.axvline(s["median_after"] / 1e3, ls="--", lw=1,
                   color={"paper-fig10": "r", "paper-fig13": "m", "paper-fig16": "b"}[name],
                   label=f"{name} after onset")
    ax.set_xlabel("median d2 RMS index of p1 [kPa]")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(os.path.join(FIGURES, "sim_index_spread.png"), dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
