#!/usr/bin/python3
"""Solid throughput: particle-steps per second (and RHS evaluations) for the USL update and
the adaptive ERK pairs, in 2-D (>= 200k particles) and 3-D (>= 100k particles), on 1 rank
and 2 ranks, with the per-phase split from each run's timers.csv.

Usage: /usr/bin/python3 bench/bench_solid.py [--quick] [--repeat N] [--methods usl,bs32,dp54]
       [--ranks 1,2] [--bin [LABEL=]PATH ...] [--out NAME]
(run from the repository root after building). Every configuration runs N times (default 3);
the best and the median throughput are reported, and the per-phase split is that of the
median run. Several --bin options compare builds: their runs alternate within each
configuration, so that the load of a shared machine falls on all of them alike. Writes
bench/results/NAME.csv and .json (NAME = solid_throughput) and prints a table. Figures on a
shared 2-core machine are noisy: compare ratios within one run of this script, not across
runs, and look at the best figure for what the code can do.

Phases (timers.csv, wall seconds summed over the run, mean over the ranks): p2g (kernel
only), stress (material update), grid (nodal update and constraints), g2p (kernel and
particle rates), halo, check (state check and stable step of each RHS), migrate, diagnostics,
io; "other" is the rest of the run's wall time: mostly ARKODE's per-step vector work.
"""
import csv
import json
import os
import statistics
import sys

from benchrun import ROOT, run_case  # noqa: E402

PHASES = ["p2g", "stress", "grid", "g2p", "halo", "check", "migrate", "diagnostics", "io"]


def option(name, default):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


def builds():
    """(label, path) of every --bin (default: this tree's build)."""
    out = []
    for i, a in enumerate(sys.argv):
        if a == "--bin":
            label, _, path = sys.argv[i + 1].rpartition("=")
            out.append((label or os.path.basename(path), path))
    return out or [("build", os.path.join(ROOT, "build", "app", "mpmfsi"))]


quick = "--quick" in sys.argv
REPEAT = int(option("--repeat", "3"))
METHODS = option("--methods", "usl,bs32,dp54").split(",")
RANKS = [int(r) for r in option("--ranks", "1,2").split(",")]
BUILDS = builds()
OUTNAME = option("--out", "solid_throughput")

# dim, dx: 2-D block 0.6 x 0.6 at ppc 2 -> (0.6/dx)^2 * 4 particles (230 400 at 0.0025);
# 3-D -> (0.6/dx)^3 * 8 (110 592 at 0.025). --quick uses 4x and 8x fewer.
CASES = [(2, 0.0025 if not quick else 0.005), (3, 0.025 if not quick else 0.05)]


def run_once(binary, dim, dx, method, ranks):
    lo, hi = ("0 0", "1 1") if dim == 2 else ("0 0 0", "1 1 1")
    blo, bhi = ("0.2 0.2", "0.8 0.8") if dim == 2 else ("0.2 0.2 0.2", "0.8 0.8 0.8")
    vf = ("0.1*sin(pi*(x-0.2)/0.6); 0.05*sin(pi*(y-0.2)/0.6)" if dim == 2 else
          "0.1*sin(pi*(x-0.2)/0.6); 0.05*sin(pi*(y-0.2)/0.6); 0")
    summary, timers = run_case(
        binary, os.path.join(ROOT, "bench", "bench_solid.ini"),
        [f"domain.dim={dim}", f"domain.lo={lo}", f"domain.hi={hi}", f"grid.dx={dx}",
         f"geometry.block.lo={blo}", f"geometry.block.hi={bhi}",
         f"solid.block.velocity_field={vf}", f"time.method={method}", "time.rtol=1e-6",
         "time.atol=1e-9", f"time.t_end={20 * dx / 60}"], ranks)
    steps = summary["steps"]
    n = summary["particle_steps"] / max(steps, 1)
    total = timers.get("total", summary["wall_s"])
    split = {k: timers.get(k, 0.0) for k in PHASES}
    split["other"] = total - sum(v for k, v in timers.items() if k != "total")
    return {"dim": dim, "particles": int(round(n)), "method": method, "ranks": ranks,
            "steps": steps, "rhs_evals": summary["rhs_evals"], "wall_s": summary["wall_s"],
            "particle_steps_per_s": summary["particle_steps_per_s"],
            "particle_rhs_per_s": n * summary["rhs_evals"] / summary["wall_s"],
            "total_s": total, **{f"t_{k}": v for k, v in split.items()}}


def summarise(label, runs):
    rates = sorted(r["particle_steps_per_s"] for r in runs)
    med = statistics.median(rates)
    row = min(runs, key=lambda r: abs(r["particle_steps_per_s"] - med))  # the median run
    return {"build": label, **row, "repeats": len(runs), "best_particle_steps_per_s": rates[-1],
            "median_particle_steps_per_s": med, "all_particle_steps_per_s": rates}


def run(dim, dx, method, ranks):
    runs = {label: [] for label, _ in BUILDS}
    for _ in range(REPEAT):
        for label, path in BUILDS:
            runs[label].append(run_once(path, dim, dx, method, ranks))
    return [summarise(label, runs[label]) for label, _ in BUILDS]


rows = []
for dim, dx in CASES:
    for method in METHODS:
        for ranks in RANKS:
            for r in run(dim, dx, method, ranks):
                rows.append(r)
                share = " ".join(f"{k} {100 * r['t_' + k] / r['total_s']:.0f}%"
                                 for k in PHASES + ["other"] if r["t_" + k] > 0.005 * r["total_s"])
                print(f"{r['build']:>8} {dim}-D {r['particles']:>7} particles {method:>5} {ranks} "
                      f"rank(s): best {r['best_particle_steps_per_s'] / 1e6:6.2f}, median "
                      f"{r['median_particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s, "
                      f"{r['rhs_evals'] / max(r['steps'], 1):.2f} RHS/step; {share}", flush=True)

os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
base = os.path.join(ROOT, "bench", "results", OUTNAME)
keys = sorted({k for r in rows for k in r if k != "all_particle_steps_per_s"},
              key=lambda k: (k != "build", k.startswith("t_"), k))
with open(base + ".csv", "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
json.dump(rows, open(base + ".json", "w"), indent=1)
print("wrote", base + ".csv", "and .json")
