#!/usr/bin/python3
"""Galilean invariance of the gas: Toro's strong shock moving across the grid (his test 5,
bench/fv_strip.py's toro3_moving) against the same problem at rest (toro3), per
fluid.volume_rate rule, under the case's method and step (cases/strong_shock.ini: usl at
time.cfl 0.9) or the one given, one rank, all in one invocation so that the wall and CPU times
compare.

Per run: L1 of the cell-averaged particle density (tests/tools/shocktube.py's measure, as
test_sod and bench_sod.py take it); the same L1 with each particle's density taken from its
spacing instead of its J (m / (V0 J_s), J_s half the distance between its two neighbours along
its row of the strip over its initial spacing: the density the motion gives, whatever J
says); on the left star plateau (the middle half between the fan's tail and the contact) the
mean density error, the mean of J / J_s - 1 and its standard deviation; the CPU time.

Usage: /usr/bin/python3 bench/bench_galilean.py [--cells 200,400,800] [--rules point,domain]
[--method usl|bs32|...] [--set key=value,...] [--out FILE.md] (from the repository root
after building). Prints a Markdown table; with --out
also writes it there.
"""
import datetime
import json
import os
import resource
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.abspath(sys.argv[sys.argv.index("--out") + 1]) if "--out" in sys.argv else None
os.environ.setdefault("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
os.environ.setdefault("MPMFSI_SOURCE_DIR", ROOT)
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
import fv_strip  # noqa: E402
from riemann import cell_profile  # noqa: E402


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


CELLS = [int(c) for c in arg("--cells", "200,400,800").split(",")]
RULES = arg("--rules", "point,domain").split(",")
METHOD = arg("--method", "usl")
EXTRA = [k for k in arg("--set", "").split(",") if k]
if METHOD == "usl" and not any(k.startswith("time.cfl=") for k in EXTRA):
    EXTRA.append("time.cfl=0.9")  # the case's (tests/tools/shocktube.py would give 0.4)


def spacing_J(P):
    x, y, V0 = P["x"][:, 0], P["x"][:, 1], P["V0"][:, 0]
    Js = np.full_like(x, np.nan)
    for row in np.unique(np.round(y, 9)):
        k = np.where(np.abs(y - row) < 1e-9)[0]
        k = k[np.argsort(x[k])]
        sp = np.empty(len(k))
        sp[1:-1] = 0.5 * (x[k[2:]] - x[k[:-2]])
        sp[0], sp[-1] = x[k[1]] - x[k[0]], x[k[-1]] - x[k[-2]]
        Js[k] = sp / np.sqrt(V0[k])
    return Js


def run(problem, N, rule):
    PR = fv_strip.PROBLEMS[problem]
    ex, t = PR.exact, PR.t
    with tempfile.TemporaryDirectory() as tmp:
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            out = shocktube.run(PR.case, N, METHOD, t, 1, [f"output.interval={t}",
                                f"fluid.volume_rate={rule}"] + EXTRA + PR.mpm_overrides(),
                               x0=PR.x0)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            P = mt.particles(mt.snapshots(out)[-1][1], "fluid")
        finally:
            os.chdir(cwd)
    edges = np.linspace(0.0, 1.0, N + 1)
    ref = ex.cell_averages(edges, t)[0]
    x, Js = P["x"][:, 0], spacing_J(P)
    l1 = float(np.abs(cell_profile(x, P["rho"][:, 0], edges) - ref).sum() / N)
    rho_s = P["m"][:, 0] / (P["V0"][:, 0] * Js)
    l1s = float(np.abs(cell_profile(x, rho_s, edges) - ref).sum() / N)
    tail = ex.x0 + (ex.u_star - ex.cl * (ex.p_star / ex.pl) ** ((ex.g - 1) / (2 * ex.g))) * t
    a, b = tail, ex.contact_position(t)
    k = (x > a + 0.25 * (b - a)) & (x < b - 0.25 * (b - a))
    r = P["J"][k, 0] / Js[k]
    return {"l1": l1, "l1_spacing": l1s, "plateau": float(P["rho"][k, 0].mean() / ex.r_star_l - 1),
            "J_bias": float(r.mean() - 1), "J_sd": float(r.std()),
            "cpu_s": r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime}


commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                        text=True).stdout.strip()
when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
L = ["# Galilean invariance per volume-rate rule (bench/bench_galilean.py)", "",
     "Toro's strong shock at rest (test 3) and moving across the grid at −19.6 (test 5), "
     f"`{METHOD}` with {', '.join(f'`{k}`' for k in EXTRA) or 'the case settings'}, one rank, "
     "N × 3 cells. L1: the cell-averaged particle density against "
     "the exact solution (as test_sod). *From the spacing*: the same with each particle's "
     "density from the distance between its two neighbours along its row (m / (V0 J_s)), the "
     "density the motion gives whatever J says. Left plateau: the middle half between the "
     "fan's tail and the contact, the mean particle density against ρ*_L = 0.5751 and the "
     "mean (standard deviation) of J / J_s − 1 there. CPU: user + system of each run. "
     "Discussion: docs/gas.md (flow across the grid).", "",
     f"bench/bench_galilean.py --cells {','.join(map(str, CELLS))} --rules {','.join(RULES)} "
     f"--method {METHOD} --set {','.join(EXTRA)}; "
     f"commit {commit} (+ working tree), {when}", "",
     "| cells | volume_rate | L1 at rest | L1 moving | **moving / rest** | L1 from the spacing, "
     "rest / moving (ratio) | moving: left plateau density | J / J_s − 1 (sd) | CPU s rest + moving |",
     "|---|---|---|---|---|---|---|---|---|"]
rows = []
for N in CELLS:
    for rule in RULES:
        rest, mov = run("toro3", N, rule), run("toro3_moving", N, rule)
        rows.append({"cells": N, "rule": rule, "rest": rest, "moving": mov})
        L.append(f"| {N} | {rule} | {rest['l1']:.3e} | {mov['l1']:.3e} | "
                 f"**{mov['l1'] / rest['l1']:.3f}** | {rest['l1_spacing']:.3e} / "
                 f"{mov['l1_spacing']:.3e} ({mov['l1_spacing'] / rest['l1_spacing']:.3f}) | "
                 f"{mov['plateau'] * 100:+.2f} % | {mov['J_bias'] * 100:+.2f} % "
                 f"({mov['J_sd'] * 100:.1f} %) | {rest['cpu_s']:.1f} + {mov['cpu_s']:.1f} |")
        print(L[-1], flush=True)
text = "\n".join(L) + "\n"
print(text)
if OUT:  # resolved before mpmtest moved the working directory
    with open(OUT, "w") as f:
        f.write(text)
    with open(os.path.splitext(OUT)[0] + ".json", "w") as f:
        json.dump({"invocation": L[0], "rows": rows}, f, indent=1)
