#!/usr/bin/python3
"""ssprk2 against bs32 on the shock tubes, with time.cfl variants: the work-precision of the
fixed-step SSP-RK2 (time.method = ssprk2) at time.cfl = 0.4, 0.6, 0.8 and of bs32 as the
cases set it (time.cfl = 0.4, atol = 1e-4), all in one invocation so that the wall times
compare. Error measure and runs as bench/bench_sod.py and tests/verification/test_sod.py
(tests/tools/shocktube.py: L1 of the cell-averaged particle density against the exact
solution; the shock position from the density profile).

Usage: /usr/bin/python3 bench/bench_ssprk2.py [--case sod|strong_shock] [--cells 100,200,...]
[--runs bs32,ssprk2@0.8,...] (from the repository root after building). Writes
bench/results/ssprk2_<case>.md: the table, the observed order per doubling, and the cost
(RHS evaluations and wall time, interpolated log-log between the bracketing resolutions) of
reaching the target L1 (Sod: 1.8e-3, bs32's figure at 800 cells in sod_work_precision.md;
Toro 3: 2.23e-2).
"""
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
os.environ.setdefault("MPMFSI_SOURCE_DIR", ROOT)
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

CASES = {"sod": (Riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), gamma=1.4, x0=0.5), 0.2, 1.8e-3),
         "strong_shock": (Riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), gamma=1.4, x0=0.5),
                          0.012, 2.23e-2)}


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def run(case, N, spec):
    """One run; spec is a method, or method@cfl."""
    method, _, cfl = spec.partition("@")
    exact, T, _ = CASES[case]
    extra = [f"output.interval={T}"] + ([f"time.cfl={cfl}"] if cfl else [])
    with tempfile.TemporaryDirectory() as tmp:
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            out = shocktube.run(f"{case}.ini", N, method, T, 1, extra)
            l1, xs, _ = shocktube.measure(out, N, exact, T)
            s = json.load(open(os.path.join(out, "summary.json")))
        finally:
            os.chdir(cwd)
    return {"cells": N, "run": spec, "l1": l1, "shock_cells": (xs - exact.shock_position(T)) * N,
            "steps": s["steps"], "rhs": s["rhs_evals"], "wall": s["wall_s"]}


def at_target(rows, target, key):
    """key at L1 = target, log-log between the rows that bracket it (None if none do)."""
    for a, b in zip(rows, rows[1:]):
        if (a["l1"] - target) * (b["l1"] - target) <= 0 and a["l1"] != b["l1"]:
            w = math.log(target / a["l1"]) / math.log(b["l1"] / a["l1"])
            return math.exp(math.log(a[key]) + w * math.log(b[key] / a[key]))
    return None


def main():
    case = arg("--case", "sod")
    cells = [int(c) for c in arg("--cells", "100,200,400,800,1600").split(",")]
    specs = arg("--runs", "bs32,ssprk2@0.4,ssprk2@0.6,ssprk2@0.8").split(",")
    rows = []
    for N in cells:
        for spec in specs:
            rows.append(run(case, N, spec))
            r = rows[-1]
            print(f"{case} {N:5d} {spec:12s} L1 {r['l1']:.4e} shock {r['shock_cells']:+.2f} cells "
                  f"steps {r['steps']} rhs {r['rhs']} wall {r['wall']:.2f} s", flush=True)
    target = CASES[case][2]
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    lines = [f"# {case}: ssprk2 against bs32", "",
             f"`/usr/bin/python3 bench/bench_ssprk2.py --case {case} --cells "
             f"{','.join(map(str, cells))} --runs {','.join(specs)}` at {commit} (one invocation; "
             "wall times on a shared 2-core machine: compare ratios within the table).", "",
             "| cells | run | L1 | order | shock offset (cells) | steps | RHS | wall s |",
             "|---|---|---|---|---|---|---|---|"]
    summary = ["", f"Cost at L1 = {target:g} (log-log between the bracketing resolutions):", ""]
    for spec in specs:
        mine = [r for r in rows if r["run"] == spec]
        for a, b in zip([None] + mine, mine):
            order = "" if a is None else f"{-math.log(b['l1'] / a['l1']) / math.log(b['cells'] / a['cells']):.2f}"
            lines.append(f"| {b['cells']} | {spec} | {b['l1']:.3e} | {order} | "
                         f"{b['shock_cells']:+.2f} | {b['steps']} | {b['rhs']} | {b['wall']:.2f} |")
        rhs, wall = at_target(mine, target, "rhs"), at_target(mine, target, "wall")
        summary.append(f"- {spec}: " + ("not bracketed by these resolutions" if rhs is None else
                                         f"{rhs:.0f} RHS evaluations, {wall:.1f} s"))
    path = os.path.join(ROOT, "bench", "results", f"ssprk2_{case}.md")
    with open(path, "w") as f:
        f.write("\n".join(lines + summary) + "\n")
    print("\n".join(summary))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
