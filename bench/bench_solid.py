#!/usr/bin/python3
"""Solid throughput: particle-steps per second (and RHS evaluations) for the USL update and
the adaptive ERK pairs, in 2-D (>= 200k particles) and 3-D (>= 100k particles), on 1 rank
and 2 ranks, with the per-phase split from each run's timers.csv.

Usage: /usr/bin/python3 bench/bench_solid.py [--quick] (run from the repository root after
building). Writes bench/results/solid_throughput.csv and .json and prints a table. Figures on
a shared 2-core machine are noisy: compare ratios within one run, not across runs.
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "build", "app", "mpmfsi")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_mpi_yield_when_idle="1")
quick = "--quick" in sys.argv

# dim, dx: 2-D block 0.6 x 0.6 at ppc 2 -> (0.6/dx)^2 * 4 particles (230 400 at 0.0025);
# 3-D -> (0.6/dx)^3 * 8 (110 592 at 0.025). --quick uses 4x and 8x fewer.
CASES = [(2, 0.0025 if not quick else 0.005), (3, 0.025 if not quick else 0.05)]
METHODS = ["usl", "bs32", "dp54"]


def run(dim, dx, method, ranks):
    with tempfile.TemporaryDirectory() as out:
        lo, hi = ("0 0", "1 1") if dim == 2 else ("0 0 0", "1 1 1")
        blo, bhi = ("0.2 0.2", "0.8 0.8") if dim == 2 else ("0.2 0.2 0.2", "0.8 0.8 0.8")
        vf = ("0.1*sin(pi*(x-0.2)/0.6); 0.05*sin(pi*(y-0.2)/0.6)" if dim == 2 else
              "0.1*sin(pi*(x-0.2)/0.6); 0.05*sin(pi*(y-0.2)/0.6); 0")
        args = [BIN, "run", os.path.join(ROOT, "bench", "bench_solid.ini"), f"output.dir={out}",
                f"domain.dim={dim}", f"domain.lo={lo}", f"domain.hi={hi}", f"grid.dx={dx}",
                f"geometry.block.lo={blo}", f"geometry.block.hi={bhi}",
                f"solid.block.velocity_field={vf}", f"time.method={method}",
                "time.rtol=1e-6", "time.atol=1e-9", f"time.t_end={20 * dx / 60}"]
        if ranks > 1:
            args = ["mpiexec", "-n", str(ranks)] + args
        subprocess.run(args, check=True, env=ENV, capture_output=True)
        summary = json.load(open(os.path.join(out, "summary.json")))
        with open(os.path.join(out, "timers.csv")) as f:
            timers = {r["phase"]: float(r["mean_s"]) for r in csv.DictReader(f)}
    steps = summary["steps"]
    n = summary["particle_steps"] / max(steps, 1)
    return {"dim": dim, "particles": int(round(n)), "method": method, "ranks": ranks,
            "steps": steps, "rhs_evals": summary["rhs_evals"], "wall_s": summary["wall_s"],
            "particle_steps_per_s": summary["particle_steps_per_s"],
            "particle_rhs_per_s": n * summary["rhs_evals"] / summary["wall_s"],
            **{f"t_{k}": v for k, v in timers.items()}}


rows = []
for dim, dx in CASES:
    for method in METHODS:
        for ranks in (1, 2):
            r = run(dim, dx, method, ranks)
            rows.append(r)
            print(f"{dim}-D {r['particles']:>7} particles {method:>5} {ranks} rank(s): "
                  f"{r['particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s, "
                  f"{r['particle_rhs_per_s'] / 1e6:6.2f} M particle-RHS/s, "
                  f"{r['rhs_evals'] / max(r['steps'], 1):.2f} RHS/step; "
                  f"p2g {r.get('t_p2g', 0):.2f} s, g2p {r.get('t_g2p', 0):.2f} s, "
                  f"stress {r.get('t_stress', 0):.2f} s, halo {r.get('t_halo', 0):.3f} s, "
                  f"total {r.get('t_total', 0):.2f} s", flush=True)

os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
base = os.path.join(ROOT, "bench", "results", "solid_throughput")
keys = sorted({k for r in rows for k in r}, key=lambda k: (k.startswith("t_"), k))
with open(base + ".csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=keys)
    w.writeheader()
    w.writerows(rows)
json.dump(rows, open(base + ".json", "w"), indent=1)
print("wrote", base + ".csv", "and .json")
