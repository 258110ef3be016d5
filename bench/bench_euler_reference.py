"""The inviscid reference for RAE 2822 (tools/euler_aerofoil.py) and the checks behind it.

1. RAE 2822 at the case's M 0.729, alpha 2.31 deg on two O-grids (192 x 64 and 384 x 128
   cells; first cell 0.002 and 0.001 chords; circle of 40 chords), each run until the density
   residual has fallen 1e5-fold: Cl, Cd, the upper-surface shock (Cp rising through Cp*), and
   the RMS difference to the experiment by the issue's measures (tools/rae2822.py). The finer
   grid's surface Cp is the reference the gas module's runs are measured against:
   bench/results/rae2822_euler_cp.csv. (A third grid, 768 x 192, stalled at a residual of
   1e-3 after 20 000 iterations, with Cl moving over 0.945-0.947; --grids adds it.)
2. The solver's own checks, each to a residual drop of 1e-4 (at M 0.3 the residual stalls near
   1e-5, and Cl is steady to 5 digits from 1e-4 on): subsonic (NACA 0012, M 0.5, alpha 1.25 deg)
   the drag, which is zero for an exact inviscid solution, on two grids; low Mach (RAE 2822,
   M 0.3) the lift against the panel method (tools/panel_aerofoil.py) with the Prandtl-Glauert
   and Karman-Tsien corrections.

Writes bench/results/rae2822_euler.{json,md} and the reference CSV. Single-threaded numpy;
about 40 minutes (--reuse takes the runs already in --work).
  /usr/bin/python3 bench/bench_euler_reference.py [--work out/euler] [--reuse]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tools"))
import rae2822  # noqa: E402

TOOL = os.path.join(ROOT, "tools", "euler_aerofoil.py")

ap = argparse.ArgumentParser()
ap.add_argument("--work", default=os.path.join(ROOT, "out", "euler"))
ap.add_argument("--reuse", action="store_true")
ap.add_argument("--out", default=os.path.join(HERE, "results", "rae2822_euler"))
ap.add_argument("--grids", default="192x64x0.002,384x128x0.001",
                help="cells around x cells out x first cell (chords), coarse to fine; the last "
                "is the reference")
a = ap.parse_args()
GRIDS = [(int(ni), int(nj), float(w)) for ni, nj, w in (g.split("x") for g in a.grids.split(","))]
os.makedirs(a.work, exist_ok=True)
env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")


def run(name, args, tol=1e-5):
    """tools/euler_aerofoil.py with args, to a residual drop of tol; its figures (and its Cp
    CSV in the work folder)."""
    js, cp = os.path.join(a.work, name + ".json"), os.path.join(a.work, name + "_cp.csv")
    if not (a.reuse and os.path.exists(js)):
        subprocess.run([sys.executable, TOOL, "--tol", str(tol), "--iters", "60000", "--out", cp,
                        "--json", js] + args, check=True, env=env, stdout=subprocess.DEVNULL)
    with open(js) as f:
        res = json.load(f)
    res.pop("history", None)
    return res, cp


exp = rae2822.experiment()
rows = []
for ni, nj, wall in GRIDS:
    res, cp_path = run(f"rae2822_{ni}x{nj}", ["--ni", str(ni), "--nj", str(nj), "--wall",
                                              str(wall)])
    for column, tail in (("cp", ""), ("cp_cell", "_cell")):
        res.update(rae2822.against_experiment(rae2822.reference(cp_path, column), exp, tail))
    rows.append(res)
    print(json.dumps(res), flush=True)
finest = os.path.join(a.work, f"rae2822_{GRIDS[-1][0]}x{GRIDS[-1][1]}_cp.csv")
shutil.copyfile(finest, a.out + "_cp.csv")
# how far each grid's Cp lies from the finest's (the reference's own discretisation error)
ref = rae2822.reference(finest)
for r, (ni, nj, _) in zip(rows, GRIDS):
    cp = rae2822.reference(os.path.join(a.work, f"rae2822_{ni}x{nj}_cp.csv"))
    r["to_finest_upper"] = rae2822.rms_against(cp, ref, "upper", 0.01)
    r["to_finest_lower"] = rae2822.rms_against(cp, ref, "lower", 0.01)

checks = []
for ni, nj, wall in GRIDS[:2]:
    res, _ = run(f"naca0012_m05_{ni}x{nj}", ["--naca", "0.12", "--mach", "0.5", "--alpha", "1.25",
                                             "--ni", str(ni), "--nj", str(nj), "--wall", str(wall)],
              1e-4)
    checks.append(res | {"case": "NACA 0012, M 0.5, alpha 1.25"})
res, _ = run("rae2822_m03_384x128", ["--mach", "0.3", "--ni", "384", "--nj", "128", "--wall",
                                     "0.001"], 1e-4)
panel = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "panel_aerofoil.py"),
                        "--mach", "0.3", "--refine", "800"], check=True, env=env,
                       capture_output=True, text=True).stdout.strip()
checks.append(res | {"case": "RAE 2822, M 0.3, alpha 2.31", "panel": panel})
for c in checks:
    print(json.dumps(c), flush=True)

with open(a.out + ".json", "w") as f:
    json.dump({"rae2822": rows, "checks": checks}, f, indent=1)
with open(a.out + ".md", "w") as f:
    f.write("# RAE 2822, M 0.729, alpha 2.31 deg: the inviscid reference (Euler, O-grid)\n\n"
            "Each figure twice: with the wall pressure extrapolated linearly from the first two "
            "cells (the reference's Cp), and with the first cell's own (the one the wall flux "
            "uses).\n\n"
            "| grid (cells) | first cell (c) | iterations | wall s | Cl | Cd | shock x/c | "
            "Cp RMS lower (target 0.05) | upper x/c <= 0.5 (0.08) | from x/c = 0.1: lower / "
            "upper | RMS to the finest grid (the reference): upper / lower |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        f.write(f"| {r['ni']} x {r['nj']} | {r['wall']} | {r['iterations']} | "
                f"{r['wall_time']:.0f} | {r['cl']:.4f}; {r['cl_cell']:.4f} | {r['cd']:.4f}; "
                f"{r['cd_cell']:.4f} | {r['shock_x']:.3f}; {r['shock_x_cell']:.3f} | "
                f"{r['rms_lower']:.3f}; {r['rms_lower_cell']:.3f} | {r['rms_upper_ahead']:.3f}; "
                f"{r['rms_upper_ahead_cell']:.3f} | {r['rms_lower_010_100']:.3f} / "
                f"{r['rms_upper_010_050']:.3f}; {r['rms_lower_010_100_cell']:.3f} / "
                f"{r['rms_upper_010_050_cell']:.3f} | "
                f"{r['to_finest_upper']:.3f} / {r['to_finest_lower']:.3f} |\n")
    f.write(f"\nExperiment's shock (the same definition): x/c = "
            f"{rae2822.shock_position(exp['upper']):.3f}.\n\nThe solver's checks:\n\n")
    for c in checks:
        f.write(f"- {c['case']}, {c['ni']} x {c['nj']}: Cl {c['cl']:.4f}, Cd {c['cd']:.5f} "
                f"(first cell's pressure: Cl {c['cl_cell']:.4f}, Cd {c['cd_cell']:.5f})"
                + (f"; panel method: {c['panel']}" if "panel" in c else "") + "\n")
print(open(a.out + ".md").read())
