"""Cost of the 3-D sphere at Mach 0.8 (cases/sphere_m08.ini, issue 52's case C) on the
refinement hierarchy against uniform grids, per particle-step (issue 51's 3-D bar: within 1.5x
of the uniform grid's).

Runs, each a separate mpmfsi process on one rank, one after another, all at the same fixed
step (time.dt_max = --dt, below every run's stable step, bs32 at a fixed step as the case runs),
for 2 + --steps steps from the case's start, and again for 2 steps, without
snapshots:
  refined         the case: 40^3 level-0 cells of 0.25 and levels 1 and 2 in its static boxes
  uniform         the same domain without refinement at level 0's spacing, with the grid
                  pressure the hierarchy takes (fluid.pressure = grid)
  uniform_part    the same with the particles' pressure (the unrefined default)
  fine_small      a uniform grid at the finest level's spacing (0.0625) over a smaller domain,
                  the cube of side --fine-side around the sphere (far-field faces, the sponge
                  scaled to a quarter), grid pressure
Printed and written per run: particles (start, and per level), steps, wall time of the stepping
loop (summary.json's wall_s, which leaves out the set-up and seeding), the user CPU time of the
process (/usr/bin/time), the peak resident memory, and the cost per particle-step: wall_s /
particle-steps (summary.json's particle_steps, the sum over steps of the particle count), and
the user CPU of the longer run less the shorter's over their particle-steps' difference (the
set-up drops out; on a shared machine the wall time carries the other jobs' load, the user CPU
much less). The refinement's own timers (restrict, prolong, relevel) as shares of the wall time.

Writes the rows as JSON and CSV under --out (default out/bench_sphere/) and the page --md
(default bench/results/sphere_cost.md).
  /usr/bin/python3 bench/bench_sphere.py [--binary build/app/mpmfsi] [--steps 6] [--dt 0.004]
      [--dx 0.25] [--runs refined,uniform,uniform_part,fine_small]
--dx 0.5 runs the scene at 20^3 level-0 cells (a quick look; the finest spacing doubles too).

  /usr/bin/python3 bench/bench_sphere.py --watch OUT_DIR
prints the stability of a run of the case (running or done) from its snapshots and csv files:
per snapshot the largest |v| and the range of rho and p, the particles per level and inside the
sphere; from diagnostics.csv the kinetic energy and the mass against the start; the drag
coefficient of obstacles.csv averaged since the previous snapshot; and the blow-up guard's
lines in run.log.
"""
import argparse
import configparser
import datetime
import glob
import os
import sys

import numpy as np

CWD = os.getcwd()  # mpmtest (imported by bench_refine) moves to a scratch folder
ROOT = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, ROOT)
from bench_refine import TIMERS, head_commit, run, write_rows  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(ROOT), "tests", "tools"))
import mpmtest as mt  # noqa: E402

ROOT = os.path.dirname(ROOT)
CASE = os.path.join(ROOT, "cases", "sphere_m08.ini")
DEFAULT_RUNS = "refined,uniform,uniform_part,fine_small"
CENTER = (4.0, 5.0, 5.0)
RADIUS = 0.5


def case_sections(drop_refine, domain=None, sponge=None):
    """The case file's text, without its [refine] sections if asked, on another domain."""
    cp = configparser.ConfigParser(inline_comment_prefixes=(";",), interpolation=None)
    cp.optionxform = str
    cp.read(CASE)
    if drop_refine:
        for s in [s for s in cp.sections() if s == "refine" or s.startswith("refine.")]:
            cp.remove_section(s)
    if domain is not None:
        lo, hi = (" ".join(f"{v:g}" for v in c) for c in domain)
        cp["domain"]["lo"], cp["domain"]["hi"] = lo, hi
        cp["geometry.air"]["lo"], cp["geometry.air"]["hi"] = lo, hi
    if sponge is not None:
        cp["freestream"]["sponge"] = f"{sponge:g}"
    lines = []
    for s in cp.sections():
        lines += [f"[{s}]"] + [f"{k} = {v}" for k, v in cp[s].items()] + [""]
    return "\n".join(lines)


