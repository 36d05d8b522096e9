#!/usr/bin/env python3
"""Flow balance in motion: the prototype behind detect/'s `flow_law` detector (issue 23).

The at-rest flow balance judges a leak only where the valve feeds nothing but the leak. The
valve's flow law holds in motion as well: over any block of samples the load flow the valve
delivers, integrated, equals the piston's swept volume, the compressed oil and the flow across
the piston,

    int qL dt = a * A (x_end - x_start) + c * int (p1 - p2) dt
                + k * ((V1 p1 - V2 p2)_end - (V1 p1 - V2 p2)_start) / 2 + d * T_block

with qL = (q1 - q2) / 2 from MODEL.md's orifice law on the command u (lagged by the spool's
tau), a = 1 / (Kv's error), k = 1 / beta, c = the valve's null leakage C_n plus any C_L, d a
flow offset. Nothing is differentiated (x's noise would swamp v). The swept volume is in phase
with the velocity and the leak's term with the load pressure, so the two separate in every
program; coefficients learned in one program judge another.

Usage: flow_law_prototype.py CAPTURE.csv LEARN_FROM LEARN_TO TEST_FROM TEST_TO
prints the learned coefficients and the change of c (as C_L) over the test span. Nominal rig
values (MODEL.md); the regression absorbs Kv's and beta's errors.
"""
import sys

import numpy as np

A = np.pi / 4 * (0.0381**2 - 0.0254**2)
KV, PS, PT, U_MAX, TAU, DP_LIN = 3.39e-7, 17.2e6, 0.1e6, 10.0, 2.5e-3, 2e5
V0 = A * 0.61 / 2 + 1e-5 + 6e-5
BLOCK_S = 0.2


def load(path):
    lines = [line for line in open(path) if not line.startswith("#")]
    header = lines[0].strip().split(",")
    values = np.loadtxt(lines[1:], delimiter=",")
    return {name: values[:, i] for i, name in enumerate(header)}


def sg(dp):
    return np.where(np.abs(dp) >= DP_LIN, np.sign(dp) * np.sqrt(np.abs(dp)), dp / np.sqrt(DP_LIN))


def blocks(capture):
    """Rows (t_end, Y, A dx, int pL dt, compression, T) per block."""
    t, u, x, p1, p2 = (capture[k] for k in ("t", "u", "x", "p1", "p2"))
    dt = t[1] - t[0]
    lag = np.exp(-dt / TAU)
    command = np.clip(u / U_MAX, -1, 1)
    opening = np.zeros_like(command)
    for k in range(1, len(command)):
        opening[k] = lag * opening[k - 1] + (1 - lag) * command[k - 1]
    q1 = np.where(opening >= 0, KV * opening * sg(PS - p1), KV * opening * sg(p1 - PT))
    q2 = np.where(opening >= 0, -KV * opening * sg(p2 - PT), -KV * opening * sg(PS - p2))
    q_load, p_load = (q1 - q2) / 2, p1 - p2
    n = int(round(BLOCK_S / dt))
    rows = []
    for b in range(len(t) // n - 1):
        s = slice(b * n, (b + 1) * n + 1)
        v1, v2 = V0 + A * x[s], V0 - A * x[s]
        stored = v1 * p1[s] - v2 * p2[s]
        rows.append((t[s][-1], np.trapz(q_load[s], dx=dt), A * (x[s][-1] - x[s][0]),
                     np.trapz(p_load[s], dx=dt), (stored[-1] - stored[0]) / 2, BLOCK_S))
    return np.array(rows)


def main():
    path = sys.argv[1]
    learn_from, learn_to, test_from, test_to = map(float, sys.argv[2:6])
    rows = blocks(load(path))
    learn = (rows[:, 0] > learn_from) & (rows[:, 0] < learn_to)
    test = (rows[:, 0] > test_from) & (rows[:, 0] < test_to)
    coef = np.linalg.lstsq(rows[learn][:, 2:], rows[learn][:, 1], rcond=None)[0]
    residual = rows[:, 1] - rows[:, 2:] @ coef
    load_integral = rows[:, 3]
    change = (load_integral[test] @ residual[test]) / (load_integral[test] @ load_integral[test])
    spread = residual[learn].std()
    snr = np.sqrt(((1e-12 * load_integral[test] * coef[0]) ** 2).mean()) / spread
    print(f"learned a={coef[0]:.4f} c={coef[1]:.3e} k={coef[2]:.3e} d={coef[3]:.3e}; "
          f"residual spread {spread:.3e} m^3 per block")
    print(f"C_L change over the test span: {change / coef[0]:.3e} m^3/(s Pa); "
          f"per-block SNR of a 1e-12 leak there: {snr:.1f}")


if __name__ == "__main__":
    main()
