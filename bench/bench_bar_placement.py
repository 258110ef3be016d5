#!/usr/bin/python3
"""The main job's tip against where its bar's faces lie between the grid's nodes, and the main
job on two and three levels against those uniform runs (issue 51's main-job item).

Every uniform grid that divides the case's 0.03 m bar height evenly (1, 1.5, 2, 2.5 mm) puts the
bar's top face (y = 0.03) on a node line, as the floor always is. Level 1 of a hierarchy puts its
nodes half a cell off level 0's (o_1 = lo - h_1 / 2), so there the top face and the floor lie
halfway between nodes. A uniform grid whose spacing is 0.03 / (k + 1/2) (2.4, 1.62, 1.18 mm)
puts the top face halfway too (the floor stays a node line). This bench runs the case
(`cases/supersonic_bar.ini`, its defaults: `velocity`, `usl`) on both families, on two levels
(level 0 at 4 mm, a level-1 box of 2 mm around the bar) and on three (a 1 mm level-2 box inside),
and reports per run: the tip's maxima and the periods between them, the bar alone's period on
the same grid, the load's slope against the tip's swing, its largest u_x, the RMS of its u_x(t)
against each family's finest run over 0-3 ms, the stand-off's mean over 1.5-3 ms
(tools/supersonic_bar.py) and the wall time. Runs are kept under --out and reused when their
folder holds a finished run of the same command (delete it to re-run).

  /usr/bin/python3 bench/bench_bar_placement.py [--out out/bench_bar_placement] \
      [--md bench/results/bar_placement.md] [--ranks-fine 2]

Writes OUT/rows.json and OUT/rows.csv, and the page --md (the commit, the date and the
command at its top)."""
import argparse
import csv
import datetime
import json
import os
import subprocess
import sys

import numpy as np
from scipy.signal import find_peaks

from benchrun import ENV, ROOT, git

sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import bar_scene  # noqa: E402

CASE = os.path.join(ROOT, "cases", "supersonic_bar.ini")
T_END = 0.003
GAP_S = 4.5e-4  # about 0.4 of the tip's period
PROMINENCE_M = 1e-3  # a sixth of the tip's swing
# name, family, overrides, ranks ("fine" takes --ranks-fine)
RUNS = [
    ("on_2.5mm", "on", ["grid.dx=0.0025"], 1),
    ("on_2mm", "on", ["grid.dx=0.002"], 1),
    ("on_1mm", "on", ["grid.dx=0.001"], "fine"),
    ("mid_2.4mm", "mid", [f"grid.dx={0.03 / 12.5!r}"], 1),
    ("mid_1.62mm", "mid", [f"grid.dx={0.03 / 18.5!r}"], 1),
    ("mid_1.18mm", "mid", [f"grid.dx={0.03 / 25.5!r}"], "fine"),
    ("levels_4_2mm", "levels", ["grid.dx=0.004", "fluid.pressure=grid", "refine.levels=2",
                                "refine.box.level=1", "refine.box.lo=0.08 0",
                                "refine.box.hi=0.16 0.07"], 1),
    ("levels_4_2_1mm", "levels", ["grid.dx=0.004", "fluid.pressure=grid", "refine.levels=3",
                                  "refine.a.level=1", "refine.a.lo=0.06 0", "refine.a.hi=0.18 0.09",
                                  "refine.b.level=2", "refine.b.lo=0.084 0",
                                  "refine.b.hi=0.136 0.06"], "fine"),
]
# The bar alone on the levels' hierarchies, in bar_scene's domain cut to 132 x 48 mm: the same
# level-0 spacing and the boxes clipped to the cut (level 2's kept two level-1 cells inside 1's).
ALONE_LEVELS = {
    "levels_4_2mm": ["refine.levels=2", "refine.box.level=1", "refine.box.lo=0.08 0",
                     "refine.box.hi=0.132 0.048"],
    "levels_4_2_1mm": ["refine.levels=3", "refine.a.level=1", "refine.a.lo=0.06 0",
                       "refine.a.hi=0.132 0.048", "refine.b.level=2", "refine.b.lo=0.084 0",
                       "refine.b.hi=0.124 0.04"],
}
REFS = {"on": "on_1mm", "mid": "mid_1.18mm"}


