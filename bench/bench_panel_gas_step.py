#!/usr/bin/python3
"""The shock panel's gas alone, stepped at its own step: how fast its time error falls.

Under `coupling.time = multirate` the shock panel's gas takes the coupling step, the gas's own
stable step, where under `monolithic` it takes the panel's, about six times smaller. So
multirate's extra error is the gas's time error at its own step. This driver measures that
error without the panel's dynamics: it builds the panel's gas-only twin from
cases/shock_panel.ini (the panel a `rigid` body at rest, so the step is the gas's; its clamp,
probe and elastic constants dropped; `coupling.time = monolithic`, `coupling.scheme` kept) and
runs it at each `time.cfl` given and at a reference `time.cfl`, per variant (a set of keys).

Per run: the load on the panel, Fx_solid of coupling.csv, against the variant's reference,
as the largest error of its impulse (the integral of Fx over time) and of its second integral
(the displacement a free mass would take from it: what the panel's tip integrates over the first
tenth of its period), each over the reference's final value; the RMS error of Fx itself over
its RMS; the steps and wall time. The order is that of each halving of `time.cfl`.

Usage: /usr/bin/python3 bench/bench_panel_gas_step.py [--dx 0.001] [--t-end 3e-4]
[--cfl 0.8,0.4,0.2,0.1] [--ref-cfl 0.025] [--variant NAME:key=value,key=value ...]
[--out DIR] (from the repository root after building; MPMFSI_BIN names another binary).
Without --variant it runs the case's own settings (`case`) alone. Writes
gas_step_twin.md and gas_step_twin.json into DIR (default out/bench_panel_gas_step).
"""
import datetime
import json
import math
import os
import subprocess
import sys
import tempfile
import time


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from benchrun import ENV, git  # noqa: E402
from euler_panel import load_errors, load_mpm  # noqa: E402


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def args_after(name):
    """Every value given after each occurrence of name."""
    return [sys.argv[i + 1] for i, a in enumerate(sys.argv[:-1]) if a == name]


BIN = os.environ.get("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
DX = float(arg("--dx", "0.001"))
T_END = float(arg("--t-end", "3e-4"))
CFLS = [float(c) for c in arg("--cfl", "0.8,0.4,0.2,0.1").split(",")]
REF = float(arg("--ref-cfl", "0.025"))
OUT = os.path.abspath(arg("--out", os.path.join(ROOT, "out", "bench_panel_gas_step")))
VARIANTS = [("case", [])]
for v in args_after("--variant"):
    name, _, keys = v.partition(":")
    VARIANTS.append((name, [k for k in keys.split(",") if k]))
if args_after("--variant"):
    VARIANTS = VARIANTS[1:]

# Sections of the panel's case the twin drops, and keys of its solid it does not take.
DROP_SECTIONS = {"clamp.base", "probe.tip", "geometry.base"}
DROP_SOLID_KEYS = {"E", "nu"}


def twin_case(path):
    """The gas-only twin of cases/shock_panel.ini, written to path."""
    out, section = [], None
    with open(os.path.join(ROOT, "cases", "shock_panel.ini")) as f:
        for line in f:
            s = line.strip()
            if s.startswith("["):
                section = s.strip("[]")
            if section in DROP_SECTIONS or s.startswith("#"):
                continue
            key = s.split("=")[0].strip() if "=" in s else None
            if section == "solid.panel" and key in DROP_SOLID_KEYS:
                continue
            if section == "solid.panel" and key == "material":
                line = "material = rigid\n"
            if section == "coupling" and key == "time":
                line = "time = monolithic\n"
            out.append(line)
    with open(path, "w") as f:
        f.writelines(out)


def run(case, cfl, keys):
    """One run; returns (t, Fx, steps, wall)."""
    with tempfile.TemporaryDirectory() as d:
        cmd = [BIN, "run", case, f"grid.dx={DX}", f"time.t_end={T_END}", f"time.cfl={cfl}",
               f"output.dir={d}", "output.interval=1", "run.progress=false"] + keys
        t0 = time.perf_counter()
        done = subprocess.run(cmd, env=ENV, capture_output=True, text=True)
        if done.returncode:
            sys.exit(f"bench_panel_gas_step: {' '.join(cmd)} failed: "
                     f"{(done.stderr.strip().splitlines() or ['?'])[-1]}")
        wall = time.perf_counter() - t0
        t, F = load_mpm(d)
    return t, F, len(t) - 1, wall


def main():
    os.makedirs(OUT, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        case = os.path.join(d, "panel_gas_twin.ini")
        twin_case(case)
        for name, keys in VARIANTS:
            ref = run(case, REF, keys)
            prev = None
            for cfl in CFLS:
                r = run(case, cfl, keys)
                e = load_errors(r[0], r[1], ref[0], ref[1], T_END)
                row = {"variant": name, "keys": keys, "cfl": cfl, "steps": r[2],
                       "wall_s": round(r[3], 2), **e, "ref_steps": ref[2]}
                if prev:
                    for k in ("impulse", "displacement"):
                        row[f"order_{k}"] = math.log(prev[k] / e[k]) / math.log(prev["cfl"] / cfl)
                rows.append(row)
                prev = row
                print(json.dumps(row), flush=True)
    commit = git("rev-parse", "--short", "HEAD")
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    head = (f"# The shock panel's gas alone at its own step\n\n`bench/bench_panel_gas_step.py`, "
            f"{commit}, {date}; dx {DX}, to t = {T_END}, reference `time.cfl = {REF}` per "
            f"variant, one rank. Errors over the reference's final impulse and displacement.\n\n"
            "| variant | `time.cfl` | steps | wall (s) | impulse | order | displacement | order "
            "| Fx RMS |\n|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        o1 = f"{r['order_impulse']:.2f}" if "order_impulse" in r else ""
        o2 = f"{r['order_displacement']:.2f}" if "order_displacement" in r else ""
        label = r["variant"] + (f" ({' '.join(r['keys'])})" if r["keys"] else "")
        lines.append(f"| {label} | {r['cfl']} | {r['steps']} | {r['wall_s']} | "
                     f"{r['impulse']:.2e} | {o1} | {r['displacement']:.2e} | {o2} | "
                     f"{r['force_rms']:.2e} |\n")
    with open(os.path.join(OUT, "gas_step_twin.md"), "w") as f:
        f.write(head + "".join(lines))
    with open(os.path.join(OUT, "gas_step_twin.json"), "w") as f:
        json.dump({"commit": commit, "date": date, "dx": DX, "t_end": T_END, "ref_cfl": REF,
                   "rows": rows}, f, indent=1)
    sys.stdout.write(head + "".join(lines))


if __name__ == "__main__":
    main()
