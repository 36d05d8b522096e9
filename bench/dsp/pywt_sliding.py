#!/usr/bin/python3
"""The PyWavelets baseline for bench/dsp: the same sliding windows (db8, level 2, window 400,
step 20, symmetric) as leakmon's streaming extractor, one pywt.wavedec per window, and for
comparison one pywt.wavedec over all windows at once (2-D, axis=-1).

usage: /usr/bin/python3 bench/dsp/pywt_sliding.py [SAMPLES]
"""
import sys
import time

import numpy as np
import pywt

WAVELET, LEVEL, WINDOW, STEP, MODE = "db8", 2, 400, 20, "symmetric"


def loop(x):
    out = []
    for start in range(0, len(x) - WINDOW + 1, STEP):
        d = pywt.wavedec(x[start:start + WINDOW], WAVELET, mode=MODE, level=LEVEL)[1]
        out.append(np.sqrt(np.mean(d * d)))
    return np.array(out)


def batched(x):
    windows = np.lib.stride_tricks.sliding_window_view(x, WINDOW)[::STEP]
    d = pywt.wavedec(windows, WAVELET, mode=MODE, level=LEVEL, axis=-1)[1]
    return np.sqrt(np.mean(d * d, axis=-1))


def best_rate(fn, x, repeats=3):
    """Samples per CPU second (process time, like Google Benchmark's items_per_second), best of
    `repeats`: on a shared machine wall time mostly measures the other processes."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        result = fn(x)
        best = min(best, time.process_time() - t0)
    return len(x) / best, result


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100000
    x = 8.65e6 + 2e4 * np.random.default_rng(1).standard_normal(n)
    loop_rate, a = best_rate(loop, x)
    batch_rate, b = best_rate(batched, x)
    assert np.allclose(a, b, rtol=1e-12, atol=0)
    print(f"pywt {pywt.__version__}, {n} samples, {len(a)} windows")
    print(f"pywt loop (one wavedec per window): {loop_rate / 1e6:.3f} M samples per CPU second")
    print(f"pywt batched (2-D wavedec of all windows): {batch_rate / 1e6:.3f} M samples per CPU second")


if __name__ == "__main__":
    main()
