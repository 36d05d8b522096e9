#!/usr/bin/python3
"""Where the false alarms under test programs come from, from a `leakmon evaluate --conditions
programs` directory (its runs.json and summary.json): per detector at its design threshold,
(1) by the phase kind the detector learned in (the phases that cover its learning period), with
the leaks found in time, (2) by the time since the phase the alarm was raised in began, and by the kind of the phase
before it. Healthy time is the monitored time before any onset, as in conditions.md.
Usage: program_false_alarms.py EVAL_DIR [DETECTOR ...]   (default: default detail_xcorr
       detail_xcorr_p1 index_cusum_p1)"""
import json
import os
import sys

from scipy.stats import chi2

SETTLE_SECONDS = 2.0  # the detectors' settle_seconds (study/evaluation_options.hpp)
WINDOW = 60.0  # detect_within


def upper_rate(events, hours):
    """One-sided 95 % upper confidence bound of a Poisson rate (exact, Garwood)."""
    return chi2.ppf(0.95, 2 * events + 2) / 2.0 / hours if hours > 0 else float("nan")


def kind(phase):
    name = phase["phase"].split()[0]
    if name == "hold" and not phase["judgeable"]:
        return "hold (not judgeable)"
    return name


def rate(count, hours):
    if hours <= 0:
        return "-"
    return "%.2f (%d in %.2f h; <= %.2f)" % (count / hours, count, hours,
                                             upper_rate(count, hours))


def main():
    directory = sys.argv[1]
    detectors = sys.argv[2:] or ["default", "detail_xcorr", "detail_xcorr_p1", "index_cusum_p1"]
    with open(os.path.join(directory, "runs.json")) as f:
        runs = [r for r in json.load(f) if "program" in r]
    with open(os.path.join(directory, "summary.json")) as f:
        learn = json.load(f)["settings"]["learn_seconds"]
    monitor_from = SETTLE_SECONDS + learn + 1.0

    # (1) By what the detector learned in: false alarms, and the leaks found in time (within
    # the window of the onset, or of the next phase's start for a hold that cannot be judged).
    print("| detector | learned in | runs | healthy h | false alarms / h (count; 95 % upper "
          "bound) | runs with a false alarm | leaks found in time |\n"
          "|---|---|---|---|---|---|---|")
    for detector in detectors:
        groups = {}
        for r in runs:
            learned = [kind(p) for p in r["program"]
                       if p["start"] < monitor_from and p["end"] > SETTLE_SECONDS]
            key = " + ".join(learned)
            g = groups.setdefault(key, [0, 0.0, 0, 0, 0, 0])
            healthy_end = min(r["onset"] if r["onset"] is not None else 1e300, r["seconds"])
            raised = sum(1 for a in r["alarms"][detector] if a["t"] < healthy_end)
            g[0] += 1
            g[1] += max(0.0, healthy_end - monitor_from) / 3600.0
            g[2] += raised
            g[3] += 1 if raised else 0
            if r["leak_phase"] is not None:
                opened_in = r["program"][r["leak_phase"]]
                deadline = (r["onset"] if opened_in["judgeable"] else opened_in["end"]) + WINDOW
                first = next((a["t"] for a in r["alarms"][detector] if a["t"] >= r["onset"]),
                             None)
                g[4] += 1
                g[5] += 1 if first is not None and first <= deadline else 0
        for key in sorted(groups):
            g = groups[key]
            print("| %s | %s | %d | %.2f | %s | %d | %d/%d |" % (
                detector, key, g[0], g[1], rate(g[2], g[1]), g[3], g[5], g[4]))

    # (2) By the time since the phase began, and the phase before.
    buckets = [(0.0, 2.0), (2.0, 30.0), (30.0, 1e300)]
    print("\n| detector | false alarms | in the phase's first 2 s | 2-30 s | later | in a phase after a "
          "hold | after steps | after a sine | after a sweep | after a triangle | in the first "
          "phase |\n|---|---|---|---|---|---|---|---|---|---|---|")
    for detector in detectors:
        total = 0
        by_time = [0, 0, 0]
        by_previous = {}
        for r in runs:
            healthy_end = min(r["onset"] if r["onset"] is not None else 1e300, r["seconds"])
            phases = r["program"]
            for a in r["alarms"][detector]:
                t = a["t"]
                if t >= healthy_end:
                    continue
                i = next((k for k, p in enumerate(phases) if p["start"] <= t < p["end"]), None)
                if i is None:
                    continue
                total += 1
                since = t - phases[i]["start"]
                for b, (lo, hi) in enumerate(buckets):
                    if lo <= since < hi:
                        by_time[b] += 1
                previous = phases[i - 1]["phase"].split()[0] if i > 0 else "first"
                by_previous[previous] = by_previous.get(previous, 0) + 1
        print("| %s | %d | %d | %d | %d | %d | %d | %d | %d | %d | %d |" % (
            detector, total, by_time[0], by_time[1], by_time[2], by_previous.get("hold", 0),
            by_previous.get("steps", 0), by_previous.get("sine", 0),
            by_previous.get("sweep", 0), by_previous.get("triangle", 0),
            by_previous.get("first", 0)))


if __name__ == "__main__":
    main()
