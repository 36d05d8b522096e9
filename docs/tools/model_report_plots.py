#!/usr/bin/python3
"""Figures of a `leakmon model check --report DIR` report, from DIR/residuals.csv:
residual time series, residuals against the physical regressors of MODEL.md, residual spectra."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(out_dir):
    d = np.genfromtxt(f"{out_dir}/residuals.csv", delimiter=",", names=True)
    t = d["t"]
    dt = np.median(np.diff(t))
    chans = [("x", 1e3, "mm"), ("p1", 1e-5, "bar"), ("p2", 1e-5, "bar")]

    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for ax, (c, scale, unit) in zip(axes, chans):
        ax.plot(t, (d[c + "_before"] - d[c]) * scale, ".", ms=1, label="nominal (calibrated)")
        ax.plot(t, (d[c + "_after"] - d[c]) * scale, ".", ms=1, label="extended")
        ax.set_ylabel(f"{c} residual [{unit}]")
    # Effects that start inside the capture (result.json's causes with onset_s): marked.
    try:
        with open(f"{out_dir}/result.json") as f:
            causes = json.load(f).get("causes", [])
    except (OSError, ValueError):
        causes = []
    for cause in causes:
        if "onset_s" in cause:
            for ax in axes:
                ax.axvline(cause["onset_s"], color="red", lw=1, ls="--")
            axes[0].annotate(f"{cause['cause']} from t = {cause['onset_s']:.2f} s",
                             (cause["onset_s"], 1.0), xycoords=("data", "axes fraction"),
                             xytext=(3, -12), textcoords="offset points", color="red")
    axes[0].legend(markerscale=8)
    axes[-1].set_xlabel("t [s] (held-out segments)")
    fig.tight_layout()
    fig.savefig(f"{out_dir}/residuals_time.png", dpi=110)

    # Regressors from the measured signals: central differences within a held-out segment
    # (the rows jump in time between segments; derivatives across a jump are left out).
    step_ok = np.diff(t) < 1.5 * dt
    inside = np.concatenate([[False], step_ok[1:] & step_ok[:-1], [False]])

    def grad(v):
        g = np.full_like(v, np.nan)
        g[1:-1] = (v[2:] - v[:-2]) / (2 * dt)
        g[~inside] = np.nan
        return g

    regressors = [
        ("load pressure p1-p2 [bar]", (d["p1"] - d["p2"]) * 1e-5),
        ("velocity [mm/s]", grad(d["x"]) * 1e3),
        ("dp1/dt [bar/s]", grad(d["p1"]) * 1e-5),
        ("du/dt [V/s]", grad(d["u"])),
        ("command u [V]", d["u"]),
        ("p1+p2 [bar]", (d["p1"] + d["p2"]) * 1e-5),
    ]
    fig, axes = plt.subplots(2, 3, figsize=(12, 7))
    res = (d["p1_before"] - d["p1"]) * 1e-5
    res2 = (d["p2_before"] - d["p2"]) * 1e-5
    for ax, (name, r) in zip(axes.flat, regressors):
        ax.plot(r, res, ".", ms=1, alpha=0.4, label="p1")
        ax.plot(r, res2, ".", ms=1, alpha=0.4, label="p2")
        ax.set_xlabel(name)
        ax.set_ylabel("nominal residual [bar]")
    axes.flat[0].legend(markerscale=8)
    fig.tight_layout()
    fig.savefig(f"{out_dir}/residuals_regressors.png", dpi=110)

    fig, ax = plt.subplots(figsize=(10, 4))
    for c in ("p1", "p2"):
        for model in ("before", "after"):
            r = np.nan_to_num(d[f"{c}_{model}"] - d[c])
            spec = np.abs(np.fft.rfft(r * np.hanning(len(r)))) ** 2
            f = np.fft.rfftfreq(len(r), dt)
            ax.semilogy(f, spec, lw=0.7, label=f"{c} {'nominal' if model == 'before' else 'extended'}")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("residual power")
    ax.legend()
    fig.tight_layout()
    fig.savefig(f"{out_dir}/residuals_spectrum.png", dpi=110)


if __name__ == "__main__":
    main(sys.argv[1])
