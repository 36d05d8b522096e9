#!/usr/bin/python3
"""Markdown tables for docs/detection.md from `leakmon evaluate` directories.
Usage: detection_tables.py EVAL_DIR              (main tables of one evaluation)
       detection_tables.py --effects DIR [DIR...] (one row per directory: the effect runs)
       detection_tables.py --pressure-only EVAL_DIR (issue 13: every detector without u and x,
                                                    per controller, at 5e-13, 1e-12, 2e-12)"""
import json
import os
import sys

from scipy.stats import chi2


def upper_rate(events, hours):
    """One-sided 95 % upper confidence bound of a Poisson rate (exact, Garwood)."""
    return chi2.ppf(0.95, 2 * events + 2) / 2.0 / hours


def cell(r):
    if r is None:
        return "-"
    delay = "" if r["median_delay"] is None else ", %.1f s" % r["median_delay"]
    return "%d/%d%s" % (r["detected"], r["leak_runs"], delay)


def false_alarms(healthy):
    return "%.2f (%d in %.1f h; <= %.2f)" % (
        healthy["false_alarms_per_hour"], healthy["false_alarms"], healthy["healthy_hours"],
        upper_rate(healthy["false_alarms"], healthy["healthy_hours"]))


def design_rows(detector, controller):
    design = [r for r in detector["rows"] if r["design"] and r["controller"] == controller]
    healthy = [r for r in design if r["leak"] == 0][0]
    return healthy, {r["leak"]: r for r in design}


def load(directory):
    with open(os.path.join(directory, "summary.json")) as f:
        return json.load(f)


def main_tables(directory):
    detectors = load(directory)["detectors"]
    sizes = sorted({r["leak"] for d in detectors for r in d["rows"] if r["leak"]})
    print("| detector | false alarms / h (count in healthy h; 95 % upper bound) | "
          + " | ".join("%.2g" % s for s in sizes) + " |")
    print("|---" * (len(sizes) + 2) + "|")
    for d in detectors:
        healthy, by_size = design_rows(d, "all")
        print("| %s | %s | " % (d["name"], false_alarms(healthy))
              + " | ".join(cell(by_size.get(s)) for s in sizes) + " |")
    print()
    print("| detector | controller | false alarms / h (count in healthy h; 95 % upper bound) "
          "| 5e-13 | 1e-12 | size error at alarm (1e-12) |")
    print("|---|---|---|---|---|---|")
    for d in detectors:
        for ctrl in ("basic", "fault_tolerant"):
            healthy, by_size = design_rows(d, ctrl)
            err = by_size.get(1e-12, {}).get("median_abs_size_error")
            print("| %s | %s | %s | %s | %s | %s |" % (
                d["name"], ctrl, false_alarms(healthy), cell(by_size.get(5e-13)),
                cell(by_size.get(1e-12)), "-" if err is None else "%.0f %%" % (100 * err)))


def effects_table(directories, names=("flow_balance", "index_cusum")):
    print("| effects (present from the start) | detector | false alarms (healthy h) | 5e-13 | 1e-12 |")
    print("|---|---|---|---|---|")
    for directory in directories:
        summary = load(directory)
        for d in summary["detectors"]:
            if d["name"] not in names:
                continue
            healthy, by_size = design_rows(d, "all")
            print("| %s | %s | %d (%.1f) | %s | %s |" % (
                summary["settings"]["effects"].replace(",", ", "), d["name"],
                healthy["false_alarms"], healthy["healthy_hours"], cell(by_size.get(5e-13)),
                cell(by_size.get(1e-12))))


# Candidates that need u and x; every other one reads the chamber pressures only.
NEEDS_VALVE_AND_POSITION = {"flow_balance", "fused", "default", "default_temp"}


def chambers(name):
    return "p1" if name == "paper" or name.endswith("_p1") else "p1, p2"


def pressure_only_table(directory):
    detectors = [d for d in load(directory)["detectors"]
                 if d["name"] not in NEEDS_VALVE_AND_POSITION]
    sizes = (5e-13, 1e-12, 2e-12)
    print("| detector | chambers | controller | false alarms / h (count in healthy h; 95 % upper "
          "bound) | " + " | ".join("%.0e" % s for s in sizes) + " |")
    print("|---" * (len(sizes) + 4) + "|")
    for d in sorted(detectors, key=lambda d: (chambers(d["name"]) == "p1", d["name"])):
        for ctrl in ("all", "basic", "fault_tolerant"):
            healthy, by_size = design_rows(d, ctrl)
            print("| %s | %s | %s | %s | %s |" % (
                d["name"], chambers(d["name"]), ctrl, false_alarms(healthy),
                " | ".join(cell(by_size.get(s)) for s in sizes)))


if __name__ == "__main__":
    if sys.argv[1] == "--effects":
        effects_table(sys.argv[2:])
    elif sys.argv[1] == "--pressure-only":
        pressure_only_table(sys.argv[2])
    else:
        main_tables(sys.argv[1])