def scenes(dx, fine_side):
    h_fine = dx / 4
    half = fine_side / 2
    small = ([c - half for c in CENTER], [c + half for c in CENTER])
    return {"refined": (None, [f"grid.dx={dx!r}"]),
            "uniform": (case_sections(True), [f"grid.dx={dx!r}", "fluid.pressure=grid",
                                              "fluid.pressure_relax=4"]),
            "uniform_part": (case_sections(True), [f"grid.dx={dx!r}"]),
            "fine_small": (case_sections(True, small, 0.25),
                           [f"grid.dx={h_fine!r}", "fluid.pressure=grid",
                            "fluid.pressure_relax=4"])}


def per_level(run_dir):
    d = np.genfromtxt(os.path.join(run_dir, "diagnostics.csv"), delimiter=",", names=True)
    return [int(d[n][0]) for n in d.dtype.names if n.startswith("particles_l")]


def one(binary, out, label, text, over, dt, steps):
    """A run of 2 + steps steps and one of 2; the user CPU per particle-step is the difference
    of the two runs' over the difference of their particle-steps, so that the set-up (seeding,
    the hierarchy, the first evaluation) drops out."""
    d = os.path.join(out, label)
    os.makedirs(d, exist_ok=True)
    case = CASE
    if text is not None:
        case = os.path.join(d, "case.ini")
        with open(case, "w") as f:
            f.write(text)
    r = {}
    for n, sub in ((2, "short"), (2 + steps, "long")):
        more = [f"time.dt_max={dt!r}", f"time.t_end={dt * (n - 0.5)!r}", "output.snapshots=false"]
        r[sub] = run(binary, os.path.join(d, sub), case, over + more)
    short, r = r["short"], r["long"]
    r["levels"] = per_level(r["dir"])
    r["steps_timed"] = r["steps"] - short["steps"]
    r["wall_per_ps_us"] = 1e6 * r["wall_s"] / r["particle_steps"]
    r["user_per_ps_us"] = (1e6 * (r["user_s"] - short["user_s"]) /
                           (r["particle_steps"] - short["particle_steps"]))
    r["user_setup_s"] = short["user_s"]
    return r


