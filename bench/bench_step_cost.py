#!/usr/bin/env python3
"""The cost of a step in instructions, counted by callgrind: a figure the machine's load does
not change, for comparisons that wall times on a shared machine cannot settle.

For every --config NAME="key=value ...", runs CASE natively to --from (writing a checkpoint),
then restarts it under `valgrind --tool=callgrind` to --to, counting only the step loop's work:
mpm_sim_run without its snapshots, its checkpoint and the integrator's start (so the step, the
boundary, migration, shifting and the post-step work; not set-up or output). Prints and writes, per configuration, the
steps and RHS evaluations of the window, the instructions per step and their ratio to the
--reference configuration's. On one rank (callgrind serialises the ranks anyway).

A partitioned scheme's equal-error cost against monolithic is then its step ratio at equal error
(bench/ablate.py) times monolithic's instructions per step over its own.

  /usr/bin/python3 bench/bench_step_cost.py --binary build/app/mpmfsi \\
      --case cases/shock_panel.ini --set "grid.dx=0.001 time.method=usl" \\
      --config mono="coupling.time=monolithic time.cfl=0.4" \\
      --config pred="coupling.time=multirate coupling.predictor=linear time.cfl=0.4" \\
      --reference mono --from 1.5e-4 --to 1.7e-4 --out out/step_cost
"""
import argparse
import csv
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from benchrun import ENV, git  # noqa: E402

TOGGLES = ["--toggle-collect=mpm_sim_run"]
# inside mpm_sim_run, but not the steps' work
OUTSIDE = ["mpm_sim.c:write_checkpoint", "mpm_sim.c:write_snapshot",
           "mpm_timescheme.c:mpm_timescheme_start", "mpm_sim.c:open_outputs"]


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)


def instructions(path):
    """The instructions of the step loop in a callgrind output file: the collected total less
    the inclusive cost of the functions in OUTSIDE."""
    out = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                         capture_output=True, text=True, check=True).stdout
    total, outside = None, {}
    for line in out.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(\S+)", line)
        if not m:
            continue
        ir, fn = int(m.group(1).replace(",", "")), m.group(2)
        if fn == "PROGRAM":
            total = ir
        for o in OUTSIDE:
            if fn.endswith("/" + o) or fn == o:
                outside[o] = max(outside.get(o, 0), ir)
    if total is None:
        raise RuntimeError(f"{path}: no instruction total (did callgrind run?)")
    return total - sum(outside.values())


def measure(binary, case, common, extra, t_from, t_to, scratch, name):
    start = os.path.join(scratch, name + "-start")
    window = os.path.join(scratch, name + "-window")
    run = [binary, "run", case, f"output.dir={start}", f"time.t_end={t_from}",
           "output.interval=1", "run.progress=false"] + common + extra
    subprocess.run(run, check=True, env=ENV, capture_output=True)
    out = os.path.join(scratch, name + ".callgrind")
    cmd = ["valgrind", "--tool=callgrind", "--collect-atstart=no", *TOGGLES,
           f"--callgrind-out-file={out}", binary, "restart",
           os.path.join(start, "checkpoint_final.h5"), f"time.t_end={t_to}",
           f"output.dir={window}", "output.interval=1", "run.progress=false"]
    subprocess.run(cmd, check=True, env=ENV, capture_output=True)
    s = summary(window)
    ir = instructions(out)
    return {"config": name, "overrides": " ".join(extra), "steps": s["steps"],
            "rhs_evals": s["rhs_evals"], "instructions": ir, "per_step": ir / s["steps"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", required=True)
    ap.add_argument("--case", required=True)
    ap.add_argument("--set", default="",
                    help="overrides every configuration shares (split as a shell splits words)")
    ap.add_argument("--config", action="append", required=True, metavar='NAME="k=v ..."')
    ap.add_argument("--reference", help="the configuration the ratios divide by")
    ap.add_argument("--from", dest="t_from", type=float, required=True)
    ap.add_argument("--to", dest="t_to", type=float, required=True)
    ap.add_argument("--out", required=True, help="folder for rows.csv and rows.json")
    a = ap.parse_args()
    if not a.t_to > a.t_from > 0:
        ap.error("--from and --to: 0 < from < to")
    configs = []
    for c in a.config:
        name, sep, rest = c.partition("=")
        if not sep or not name:
            ap.error(f'--config {c!r}: write NAME="key=value ..."')
        configs.append((name, shlex.split(rest)))
    names = [n for n, _ in configs]
    if a.reference and a.reference not in names:
        ap.error(f"--reference {a.reference}: not one of the configurations {names}")
    rows = []
    with tempfile.TemporaryDirectory(prefix="step_cost_") as scratch:
        for name, extra in configs:
            rows.append(measure(a.binary, a.case, shlex.split(a.set), extra, a.t_from, a.t_to,
                                scratch, name))
            r = rows[-1]
            print(f"{name}: {r['steps']} steps, {r['rhs_evals']} RHS, "
                  f"{r['per_step'] / 1e6:.2f} M instructions per step", flush=True)
    ref = next((r for r in rows if r["config"] == a.reference), None)
    for r in rows:
        r["per_step_over_reference"] = r["per_step"] / ref["per_step"] if ref else None
    os.makedirs(a.out, exist_ok=True)
    version = subprocess.run([a.binary, "version"], capture_output=True, text=True).stdout
    meta = {"revision": git("rev-parse", "--short", "HEAD"), "binary": a.binary,
            "binary_version": version.strip().splitlines()[0] if version.strip() else "unknown",
            "case": a.case, "set": a.set,
            "from": a.t_from, "to": a.t_to, "reference": a.reference, "rows": rows}
    with open(os.path.join(a.out, "rows.json"), "w") as f:
        json.dump(meta, f, indent=1)
    with open(os.path.join(a.out, "rows.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    if ref:
        print(f"per step over {a.reference}: " +
              ", ".join(f"{r['config']} {r['per_step_over_reference']:.3f}" for r in rows))


if __name__ == "__main__":
    main()
