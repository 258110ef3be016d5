"""RAE 2822 work-precision and the wall treatments' cost on it.

1. Work-precision: cases/rae2822.ini at grid.dx = 0.04, 0.028 and 0.02 (25, 36 and 50 cells per
   chord) on `--ranks` ranks to its t_end, each analysed by tools/rae2822.py: Cp RMS against the
   experiment (lower surface; upper surface ahead of the shock), the shock position, Cl, Cd,
   steadiness, against the wall time. The runs are kept in out/rae2822_dx*/ (--reuse analyses
   runs already there instead of running them again).
2. Cost: least_squares against ghost per step, on 1 rank at dx = 0.04 over t in [0, 1]
   (`--repeats` alternated runs each; ghost blew up on this case at t = 2.4 before its held
   nodes coasted, 2026-12-05, so the comparison stops well before). No test asserts a time.

Writes bench/results/rae2822.{csv,json,md}, rae2822_cp.png (Cp of every resolution against the
experiment) and rae2822_field.png (the finest run's particles).
  /usr/bin/python3 bench/bench_rae2822.py [--binary build/app/mpmfsi] [--ranks 2] [--reuse]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import benchrun  # noqa: E402
import rae2822  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--binary", default=os.path.join(benchrun.ROOT, "build", "app", "mpmfsi"))
ap.add_argument("--ranks", type=int, default=2)
ap.add_argument("--dx", default="0.04,0.028,0.02")
ap.add_argument("--repeats", type=int, default=3)
ap.add_argument("--reuse", action="store_true")
ap.add_argument("--skip-cost", action="store_true")
ap.add_argument("--keep-cost", action="store_true", help="take the cost from the JSON already there")
ap.add_argument("--out", default=os.path.join(benchrun.ROOT, "bench", "results", "rae2822"))
a = ap.parse_args()
case = os.path.join(benchrun.ROOT, "cases", "rae2822.ini")


def run_dir(dx):
    return os.path.join(benchrun.ROOT, "out", f"rae2822_dx{dx}")


def full_run(dx):
    out = run_dir(dx)
    args = [a.binary, "run", case, f"output.dir={out}", f"grid.dx={dx}", "run.progress=false",
            "output.overwrite=true"]
    if a.ranks > 1:
        args = ["mpiexec", "-n", str(a.ranks)] + args
    subprocess.run(args, check=True, env=benchrun.ENV, capture_output=True)


rows, curves = [], []
for dx in [float(v) for v in a.dx.split(",")]:
    if not a.reuse:
        full_run(dx)
    with open(os.path.join(run_dir(dx), "summary.json")) as f:
        s = json.load(f)
    res, cp, exp = rae2822.analyse(run_dir(dx), 5)
    row = {"dx": dx, "cells_per_chord": round(1 / dx), "ranks": s["ranks"], "steps": s["steps"],
           "wall_s": s["wall_s"], "particle_steps": s["particle_steps"]}
    row.update({k: res[k] for k in ("rms_lower", "rms_upper_ahead", "rms_lower_010_100",
                                    "rms_upper_010_050", "shock_x", "cl", "cd",
                                    "cl_change", "cp_drift_rms", "steady", "t_from", "t_to")})
    row.update({k: v for k, v in res.items() if k.startswith("ref_")})
    rows.append(row)
    curves.append((dx, cp))
    print(json.dumps(row), flush=True)

cost = None
if a.keep_cost:
    with open(a.out + ".json") as f:
        cost = json.load(f)["cost"]
elif not a.skip_cost:
    samples = []
    for r in range(a.repeats):
        for t in ("ghost", "least_squares"):
            s, _ = benchrun.run_case(a.binary, case, ["grid.dx=0.04", "time.t_end=1",
                                                      "run.progress=false",
                                                      "output.snapshots=false",
                                                      f"fluid.wall_treatment={t}"], 1)
            samples.append({"treatment": t, "ms_per_step": 1e3 * s["wall_s"] / s["steps"],
                            "ns_per_particle_step": 1e9 * s["wall_s"] / s["particle_steps"]})
            print(json.dumps(samples[-1]), flush=True)
    med = {t: {k: statistics.median(x[k] for x in samples if x["treatment"] == t)
               for k in ("ms_per_step", "ns_per_particle_step")} for t in ("ghost", "least_squares")}
    cost = {"median": med, "samples": samples,
            "ratio_per_step": med["least_squares"]["ms_per_step"] / med["ghost"]["ms_per_step"]}

os.makedirs(os.path.dirname(a.out), exist_ok=True)
keys = list(rows[0])
with open(a.out + ".csv", "w") as f:
    f.write(",".join(keys) + "\n")
    for row in rows:
        f.write(",".join(str(row[k]) for k in keys) + "\n")
with open(a.out + ".json", "w") as f:
    json.dump({"runs": rows, "cost": cost,
               "targets": {"rms_lower": 0.05, "rms_upper_ahead": 0.08, "shock_dx": 0.08}}, f,
              indent=1)
exp_shock = rae2822.shock_position(rae2822.experiment()["upper"])
with open(a.out + ".md", "w") as f:
    f.write("# RAE 2822, M 0.729, alpha 2.31 deg, inviscid, least_squares\n\n")
    f.write("| dx (cells/chord) | steps | wall s (ranks) | Cp RMS lower | Cp RMS upper x/c<=0.5 | "
            "the same from x/c = 0.1 | shock x/c | Cl | Cd | steady |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        shock = f"{r['shock_x']:.3f}" if r["shock_x"] is not None else "none"
        f.write(f"| {r['dx']} ({r['cells_per_chord']}) | {r['steps']} | {r['wall_s']:.0f} "
                f"({r['ranks']}) | {r['rms_lower']:.3f} | {r['rms_upper_ahead']:.3f} | "
                f"{r['rms_lower_010_100']:.3f} / {r['rms_upper_010_050']:.3f} | {shock} | "
                f"{r['cl']:.3f} | {r['cd']:.4f} | {'yes' if r['steady'] else 'no'} "
                f"(Cl {100 * r['cl_change']:.1f} %, Cp {r['cp_drift_rms']:.3f}) |\n")
    f.write(f"\nExperiment's shock (same definition, Cp rising through Cp*): x/c = {exp_shock:.3f}. "
            "Targets: RMS lower <= 0.05, upper ahead <= 0.08, shock within 0.08 c.\n")
    if "ref_rms_upper" in rows[0]:
        f.write("\nAgainst the inviscid reference (Euler on a body-fitted grid, "
                "[rae2822_euler.md](rae2822_euler.md); RMS at stations every 0.01 c):\n\n"
                "| cells per chord | upper, x/c 0.01-0.99 | lower | nose (0.01-0.1): upper / "
                "lower | upper 0.1-0.5 | lower 0.1-0.99 | shock x/c (reference's) |\n"
                "|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['cells_per_chord']} | {r['ref_rms_upper']:.3f} | "
                    f"{r['ref_rms_lower']:.3f} | {r['ref_rms_upper_nose']:.3f} / "
                    f"{r['ref_rms_lower_nose']:.3f} | {r['ref_rms_upper_010_050']:.3f} | "
                    f"{r['ref_rms_lower_010']:.3f} | {r['shock_x']:.3f} "
                    f"({r['ref_shock_x']:.3f}) |\n")
    if cost:
        m = cost["median"]
        f.write(f"\nCost at dx = 0.04, 1 rank, t in [0, 1], median of {a.repeats}: ghost "
                f"{m['ghost']['ms_per_step']:.2f} ms/step, least_squares "
                f"{m['least_squares']['ms_per_step']:.2f} ms/step: ratio "
                f"{cost['ratio_per_step']:.3f} (target <= 1.15).\n")

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
fig, ax = plt.subplots(figsize=(7, 5))
exp = rae2822.experiment()
for k, (dx, cp) in enumerate(curves):
    for side, ls in (("upper", "-"), ("lower", "--")):
        ax.plot([p[0] for p in cp[side]], [p[1] for p in cp[side]], ls, color=f"C{k}",
                label=f"dx = {dx} {side}")
for side, mk in (("upper", "o"), ("lower", "s")):
    ax.plot([p[0] for p in exp[side]], [p[1] for p in exp[side]], mk, mfc="none", color="k",
            ms=4, label=f"experiment {side}")
rae2822.plot_reference(ax)
ax.axhline(rae2822.cp_critical(), color="gray", lw=0.5, ls=":", label="Cp*")
ax.invert_yaxis()
ax.set_xlabel("x/c")
ax.set_ylabel("Cp")
ax.set_title("RAE 2822, M 0.729, alpha 2.31 deg (inviscid) against the experiment")
ax.legend(fontsize=6, ncol=2)
fig.tight_layout()
fig.savefig(a.out + "_cp.png", dpi=110)
rae2822.plot_field(run_dir(curves[-1][0]), a.out + "_field.png")
print(open(a.out + ".md").read())
