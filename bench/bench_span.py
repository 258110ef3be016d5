#!/usr/bin/env python3
"""Cost of the exact span integrals (common/mpm_span.c) and of the grid pressure on Sod.

1. Builds bench/bench_span.c with mpicc against this checkout's common/mpm_span.c (the build's
   -O3 -g) and runs it: ns per span of the force and the divergence, 2-D and 3-D, for the direct
   Gauss-point sum the library used before (kept only in the bench) and the library's code, in
   one process, old and new alternating; and how far the two agree on half spans and skips.
2. Runs cases/sod.ini (400 cells, bs32, t_end 0.2, 1 rank) with fluid.pressure = grid and
   particle under the OLD and the NEW mpmfsi, the four in turn, ROUNDS times, and takes each
   run's wall time from its summary.json (the step loop's own clock, set-up excluded). Quotes
   medians and the grid/particle ratio of each build.

Writes OUT (markdown) with the commit, date and command.

  /usr/bin/python3 bench/bench_span.py --old /path/to/old/build/app/mpmfsi \\
      [--new build/app/mpmfsi] [--rounds 5] [--out bench/results/span_cost.md]
"""
import argparse
import datetime
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from bench_build_ab import run  # noqa: E402  (one mpmfsi run, its wall_s and steps)


def micro(build):
    """Build and run bench_span.c; its stdout lines."""
    exe = os.path.join(build, "bench_span", "bench_span")
    os.makedirs(os.path.dirname(exe), exist_ok=True)
    hdf5 = [f"-isystem{d}" for d in ("/usr/include/hdf5/openmpi",) if os.path.isdir(d)]
    cmd = ["mpicc", "-O3", "-g", "-DNDEBUG", "-Wall", "-Wextra", "-Werror", "-std=c11",
           f"-I{ROOT}/common", f"-I{build}/common"] + hdf5 + [
           os.path.join(HERE, "bench_span.c"), os.path.join(ROOT, "common", "mpm_span.c"),
           "-lm", "-o", exe]
    subprocess.run(cmd, check=True)
    return subprocess.run([exe], capture_output=True, text=True, check=True).stdout.splitlines()


def sod(old, new, rounds):
    """{(build, pressure): [wall_s ...]} and the step counts, the four runs in turn."""
    case = os.path.join(ROOT, "cases", "sod.ini")
    walls, steps = {}, {}
    for k in range(rounds):
        for name, binary in (("old", old), ("new", new)):
            for pressure in ("grid", "particle"):
                r = run(binary, case, 1, 0.2, [f"fluid.pressure={pressure}"])
                walls.setdefault((name, pressure), []).append(r["wall_s"])
                steps[(name, pressure)] = r["steps"]
                print(f"round {k}: {name} {pressure}: {r['wall_s']:.3f} s, {r['steps']} steps",
                      flush=True)
    return walls, steps


def git_head():
    return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()


def report(a, lines, walls, steps):
    rows = [l.split() for l in lines if l and l[0] in "23"]
    agree = [l for l in lines if l.startswith("agree")]
    med = {k: statistics.median(v) for k, v in walls.items()}
    out = [
        "# Cost of the exact span integrals (fluid.pressure = grid)", "",
        f"Made by `/usr/bin/python3 bench/bench_span.py --old OLD --rounds {a.rounds}` at commit "
        f"{git_head()} (new), OLD being mpmfsi built the same way at {a.old_label}, "
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, on a shared 2-core "
        "machine (other jobs running: compare ratios, not absolute times).", "",
        "## The integrals alone (bench/bench_span.c, one process, old and new alternating)", "",
        "Old: the direct sum over the 3^dim Gauss points of each span with all 3^dim basis "
        "values and gradients at each; new: sum factorisation with the exact 1-D matrices "
        "(common/mpm_span.c). Fastest of 7 trials of 3 calls each; random fields on a box of "
        "128^2 (2-D) or 32^3 (3-D) full spans.", "",
        "| dim | integral | spans | old ns/span | new ns/span | old/new |",
        "| --- | --- | --- | --- | --- | --- |"]
    out += [f"| {r[0]}-D | {r[1]} | {r[2]} | {r[3]} | {r[4]} | {r[5]} |" for r in rows]
    out += ["", "Agreement, largest |new - old| over largest |old|:", ""]
    out += [f"- {l[len('agree '):]}" for l in agree]
    out += ["", f"## Sod, 400 cells, bs32, t_end 0.2, 1 rank ({a.rounds} rounds, the four runs in "
            "turn; wall of the step loop from summary.json)", "",
            "| build | pressure | median wall s | min | max | steps |",
            "| --- | --- | --- | --- | --- | --- |"]
    for key in (("old", "grid"), ("old", "particle"), ("new", "grid"), ("new", "particle")):
        v = walls[key]
        out.append(f"| {key[0]} | {key[1]} | {med[key]:.3f} | {min(v):.3f} | {max(v):.3f} | "
                   f"{steps[key]} |")
    r_old = med[("old", "grid")] / med[("old", "particle")]
    r_new = med[("new", "grid")] / med[("new", "particle")]
    pair = [g / p for g, p in zip(walls[("new", "grid")], walls[("new", "particle")])]
    out += ["", f"Grid over particle pressure: {r_old:.2f}x with the old integrals, {r_new:.2f}x "
            f"with the new (per round {min(pair):.2f} to {max(pair):.2f}); the grid pressure's "
            f"run: old/new {med[('old', 'grid')] / med[('new', 'grid')]:.2f}x.", ""]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--old", required=True, help="mpmfsi built from the code before (baseline)")
    ap.add_argument("--old-label", default=None, help="how to name the baseline in OUT (its commit)")
    ap.add_argument("--new", default=os.path.join(ROOT, "build", "app", "mpmfsi"))
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="this checkout's build")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "span_cost.md"))
    a = ap.parse_args()
    a.old_label = a.old_label or a.old
    if not shutil.which("mpicc"):
        sys.exit("bench_span.py: mpicc not found (it builds bench/bench_span.c)")
    lines = micro(a.build)
    print("\n".join(lines), flush=True)
    runs = os.path.join(a.build, "bench_span", "runs")  # bench_build_ab.run's run folders
    os.makedirs(runs, exist_ok=True)
    tempfile.tempdir = runs
    try:
        walls, steps = sod(a.old, a.new, a.rounds)
    finally:
        shutil.rmtree(runs, ignore_errors=True)
    text = report(a, lines, walls, steps)
    with open(a.out, "w") as f:
        f.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