def finished(out, cmd):
    try:
        with open(os.path.join(out, "bench_command.json")) as f:
            if json.load(f) != cmd:
                return False
        with open(os.path.join(out, "summary.json")) as f:
            return json.load(f).get("t", 0.0) >= T_END * (1 - 1e-9)
    except (OSError, ValueError):
        return False


def run(binary, name, overrides, ranks, root):
    out = os.path.join(root, name)
    cmd = ([binary, "run", CASE] + overrides + [f"output.dir={out}", "run.progress=false"])
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    if not finished(out, cmd):
        os.makedirs(out, exist_ok=True)
        print(f"running {name}: {' '.join(cmd)}", flush=True)
        subprocess.run(cmd, check=True, env=ENV, capture_output=True)
        with open(os.path.join(out, "bench_command.json"), "w") as f:
            json.dump(cmd, f)
    subprocess.run([sys.executable, os.path.join(ROOT, "tools", "supersonic_bar.py"), out],
                   check=True, capture_output=True)
    return out


def alone(binary, name, dx, root, extra=()):
    """The bar's first period alone at spacing dx, on the hierarchy extra names if any
    (tests/tools/bar_scene.py, as test_bar_clamp runs it), ms."""
    out, case = os.path.join(root, name + "_alone"), os.path.join(root, name + "_alone.ini")
    bar_scene.write(case, dx=dx)
    subprocess.run([binary, "run", case, f"output.dir={out}", "output.overwrite=true",
                    "run.progress=false"] + list(extra), check=True, env=ENV, capture_output=True)
    return 1e3 * bar_scene.period(out)[0]


def tip(out):
    p = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
    return p["t"], p["tip_ux"], p["tip_vx"]


def maxima(t, ux):
    """Times of the tip's u_x maxima: the peaks of u_x resampled every microsecond, at least
    GAP_S apart and standing PROMINENCE_M above the troughs beside them, so that a ripple on a
    swing (a gas particle's kick at the tip) is not taken for one; each refined by the parabola
    through it and its neighbours."""
    g = np.arange(0.0, t[-1], 1e-6)
    u = np.interp(g, t, ux)
    k, _ = find_peaks(u, distance=int(GAP_S / 1e-6), prominence=PROMINENCE_M)
    k = k[(k > 0) & (k < len(u) - 1)]
    a, b, c = u[k - 1], u[k], u[k + 1]
    return g[k] + 1e-6 * 0.5 * (a - c) / (a - 2 * b + c)


def stiffness(out, t, ux, vx):
    """-dF/du of the gas's load on the bar: the least-squares fit F = a + b u + c v of the load
    (coupling.csv, Fx_solid) against the tip's u_x and v_x over 0.3-3 ms (after the start's
    transient), -b in N/m per m of span: the stiffness the flow adds where positive."""
    c = np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)
    g = np.linspace(3e-4, T_END, 2000)
    A = np.c_[np.ones_like(g), np.interp(g, t, ux), np.interp(g, t, vx)]
    co = np.linalg.lstsq(A, np.interp(g, c["t"], c["Fx_solid"]), rcond=None)[0]
    return -float(co[1])


def measure(out, ranks):
    t, ux, vx = tip(out)
    tm = maxima(t, ux)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "standoff.csv")) as f:
        so = [float(r["standoff_m"]) for r in csv.DictReader(f) if float(r["t"]) >= 0.0015 - 1e-9]
    return {"maxima_ms": [1e3 * x for x in tm], "periods_ms": [1e3 * x for x in np.diff(tm)],
            "tip_ux_max_mm": 1e3 * float(ux.max()), "flow_stiffness": stiffness(out, t, ux, vx),
            "standoff_mean_mm": 1e3 * float(np.mean(so)),
            "steps": s.get("steps"), "wall_s": s.get("wall_s"), "ranks": ranks,
            "build": s.get("version", "?").split("git ")[-1].rstrip(")")}


