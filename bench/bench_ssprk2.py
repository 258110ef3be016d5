#!/usr/bin/python3
"""The gas's time methods against each other on the shock tubes, with time.cfl variants: the
work-precision of the fixed-step SSP-RK2 (time.method = ssprk2), of bs32 as the cases set it
(adaptive, time.cfl = 0.4, atol = 1e-4) and of bs32 at a fixed step (time.adaptive = false),
all in one invocation so that the wall times compare. Error measure and runs as
bench/bench_sod.py and tests/verification/test_sod.py (tests/tools/shocktube.py: L1 of the
cell-averaged particle density against the exact solution; the shock position from the density
profile). The double rarefaction (Toro's 123 problem, cases/double_rarefaction.ini) is measured
as tests/verification/test_near_vacuum.py does (the nodal density's L1; no shock).

A run is `method[@cfl][:fixed][:key=value...]`: time.method, time.cfl, `:fixed` for
time.adaptive = false (the pairs at the fixed CFL step; the one-stage methods and ssprk2 always
take it), and any other setting (`:fluid.ppc=3`).

Usage: /usr/bin/python3 bench/bench_ssprk2.py [--case sod|strong_shock|double_rarefaction]
[--cells 100,200,...] [--runs bs32,ssprk2@0.4,bs32@0.8:fixed,...] [--out NAME] (from the
repository root after building). Writes bench/results/NAME.md (default ssprk2_<case>): the
table, the observed order per doubling, and the cost (RHS evaluations and wall time,
interpolated log-log between the bracketing resolutions) of reaching the target L1 (Sod:
1.8e-3, bs32's figure at 800 cells in sod_work_precision.md; Toro 3: 2.23e-2; double
rarefaction: 0.0131, usl's at 400 cells), with its ratio to the first run's cost.

`--case pulse`: the energy drift of the acoustic pulse (cases/acoustic_pulse.ini) between slip
faces to t = 25 (about six round trips; 160 cells): the change of the total energy relative to
the acoustic energy (twice the kinetic energy at t = 0.5, when the two pulses have parted). An
undamped wave the method amplifies shows as a positive drift.
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

import mpmtest as mt  # noqa: E402
import numpy as np  # noqa: E402

CASES = {"sod": (Riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), gamma=1.4, x0=0.5), 0.2, 1.8e-3),
         "strong_shock": (Riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), gamma=1.4, x0=0.5),
                          0.012, 2.23e-2),
         "double_rarefaction": (Riemann((1.0, -2.0, 0.4), (1.0, 2.0, 0.4)), 0.15, 0.0131)}
PULSE_T = 25.0


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def parse(spec):
    """(method, extra settings) of a run `method[@cfl][:fixed][:key=value...]`."""
    head, *flags = spec.split(":")
    method, _, cfl = head.partition("@")
    extra = [f"time.cfl={cfl}"] if cfl else []
    for flag in flags:
        if flag != "fixed" and "=" not in flag:
            raise SystemExit(f"bench_ssprk2: run '{spec}': '{flag}' is neither 'fixed' nor "
                             "key=value")
        extra.append("time.adaptive=false" if flag == "fixed" else flag)
    return method, extra


def nodal_l1(out, N, exact):
    """The double rarefaction's L1 of the nodal density, as test_near_vacuum measures it."""
    return shocktube.nodal_density(out, N, exact)[0]


def run(case, N, spec):
    """One run of `case` at N cells."""
    method, extra = parse(spec)
    exact, T, _ = CASES[case]
    extra = [f"output.interval={T}"] + extra
    with tempfile.TemporaryDirectory(dir=os.path.join(ROOT, "build")) as tmp:
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            out = shocktube.run(f"{case}.ini", N, method, T, 1, extra)
            if case == "double_rarefaction":
                l1, offset = nodal_l1(out, N, exact), float("nan")
            else:
                l1, xs, _ = shocktube.measure(out, N, exact, T)
                offset = (xs - exact.shock_position(T)) * N
            s = json.load(open(os.path.join(out, "summary.json")))
        finally:
            os.chdir(cwd)
    return {"cells": N, "run": spec, "l1": l1, "shock_cells": offset,
            "steps": s["steps"], "rhs": s["rhs_evals"], "wall": s["wall_s"]}


