#!/usr/bin/python3
"""PyWavelets as the oracle for leakmon's DSP tests.

usage: pywt_oracle.py REQUEST RESULT

REQUEST holds one request per line, each followed by a line of numbers where noted:
  filters WAVELET                         -> dec_lo, dec_hi, rec_lo, rec_hi (one line each)
  max_level N WAVELET                     -> pywt.dwt_max_level(N, WAVELET)
  wavedec WAVELET MODE LEVEL  + signal    -> one line per array of pywt.wavedec (cA_n, cD_n..cD1)
  sliding WAVELET MODE LEVEL WINDOW STEP  + signal
                                          -> rms and energy of the level-LEVEL detail of every
                                             window (nan where the window holds a nan sample)
RESULT gets, per request, a line `result K` then its lines; numbers are written with 17
significant digits.
"""
import sys

import numpy as np
import pywt


def fmt(values):
    return " ".join(format(float(v), ".17g") for v in values)


def main(request_path, result_path):
    lines = open(request_path).read().splitlines()
    out = []
    i = 0
    k = 0
    while i < len(lines):
        words = lines[i].split()
        i += 1
        if not words:
            continue
        out.append(f"result {k}")
        k += 1
        kind = words[0]
        if kind == "filters":
            w = pywt.Wavelet(words[1])
            for bank in (w.dec_lo, w.dec_hi, w.rec_lo, w.rec_hi):
                out.append(fmt(bank))
        elif kind == "max_level":
            out.append(str(pywt.dwt_max_level(int(words[1]), words[2])))
        elif kind == "wavedec":
            x = np.array([float(v) for v in lines[i].split()])
            i += 1
            for c in pywt.wavedec(x, words[1], mode=words[2], level=int(words[3])):
                out.append(fmt(c))
        elif kind == "sliding":
            wavelet, mode, level, window, step = words[1], words[2], int(words[3]), \
                int(words[4]), int(words[5])
            x = np.array([float(v) for v in lines[i].split()])
            i += 1
            rms, energy = [], []
            for start in range(0, len(x) - window + 1, step):
                seg = x[start:start + window]
                if np.isnan(seg).any():
                    rms.append(float("nan"))
                    energy.append(float("nan"))
                    continue
                d = pywt.wavedec(seg, wavelet, mode=mode, level=level)[1]
                rms.append(np.sqrt(np.mean(d ** 2)))
                energy.append(np.sum(d ** 2))
            out.append(fmt(rms))
            out.append(fmt(energy))
        else:
            sys.exit(f"{request_path}:{i}: unknown request '{kind}'")
    with open(result_path, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
