#!/usr/bin/python3
"""Plots of `leakmon evaluate` results: ROC curves per detector, detection probability and
delay against leak size, false alarms per hour, and the ROC curves of every pressure-only
detector beside the paper's rule per controller (roc_pressure.png, issue 13).
Usage: detection_plots.py EVAL_DIR [FIG_DIR] (FIG_DIR defaults to EVAL_DIR)."""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

LPM_PER_MPA = 6e10  # m^3/(s Pa) -> l/min/MPa


def rows(detector, controller="all"):
    return [r for r in detector["rows"] if r["controller"] == controller]


# Detectors that need u and x; every other candidate uses the chamber pressures only (and `temp`
# where its name says so), so detectors added later show up in the pressure-only figure.
NEEDS_VALVE_AND_POSITION = {"flow_balance", "fused", "default", "default_temp"}


def pressure_only(detectors):
    return [d for d in detectors if d["name"] not in NEEDS_VALVE_AND_POSITION]


def roc_pressure(summary, dst):
    """ROC per controller (rows) and leak size (columns) of the pressure-only detectors, the
    paper's rule among them; the star marks each detector's design threshold."""
    detectors = pressure_only(summary["detectors"])
    sizes = sorted({r["leak"] for d in detectors for r in d["rows"] if r["leak"]})
    shown = [s for s in sizes if s in (5e-13, 1e-12, 2e-12)] or sizes[:3]
    controllers = ["basic", "fault_tolerant"]
    if not shown:
        return
    fig, axes = plt.subplots(len(controllers), len(shown), figsize=(5 * len(shown), 4.2 * 2),
                             squeeze=False)
    for i, ctrl in enumerate(controllers):
        for j, size in enumerate(shown):
            ax = axes[i][j]
            for d in detectors:
                pts = sorted((r["false_alarms_per_hour"], r["detection_rate"], r["design"])
                             for r in rows(d, ctrl) if r["leak"] == size)
                if not pts:
                    continue
                style = dict(marker="o", linewidth=2.2) if d["name"] == "paper" else \
                    dict(marker=".", linewidth=1.2)
                ax.plot([max(p[0], 1e-3) for p in pts], [p[1] for p in pts], label=d["name"],
                        **style)
                for p in pts:
                    if p[2]:
                        ax.plot(max(p[0], 1e-3), p[1], marker="*", color="k", markersize=11)
            ax.set_xscale("log")
            ax.axvline(0.1, color="grey", linestyle="--", linewidth=0.8)
            ax.axhline(0.9, color="grey", linestyle=":", linewidth=0.8)
            ax.set_ylim(-0.02, 1.02)
            ax.set_title("%s, C_L = %.2g (%.3f l/min/MPa)" % (ctrl, size, size * LPM_PER_MPA),
                         fontsize=9)
            if i == len(controllers) - 1:
                ax.set_xlabel("false alarms per hour (0 plotted at 1e-3)")
            if j == 0:
                ax.set_ylabel("detected within %g s" % summary["settings"]["detect_within"])
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Pressure only: ROC per controller (star: design threshold)")
    fig.tight_layout()
    fig.savefig(os.path.join(dst, "roc_pressure.png"), dpi=100)


def main():
    src = sys.argv[1]
    dst = sys.argv[2] if len(sys.argv) > 2 else src
    os.makedirs(dst, exist_ok=True)
    with open(os.path.join(src, "summary.json")) as f:
        summary = json.load(f)
    detectors = summary["detectors"]
    sizes = sorted({r["leak"] for d in detectors for r in d["rows"] if r["leak"]})

    # ROC: detection within the window against false alarms per hour, one panel per leak size.
    shown = [s for s in sizes if s in (5e-13, 1e-12)] or sizes[:2]
    fig, axes = plt.subplots(1, len(shown), figsize=(5 * len(shown), 4), squeeze=False)
    for ax, size in zip(axes[0], shown):
        for d in detectors:
            pts = sorted((r["false_alarms_per_hour"], r["detection_rate"], r["design"])
                         for r in rows(d) if r["leak"] == size)
            fa = [max(p[0], 1e-3) for p in pts]
            ax.plot(fa, [p[1] for p in pts], marker="o", label=d["name"])
            for p in pts:
                if p[2]:
                    ax.plot(max(p[0], 1e-3), p[1], marker="*", color="k", markersize=12)
        ax.set_xscale("log")
        ax.axvline(0.1, color="grey", linestyle="--", linewidth=0.8)
        ax.set_xlabel("false alarms per hour (0 plotted at 1e-3)")
        ax.set_ylabel("detected within %g s" % summary["settings"]["detect_within"])
        ax.set_title("C_L = %.2g m^3/(s Pa) = %.3f l/min/MPa" % (size, size * LPM_PER_MPA))
        ax.set_ylim(-0.02, 1.02)
    axes[0][0].legend(fontsize=8)
    fig.suptitle("ROC (star: design threshold)")
    fig.tight_layout()
    fig.savefig(os.path.join(dst, "roc.png"), dpi=110)

    # Detection probability and median delay against leak size at the design threshold.
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for d in detectors:
        pts = sorted((r["leak"], r["detection_rate"], r["median_delay"])
                     for r in rows(d) if r["design"] and r["leak"])
        fa = [r["false_alarms_per_hour"] for r in rows(d) if r["design"] and r["leak"] == 0]
        label = "%s (%.2f false alarms/h)" % (d["name"], fa[0]) if fa else d["name"]
        x = [p[0] * LPM_PER_MPA for p in pts]
        ax1.plot(x, [p[1] for p in pts], marker="o", label=label)
        ax2.plot(x, [p[2] if p[2] is not None else float("nan") for p in pts], marker="o",
                 label=label)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xlabel("C_L [l/min/MPa]")
    ax1.set_ylabel("detected within %g s" % summary["settings"]["detect_within"])
    ax1.axhline(0.9, color="grey", linestyle="--", linewidth=0.8)
    ax2.set_ylabel("median delay of detected runs [s]")
    ax2.set_yscale("log")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(dst, "detection_vs_size.png"), dpi=110)

    # False alarms per hour at the design threshold, per controller.
    fig, ax = plt.subplots(figsize=(7, 4))
    controllers = ["basic", "fault_tolerant", "all"]
    width = 0.8 / len(controllers)
    for k, ctrl in enumerate(controllers):
        values = []
        for d in detectors:
            r = [r for r in rows(d, ctrl) if r["design"] and r["leak"] == 0]
            values.append(r[0]["false_alarms_per_hour"] if r else float("nan"))
        ax.bar([i + k * width for i in range(len(detectors))], values, width, label=ctrl)
    ax.set_xticks([i + width for i in range(len(detectors))])
    ax.set_xticklabels([d["name"] for d in detectors], rotation=20)
    ax.axhline(0.1, color="grey", linestyle="--", linewidth=0.8)
    ax.set_ylabel("false alarms per hour (design threshold)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(dst, "false_alarms.png"), dpi=110)
    roc_pressure(summary, dst)
    print("wrote roc.png, detection_vs_size.png, false_alarms.png, roc_pressure.png into", dst)


if __name__ == "__main__":
    main()