def rms_mm(a, b):
    """RMS of u_x(t) of run a against run b on a 10 us grid over 0-3 ms, mm."""
    g = np.linspace(0.0, T_END, 301)
    (ta, ua, _), (tb, ub, _) = tip(a), tip(b)
    return 1e3 * float(np.sqrt(np.mean((np.interp(g, ta, ua) - np.interp(g, tb, ub)) ** 2)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "app", "mpmfsi"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_bar_placement"))
    ap.add_argument("--md", default=os.path.join(ROOT, "bench", "results", "bar_placement.md"))
    ap.add_argument("--ranks-fine", type=int, default=2)
    a = ap.parse_args(argv)
    outs, rows = {}, []
    for name, family, overrides, ranks in RUNS:
        ranks = a.ranks_fine if ranks == "fine" else ranks
        outs[name] = run(a.binary, name, overrides, ranks, a.out)
        rows.append(dict(name=name, family=family, overrides=" ".join(overrides),
                         **measure(outs[name], ranks)))
        rows[-1]["alone_period_ms"] = alone(a.binary, name, float(overrides[0].split("=")[1]),
                                            a.out, ALONE_LEVELS.get(name, ()))
        rows[-1]["ratio"] = [p / rows[-1]["alone_period_ms"] for p in rows[-1]["periods_ms"]]
    for r in rows:
        for fam, ref in REFS.items():
            r[f"rms_vs_{ref}_mm"] = rms_mm(outs[r["name"]], outs[ref])
    with open(os.path.join(a.out, "rows.json"), "w") as f:
        json.dump(rows, f, indent=1)
    keys = ["name", "family", "overrides", "periods_ms", "alone_period_ms", "ratio",
            "flow_stiffness", "tip_ux_max_mm", "standoff_mean_mm"] + [
        f"rms_vs_{ref}_mm" for ref in REFS.values()] + ["steps", "wall_s", "ranks", "build"]
    with open(os.path.join(a.out, "rows.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    lines = [
        "# The main job's tip against its faces' placement, and on levels",
        "",
        f"`/usr/bin/python3 bench/bench_bar_placement.py` at {git('rev-parse', '--short', 'HEAD')}"
        f", {datetime.date.today().isoformat()}, on this project's 2-core machine (one run at a "
        "time; the finest runs on 2 ranks; build: the run's own, from its summary.json, for runs "
        "kept from an earlier invocation). `on`: the bar's top face on a node line "
        "(every grid whose spacing divides 0.03 m); `mid`: halfway between node lines (spacing "
        "0.03 / (k + 1/2)); `levels`: 4 / 2 mm and 4 / 2 / 1 mm, whose finer levels' node lines "
        "lie half a cell off the top face and the floor. RMS: the tip's u_x(t) over 0-3 ms against "
        "the named run. Periods: between successive maxima of u_x. Alone: the bar's first "
        "period without the gas at the same spacing and levels (tests/tools/bar_scene.py, as "
        "test_bar_clamp runs it); periods / alone: the flow's effect. -dF/du: the load's slope "
        "against the tip's u_x, fitted with v_x over 0.3-3 ms, per m of span.",
        "",
        "| run | case overrides | periods (ms) | alone (ms) | periods / alone | -dF/du (MN/m²) "
        "| largest u_x (mm) | stand-off, mean 1.5-3 ms (mm) "
        "| RMS vs on_1mm (mm) | RMS vs mid_1.18mm (mm) | steps | wall (s), ranks | build |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['name']} | `{r['overrides']}` | "
            f"{', '.join(f'{p:.3f}' for p in r['periods_ms'])} | "
            f"{r['alone_period_ms']:.3f} | {', '.join(f'{q:.3f}' for q in r['ratio'])} | "
            f"{1e-6 * r['flow_stiffness']:.2f} | {r['tip_ux_max_mm']:.2f} | "
            f"{r['standoff_mean_mm']:.1f} | {r['rms_vs_on_1mm_mm']:.2f} | "
            f"{r['rms_vs_mid_1.18mm_mm']:.2f} | {r['steps']} | {r['wall_s']:.0f}, {r['ranks']} | "
            f"{r['build']} |")
    with open(a.md, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
