#!/usr/bin/python3
"""Fluid throughput: particle-steps per second (and RHS evaluations) of the gas module for the
classic updates (usl, musl) and the adaptive bs32, in 2-D (262 144 particles) and 3-D
(110 592 particles), on 1 rank and 2 ranks, with the per-phase split from each run's
timers.csv. About 40 steps per run (t_end = 40 CFL steps of the undisturbed gas).

Usage: /usr/bin/python3 bench/bench_fluid.py [--quick] (from the repository root after
building). Writes bench/results/fluid_throughput.csv and .json and prints a table. Figures on
a shared 2-core machine are noisy: compare ratios within one run, not across runs.
"""
import csv
import json
import math
import os
import sys

from benchrun import ROOT, run_case  # noqa: E402

BIN = os.path.join(ROOT, "build", "app", "mpmfsi")
quick = "--quick" in sys.argv

# dim, cells per side: 2-D 256^2 x 4 = 262 144 particles, 3-D 24^3 x 8 = 110 592 (--quick:
# 4x and 8x fewer).
CASES = [(2, 256 if not quick else 128), (3, 24 if not quick else 12)]
METHODS = ["usl", "musl", "bs32"]
C0 = math.sqrt(1.4)  # sound speed of the undisturbed gas


def run(dim, cells, method, ranks):
    dx = 1.0 / cells
    extra = [] if dim == 2 else [
        "domain.lo=0 0 0", "domain.hi=1 1 1", "geometry.box.lo=0 0 0",
        "geometry.box.hi=1 1 1", "boundary.z_lo=periodic", "boundary.z_hi=periodic",
        "gas.air.pressure_field=1 + 0.5*exp(-((x-0.5)^2 + (y-0.5)^2 + (z-0.5)^2)/0.01)"]
    summary, timers = run_case(
        BIN, os.path.join(ROOT, "bench", "bench_fluid.ini"),
        [f"domain.dim={dim}", f"grid.dx={dx}", f"time.method={method}",
         f"time.t_end={40 * 0.4 * dx / C0}"] + extra, ranks)
    steps = summary["steps"]
    n = summary["particle_steps"] / max(steps, 1)
    return {"dim": dim, "particles": int(round(n)), "method": method, "ranks": ranks,
            "steps": steps, "rhs_evals": summary["rhs_evals"], "wall_s": summary["wall_s"],
            "particle_steps_per_s": summary["particle_steps_per_s"],
            "particle_rhs_per_s": n * summary["rhs_evals"] / summary["wall_s"],
            **{f"t_{k}": v for k, v in timers.items()}}


rows = []
for dim, cells in CASES:
    for method in METHODS:
        for ranks in (1, 2):
            r = run(dim, cells, method, ranks)
            rows.append(r)
            print(f"{dim}-D {r['particles']:>7} particles {method:>5} {ranks} rank(s): "
                  f"{r['particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s, "
                  f"{r['particle_rhs_per_s'] / 1e6:6.2f} M particle-RHS/s, "
                  f"{r['rhs_evals'] / max(r['steps'], 1):.2f} RHS/step; "
                  f"p2g {r.get('t_p2g', 0):.2f} s, g2p {r.get('t_g2p', 0):.2f} s, "
                  f"stress {r.get('t_stress', 0):.2f} s, halo {r.get('t_halo', 0):.3f} s, "
                  f"total {r.get('t_total', 0):.2f} s", flush=True)

os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
base = os.path.join(ROOT, "bench", "results", "fluid_throughput")
keys = sorted({k for r in rows for k in r}, key=lambda k: (k.startswith("t_"), k))
with open(base + ".csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=keys)
    w.writeheader()
    w.writerows(rows)
json.dump(rows, open(base + ".json", "w"), indent=1)
print("wrote", base + ".csv", "and .json")
