#!/usr/bin/python3
"""Finite-volume reference for the load on the shock panel held rigid (the gas-only twin of
cases/shock_panel.ini that bench/bench_panel_gas_step.py runs in mpmfsi).

Problem (2-D inviscid Euler, gamma = 1.4, the case's geometry): a channel x in [0, 0.33] m,
y in [0, 0.065] m, slip walls top and bottom and at x = 0.33; a rigid plate x in
[0.08, 0.081], y in [0, 0.05] with slip faces; at t = 0 the Ms = 1.21 shock stands at
x = 0.06 (post-shock air upstream: rho 1.63, p 1.557e5, u 109.6; still air downstream: rho
1.2, p 1.01e5); at x = 0 the post-shock state is held (the case's far field; the wave the plate
reflects reaches x = 0 after about 0.35 ms, so to the default 0.3 ms the two agree). The solver
is bench/euler_reference.py's (MUSCL-Hancock, HLLC, reflecting ghost cells at solid faces).

Output: the plate's load Fx (front minus back, N per metre of span) every --every seconds, in
<prefix>.csv and <prefix>.json. With --compare DIR ... each mpmfsi run folder's Fx_solid
(coupling.csv) or Fx (obstacles.csv) is compared with it as bench_panel_gas_step.py does: the
largest error of the impulse and of its integral over the reference's final values.

Usage (from the repository root): /usr/bin/python3 bench/euler_panel.py [--dx 0.0005]
[--t-end 3e-4] [--every 1e-6] [--prefix out/euler_panel/dx0.5] [--compare DIR ...]
--dx must divide 1 mm. Speed: about 0.5 us a cell-step (numpy, one core): 0.5 mm to 0.3 ms
takes under a minute, 0.25 mm about five.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from euler_reference import Euler2D  # noqa: E402

LENGTH, HEIGHT = 0.33, 0.065
PLATE = (0.08, 0.081, 0.05)  # x0, x1, top
SHOCK_X = 0.06
W_SHOCKED = (1.63, 109.6, 0.0, 1.557e5)
W_STILL = (1.2, 0.0, 0.0, 1.01e5)


def run(dx, t_end, every, cfl):
    for L in (LENGTH, HEIGHT, PLATE[0], PLATE[1], PLATE[2], SHOCK_X):
        if abs(L / dx - round(L / dx)) > 1e-9:
            sys.exit(f"euler_panel: --dx {dx} does not divide {L} m; use a divisor of 1 mm")
    nx, ny = int(round(LENGTH / dx)), int(round(HEIGHT / dx))
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dx
    solid = ((x[:, None] > PLATE[0]) & (x[:, None] < PLATE[1])) & (y[None, :] < PLATE[2])
    bc = {"xlo": ("inflow", W_SHOCKED), "xhi": "wall", "ylo": "wall", "yhi": "wall"}
    s = Euler2D(nx, ny, dx, dx, solid, bc, W_STILL, "vanleer", cfl)
    W = np.where((x < SHOCK_X)[None, :, None], np.array(W_SHOCKED)[:, None, None],
                 np.array(W_STILL)[:, None, None]) * np.ones((1, nx, ny))
    s.set_interior(W)
    t0 = time.time()
    ts, fx = [0.0], [0.0]
    n = int(round(t_end / every))
    for k in range(1, n + 1):
        target = k * every
        while s.t < target - 1e-15:
            s.step(min(s.max_dt(), target - s.t))
        s.t = target
        front, back, _ = s.body_forces()
        ts.append(target)
        fx.append(front - back)
    return np.array(ts), np.array(fx), s.steps, time.time() - t0, (nx, ny)


def integrals(t, F, T):
    """The impulse of the load F(t) and the impulse's integral, on the times T."""
    imp = np.concatenate([[0.0], np.cumsum(0.5 * (F[1:] + F[:-1]) * np.diff(t))])
    i = np.interp(T, t, imp)
    return i, np.concatenate([[0.0], np.cumsum(0.5 * (i[1:] + i[:-1]) * np.diff(T))])


def load_errors(t, F, tr, Fr, t_end):
    """The load F(t) against the reference Fr(tr) to t_end: the largest error of the impulse and
    of its integral over the reference's values at t_end, the impulse's error there, and the
    RMS error of F over the reference's RMS."""
    T = np.linspace(0.0, t_end, 3001)
    (i, s), (ir, sr) = integrals(t, F, T), integrals(tr, Fr, T)
    f, fr = np.interp(T, t, F), np.interp(T, tr, Fr)
    return {"impulse": float(np.max(abs(i - ir)) / ir[-1]),
            "impulse_end": float((i[-1] - ir[-1]) / ir[-1]),
            "displacement": float(np.max(abs(s - sr)) / sr[-1]),
            "force_rms": float(np.sqrt(np.mean((f - fr) ** 2) / np.mean(fr ** 2)))}


def load_mpm(d):
    if os.path.exists(os.path.join(d, "coupling.csv")):
        a = np.genfromtxt(os.path.join(d, "coupling.csv"), delimiter=",", names=True)
        return a["t"], a["Fx_solid"]
    a = np.genfromtxt(os.path.join(d, "obstacles.csv"), delimiter=",", names=True, dtype=None,
                      encoding=None)
    return np.concatenate([[0.0], a["t"]]), np.concatenate([[0.0], a["Fx"]])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dx", type=float, default=0.0005)
    ap.add_argument("--t-end", type=float, default=3e-4)
    ap.add_argument("--every", type=float, default=1e-6)
    ap.add_argument("--cfl", type=float, default=0.8)
    ap.add_argument("--prefix", default=None)
    ap.add_argument("--compare", nargs="*", default=[])
    a = ap.parse_args()
    prefix = a.prefix or os.path.join(os.path.dirname(HERE), "out", "euler_panel",
                                      f"dx{a.dx * 1e3:g}")
    os.makedirs(os.path.dirname(os.path.abspath(prefix)), exist_ok=True)
    t, F, steps, wall, (nx, ny) = run(a.dx, a.t_end, a.every, a.cfl)
    np.savetxt(prefix + ".csv", np.column_stack([t, F]), delimiter=",", header="t,Fx",
               comments="")
    T = np.linspace(0.0, a.t_end, 3001)
    ir, sr = integrals(t, F, T)
    rows = [{"run": d, **load_errors(*load_mpm(d), t, F, a.t_end)} for d in a.compare]
    summary = {"dx": a.dx, "cells": [nx, ny], "t_end": a.t_end, "steps": steps,
               "wall_s": round(wall, 1), "impulse": float(ir[-1]), "displacement": float(sr[-1]),
               "Fx_at": {f"{tq * 1e6:g}us": float(np.interp(tq, t, F))
                         for tq in (6e-5, 1.2e-4, 1.8e-4, 2.4e-4, 3e-4) if tq <= a.t_end},
               "compare": rows}
    with open(prefix + ".json", "w") as f:
        json.dump(summary, f, indent=1)
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
