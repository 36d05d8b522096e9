#!/usr/bin/python3
"""Markdown tables for docs/detection.md from a `leakmon evaluate` directory.
Usage: detection_tables.py EVAL_DIR"""
import json
import os
import sys


def cell(r):
    if r is None:
        return "-"
    delay = "" if r["median_delay"] is None else ", %.1f s" % r["median_delay"]
    return "%d/%d%s" % (r["detected"], r["leak_runs"], delay)


def main():
    with open(os.path.join(sys.argv[1], "summary.json")) as f:
        summary = json.load(f)
    detectors = summary["detectors"]
    sizes = sorted({r["leak"] for d in detectors for r in d["rows"] if r["leak"]})
    print("| detector | false alarms / h | " + " | ".join("%.2g" % s for s in sizes) + " |")
    print("|---" * (len(sizes) + 2) + "|")
    for d in detectors:
        design = [r for r in d["rows"] if r["design"] and r["controller"] == "all"]
        healthy = [r for r in design if r["leak"] == 0][0]
        by_size = {r["leak"]: r for r in design}
        print("| %s | %.2f (%d in %.1f h) | " % (d["name"], healthy["false_alarms_per_hour"],
                                                 healthy["false_alarms"], healthy["healthy_hours"])
              + " | ".join(cell(by_size.get(s)) for s in sizes) + " |")
    print()
    print("| detector | controller | false alarms / h (healthy h) | 5e-13 | 1e-12 | size error at alarm (1e-12) |")
    print("|---|---|---|---|---|---|")
    for d in detectors:
        for ctrl in ("basic", "fault_tolerant"):
            design = [r for r in d["rows"] if r["design"] and r["controller"] == ctrl]
            healthy = [r for r in design if r["leak"] == 0][0]
            by_size = {r["leak"]: r for r in design}
            err = by_size.get(1e-12, {}).get("median_abs_size_error")
            print("| %s | %s | %.2f (%.1f) | %s | %s | %s |" % (
                d["name"], ctrl, healthy["false_alarms_per_hour"], healthy["healthy_hours"],
                cell(by_size.get(5e-13)), cell(by_size.get(1e-12)),
                "-" if err is None else "%.0f %%" % (100 * err)))


if __name__ == "__main__":
    main()