def pulse(spec):
    """The acoustic pulse between slip faces to PULSE_T: (drift of the total energy in % of the
    acoustic energy, steps, RHS evaluations, wall s)."""
    method, extra = parse(spec)
    with tempfile.TemporaryDirectory(dir=os.path.join(ROOT, "build")) as tmp:
        out = os.path.join(tmp, "pulse")
        mt.run(["run", mt.case("acoustic_pulse.ini"), f"output.dir={out}", "boundary.x_lo=slip",
                "boundary.x_hi=slip", f"time.method={method}", f"time.t_end={PULSE_T}",
                f"output.interval={PULSE_T}", "run.progress=false"] + extra)
        d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
        s = json.load(open(os.path.join(out, "summary.json")))
    e_ac = 2.0 * np.interp(0.5, d["t"], d["kinetic"])
    drift = 100.0 * (d["total"][-1] - d["total"][0]) / e_ac
    return drift, s["steps"], s["rhs_evals"], s["wall_s"]


def commit_line(args):
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    date = subprocess.run(["date", "-u", "+%Y-%m-%d %H:%M UTC"], capture_output=True,
                          text=True).stdout.strip()
    return (f"`/usr/bin/python3 bench/bench_ssprk2.py {args}` at {commit}, {date} (one "
            "invocation; wall times on a shared 2-core machine: compare ratios within the table).")


def main_pulse(specs, name):
    lines = [f"# acoustic pulse between slip faces to t = {PULSE_T:g}: energy drift", "",
             commit_line(f"--case pulse --runs {','.join(specs)}"), "",
             "| run | drift (% of the acoustic energy) | steps | RHS | wall s |", "|---|---|---|---|---|"]
    for spec in specs:
        drift, steps, rhs, wall = pulse(spec)
        print(f"pulse {spec:16s} drift {drift:+.4f} % steps {steps} rhs {rhs} wall {wall:.2f} s",
              flush=True)
        lines.append(f"| {spec} | {drift:+.4f} | {steps} | {rhs} | {wall:.2f} |")
    path = os.path.join(ROOT, "bench", "results", f"{name}.md")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {path}")


def at_target(rows, target, key):
    """key at L1 = target, log-log between the rows that bracket it (None if none do)."""
    for a, b in zip(rows, rows[1:]):
        if (a["l1"] - target) * (b["l1"] - target) <= 0 and a["l1"] != b["l1"]:
            w = math.log(target / a["l1"]) / math.log(b["l1"] / a["l1"])
            return math.exp(math.log(a[key]) + w * math.log(b[key] / a[key]))
    return None


def main():
    case = arg("--case", "sod")
    if case == "pulse":
        specs = arg("--runs", "bs32,ssprk2@0.4").split(",")
        return main_pulse(specs, arg("--out", "pulse_drift"))
    cells = [int(c) for c in arg("--cells", "100,200,400,800,1600").split(",")]
    specs = arg("--runs", "bs32,ssprk2@0.4,ssprk2@0.6,ssprk2@0.8").split(",")
    rows = []
    for N in cells:
        for spec in specs:
            rows.append(run(case, N, spec))
            r = rows[-1]
            print(f"{case} {N:5d} {spec:16s} L1 {r['l1']:.4e} shock {r['shock_cells']:+.2f} cells "
                  f"steps {r['steps']} rhs {r['rhs']} wall {r['wall']:.2f} s", flush=True)
    target = CASES[case][2]
    name = arg("--out", f"ssprk2_{case}")
    lines = [f"# {case}: the gas's time methods", "",
             commit_line(f"--case {case} --cells {','.join(map(str, cells))} --runs "
                         f"{','.join(specs)}" + (f" --out {name}" if "--out" in sys.argv else "")),
             "",
             "| cells | run | L1 | order | shock offset (cells) | steps | RHS | wall s |",
             "|---|---|---|---|---|---|---|---|"]
    summary = ["", f"Cost at L1 = {target:g} (log-log between the bracketing resolutions; "
               f"ratio: the first run's RHS count over this run's):", ""]
    first = None
    for spec in specs:
        mine = [r for r in rows if r["run"] == spec]
        for a, b in zip([None] + mine, mine):
            order = "" if a is None else f"{-math.log(b['l1'] / a['l1']) / math.log(b['cells'] / a['cells']):.2f}"
            lines.append(f"| {b['cells']} | {spec} | {b['l1']:.3e} | {order} | "
                         f"{'' if math.isnan(b['shock_cells']) else format(b['shock_cells'], '+.2f')} | {b['steps']} | {b['rhs']} | {b['wall']:.2f} |")
        rhs, wall = at_target(mine, target, "rhs"), at_target(mine, target, "wall")
        if first is None:
            first = rhs
        ratio = f", {first / rhs:.2f}x" if rhs and first else ""
        summary.append(f"- {spec}: " + ("not bracketed by these resolutions" if rhs is None else
                                         f"{rhs:.0f} RHS evaluations, {wall:.1f} s{ratio}"))
    path = os.path.join(ROOT, "bench", "results", f"{name}.md")
    with open(path, "w") as f:
        f.write("\n".join(lines + summary) + "\n")
    print("\n".join(summary))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