def page(rows, commit, command, dx, dt):
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = ["# Cost of the 3-D sphere at Mach 0.8 on the hierarchy against uniform grids", "",
             f"Made by `{command}` at commit {commit}, {now}, on a shared 2-core machine (the "
             "runs one after another; other jobs may run beside them, and then the wall times "
             "carry the machine's load: compare the user CPU column first). One rank, "
             f"`cases/sphere_m08.ini` with level 0 at dx = {dx:g}, every run at the fixed step "
             f"{dt:g} from the case's start, no snapshots. Wall: the stepping loop "
             "(summary.json), per particle-step: over the sum over steps of the particle count. "
             "User CPU (from /usr/bin/time): the whole process; per particle-step: the run's "
             "less that of a run of its first 2 steps, over the difference of their "
             "particle-steps (the set-up drops out; the set-up column is the short run's). "
             "Peak memory from /usr/bin/time.", "",
             "| run | particles (start) | per level | steps (timed) | RHS | wall s | user CPU s "
             "(set-up) | peak MB | wall µs / particle-step | user µs / particle-step | restrict "
             "| prolong | relevel |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for label, r in rows.items():
        share = [f"{100 * r['timers'].get(k, 0.0) / r['wall_s']:.1f} %" for k in TIMERS[:3]]
        levels = " / ".join(str(n) for n in r["levels"]) or "-"
        lines.append(f"| {label} | {r['particles_start']} | {levels} | {r['steps']} "
                     f"({r['steps_timed']}) | {r['rhs']} | {r['wall_s']:.1f} | {r['user_s']:.1f} "
                     f"({r['user_setup_s']:.1f}) | {r['rss_mb']:.0f} | "
                     f"{r['wall_per_ps_us']:.2f} | {r['user_per_ps_us']:.2f} | "
                     + " | ".join(share) + " |")
    lines.append("")
    ref = rows.get("refined")
    for label, r in rows.items():
        if ref is not None and label != "refined":
            wall = ref["wall_per_ps_us"] / r["wall_per_ps_us"]
            lines.append(f"- refined against {label}: {wall:.2f}× the wall per particle-step, "
                         f"{ref['user_per_ps_us'] / r['user_per_ps_us']:.2f}× the user CPU per "
                         f"particle-step, {ref['rss_mb'] / r['rss_mb']:.2f}× the peak memory.")
    return "\n".join(lines)


def watch(out):
    """Print the stability of a run of the case, snapshot by snapshot."""
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    ob = np.genfromtxt(os.path.join(out, "obstacles.csv"), delimiter=",", names=True,
                       dtype=None, encoding=None)
    print(f"steps {int(d['step'][-1])}, t = {d['t'][-1]:.4f}; mass "
          f"{d['mass'][-1] / d['mass'][0] - 1:+.2e} of the start, kinetic energy "
          f"{d['kinetic'][-1] / d['kinetic'][0]:.4f} of the start "
          f"(largest {d['kinetic'].max() / d['kinetic'][0]:.4f}), total energy "
          f"{d['total'][-1] / d['total'][0] - 1:+.2e}")
    print("t | particles (per level) | inside the sphere | max |v| | rho min..max | p min..max"
          " | Cd since the previous snapshot")
    t_prev = 0.0
    for path in sorted(glob.glob(os.path.join(out, "snap_*.h5"))):
        p = mt.particles(path, "fluid")
        t = p["time"]
        speed = np.linalg.norm(p["v"], axis=1)
        r = np.linalg.norm(p["x"] - np.array(CENTER), axis=1)
        levels = np.bincount(p["level"].astype(int).ravel())
        sel = (ob["t"] > t_prev) & (ob["t"] <= t)
        cd = f"{ob['Cd'][sel].mean():.3f}" if sel.any() else "-"
        print(f"{t:.3f} | {len(speed)} ({' / '.join(map(str, levels))}) | {(r < RADIUS).sum()} | "
              f"{speed.max():.3f} | {p['rho'].min():.3f}..{p['rho'].max():.3f} | "
              f"{p['p'].min():.3f}..{p['p'].max():.3f} | {cd}")
        t_prev = t
    with open(os.path.join(out, "run.log")) as f:
        guard = [line.strip() for line in f if "guard" in line or "collaps" in line]
    print("\n".join(guard) if guard else "run.log: no blow-up guard line")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "app", "mpmfsi"),
                    type=lambda b: os.path.join(CWD, b))
    ap.add_argument("--runs", default=DEFAULT_RUNS)
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--dt", type=float, default=0.004)
    ap.add_argument("--dx", type=float, default=0.25)
    ap.add_argument("--fine-side", type=float, default=2.5)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_sphere"),
                    type=lambda d: os.path.join(CWD, d))
    ap.add_argument("--md", default=os.path.join(ROOT, "bench", "results", "sphere_cost.md"),
                    type=lambda m: os.path.join(CWD, m))
    ap.add_argument("--watch", metavar="OUT_DIR", help="print the stability of a run and stop")
    a = ap.parse_args()
    if a.watch:
        return watch(os.path.join(CWD, a.watch))
    table = scenes(a.dx, a.fine_side)
    rows = {}
    for label in a.runs.split(","):
        if label not in table:
            raise SystemExit(f"unknown run {label}: choose among {DEFAULT_RUNS}")
        rows[label] = one(a.binary, a.out, label, *table[label], a.dt, a.steps)
        r = rows[label]
        print(f"{label}: {r['particles_start']} particles {r['levels']}, {r['steps']} steps, "
              f"wall {r['wall_s']:.1f} s, user {r['user_s']:.1f} s, {r['rss_mb']:.0f} MB, "
              f"{r['wall_per_ps_us']:.2f} / {r['user_per_ps_us']:.2f} µs per particle-step "
              "(wall / user)", flush=True)
    os.makedirs(a.out, exist_ok=True)
    flat = [dict(run=label, **{k: v for k, v in r.items() if k not in ("timers", "dir", "levels")},
                 levels=" ".join(map(str, r["levels"])),
                 **{f"t_{k}": r["timers"].get(k, 0.0) for k in TIMERS})
            for label, r in rows.items()]
    write_rows(a.out, "sphere_cost", flat)
    commit = head_commit()
    defaults = {"runs": DEFAULT_RUNS, "steps": 6, "dt": 0.004, "dx": 0.25, "fine_side": 2.5}
    extra = "".join(f" --{k.replace('_', '-')} {getattr(a, k)}" for k, v in defaults.items()
                    if getattr(a, k) != v)
    command = "/usr/bin/python3 bench/bench_sphere.py" + extra
    with open(a.md, "w") as f:
        f.write(page(rows, commit, command, a.dx, a.dt) + "\n")
    print(f"wrote {a.md}")


if __name__ == "__main__":
    main()
