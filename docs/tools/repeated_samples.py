#!/usr/bin/python3
"""How often a capture's samples repeat the one before exactly on every channel of a set (the
quantity pipeline/repeated_samples.hpp judges; docs/daemon.md "Events"): per column set, the share
of repeating samples and the most of them in any 500-sample window (the daemon holds the leak
decision from 100).
Usage: repeated_samples.py CAPTURE.csv ...   (e.g. `leakmon sim --preset healthy --seed 5 ...`)"""
import io
import sys

import numpy as np

WINDOW = 500
SETS = (("p1", "p2"), ("p1", "p2", "x"), ("p1", "p2", "x", "u"))


def load(path):
    lines = [line for line in open(path) if not line.startswith("#")]
    names = lines[0].strip().split(",")
    values = np.genfromtxt(io.StringIO("".join(lines[1:])), delimiter=",")
    return {name: values[:, i] for i, name in enumerate(names)}


for path in sys.argv[1:]:
    capture = load(path)
    for columns in SETS:
        if not all(c in capture for c in columns):
            continue
        repeat = np.ones(len(capture["t"]) - 1, bool)
        for c in columns:
            repeat &= np.diff(capture[c]) == 0
        most = int(np.convolve(repeat, np.ones(WINDOW), "valid").max())
        print(f"{path} {'+'.join(columns)}: {repeat.mean():.4f} of the samples, "
              f"at most {most} of {WINDOW}")
