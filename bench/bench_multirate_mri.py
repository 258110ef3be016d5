"""Multirate with an ERK pair (ARKODE MRIStep) against monolithic, on the shock-loaded panel.

    /usr/bin/python3 bench/bench_multirate_mri.py [--dx DX] [--window T] [--ref-cfl C]
                                                  [--cfl C ...] [--mri-cfl C ...] [--ranks N]
                                                  [--tag T] [key=value ...]

The panel (cases/shock_panel.ini) is the fast module: its stable step is about a seventh of the
air's. With time.method = bs32 (fixed steps, time.adaptive = false; the gas's PIC share off, as
the ERK pairs require) the runs are:
  reference   monolithic at time.cfl = --ref-cfl (every step at the panel's limit);
  monolithic  at each --cfl (the panel's stable step sets every step of both modules);
  mristep     coupling.time = multirate at each --cfl and --mri-cfl: the gas steps at time.cfl
              of its own limit, the panel substeps inside with MRI-GARK-ERK33a coupling.
Error: the largest difference of the panel tip's x displacement (probes.csv, every step) from the
reference's over the window, relative to the reference's largest |tip|. Cost: wall time, steps,
joint RHS evaluations. The runs go one after the other, the pairs at each time.cfl back to back,
so a pair sees about the same load; their wall-time ratio is the speed-up at that time.cfl, and
the two errors say whether it comes at equal error. Cost at equal error: MRIStep's wall time at
each monolithic run's error, interpolated log-log between the MRIStep runs that bracket it
(--mri-cfl adds MRIStep runs at smaller steps for that).

key=value pairs go to every run (coupling.scheme=traction, say). Writes
bench/results/multirate_mri<tag>.md and .json; the committed multirate_mri.md was made with
--ranks 2, alone on the machine (without --tag a run replaces it).
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from benchrun import ENV, ROOT, loglog  # noqa: E402

CASE = os.path.join(ROOT, "cases", "shock_panel.ini")
RESULTS = os.path.join(HERE, "results")
ERK = ["time.method=bs32", "time.adaptive=false", "fluid.pic_fraction=0"]


def parse():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("overrides", nargs="*", help="key=value for every run")
    ap.add_argument("--dx", type=float, default=0.001)
    ap.add_argument("--window", type=float, default=1e-4, help="simulated time, s")
    ap.add_argument("--ref-cfl", type=float, default=0.1)
    ap.add_argument("--cfl", nargs="+", type=float, default=[0.4])
    ap.add_argument("--mri-cfl", nargs="*", type=float, default=[],
                    help="MRIStep alone at these time.cfl too")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--tag", default="")
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "app", "mpmfsi"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_multirate_mri"))
    return ap.parse_args()


def run(args, name, extra):
    out = os.path.join(args.out, name)
    cmd = [args.binary, "run", CASE, f"output.dir={out}", "output.overwrite=true",
           "output.interval=1e9", "run.progress=false", f"grid.dx={args.dx}",
           f"time.t_end={args.window}"] + ERK + args.overrides + extra
    if args.ranks > 1:
        cmd = ["mpiexec", "-n", str(args.ranks)] + cmd
    t0 = time.time()
    subprocess.run(cmd, env=ENV, check=True, capture_output=True)
    wall = time.time() - t0
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    p = np.loadtxt(os.path.join(out, "probes.csv"), delimiter=",", skiprows=1, ndmin=2)
    print(f"{name}: {wall:.1f} s, {s['steps']} steps, {s['rhs_evals']} joint RHS, tip "
          f"{p[-1, 1] * 1e3:.6f} mm at {p[-1, 0] * 1e3:.3f} ms", flush=True)
    return {"wall_s": wall, "steps": s["steps"], "rhs": s["rhs_evals"],
            "imbalance": s.get("coupling_imbalance"), "t": p[:, 0], "ux": p[:, 1]}


def equal_error_wall(points, err):
    """Wall time at error err, log-log between the two (error, wall) points around it."""
    for p0, p1 in zip(points, points[1:]):
        if p0[0] <= err <= p1[0] and p0[0] < p1[0]:
            return loglog(err, p0, p1)
    return None


def main():
    args = parse()
    ref = run(args, f"reference_{args.ref_cfl:g}",
              ["coupling.time=monolithic", f"time.cfl={args.ref_cfl}"])
    scale = float(np.max(np.abs(ref["ux"])))
    rows = []
    pairs = [(cfl, scheme) for cfl in args.cfl for scheme in ("monolithic", "mristep")]
    pairs += [(cfl, "mristep") for cfl in args.mri_cfl if cfl not in args.cfl]
    keys = {"monolithic": ["coupling.time=monolithic"], "mristep": ["coupling.time=multirate"]}
    for cfl, scheme in pairs:
        r = run(args, f"{scheme}_{cfl:g}", keys[scheme] + [f"time.cfl={cfl}"])
        err = float(np.max(np.abs(np.interp(ref["t"], r["t"], r["ux"]) - ref["ux"])))
        rows.append({"scheme": scheme, "cfl": cfl, "wall_s": r["wall_s"], "steps": r["steps"],
                     "rhs": r["rhs"], "err_rel": err / scale, "imbalance": r["imbalance"]})
    lines = ["# Multirate (MRIStep) against monolithic: shock panel, bs32 fixed steps",
             "", f"{' '.join(args.overrides) or 'the case as it stands'}; "
             f"dx = {args.dx * 1e3:g} mm, window {args.window * 1e3:g} ms, {args.ranks} "
             f"rank(s); reference: monolithic at time.cfl = {args.ref_cfl:g} "
             f"({ref['wall_s']:.1f} s, {ref['steps']} steps); largest reference tip "
             f"{scale * 1e3:.4f} mm. Generated by bench/bench_multirate_mri.py.", "",
             "| scheme | time.cfl | wall (s) | steps | joint RHS | tip error (rel.) | momentum "
             "imbalance |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scheme']} | {r['cfl']:g} | {r['wall_s']:.1f} | {r['steps']} | "
                     f"{r['rhs']} | {r['err_rel']:.2e} | {r['imbalance']:.1e} |")
    lines.append("")
    for cfl in args.cfl:
        m = next(r for r in rows if r["scheme"] == "monolithic" and r["cfl"] == cfl)
        q = next(r for r in rows if r["scheme"] == "mristep" and r["cfl"] == cfl)
        lines.append(f"- time.cfl = {cfl:g}: mristep {m['wall_s'] / q['wall_s']:.2f}x cheaper "
                     f"than monolithic; tip errors {q['err_rel']:.2e} against "
                     f"{m['err_rel']:.2e}.")
    mri = sorted((r["err_rel"], r["wall_s"]) for r in rows if r["scheme"] == "mristep")
    for m in (r for r in rows if r["scheme"] == "monolithic"):
        w = equal_error_wall(mri, m["err_rel"])
        lines.append(f"- at monolithic's error at time.cfl = {m['cfl']:g} ({m['err_rel']:.2e}): "
                     + (f"mristep would take {w:.1f} s, {m['wall_s'] / w:.2f}x cheaper "
                        f"(interpolated)" if w else "outside mristep's measured errors"))
    text = "\n".join(lines) + "\n"
    print(text)
    os.makedirs(RESULTS, exist_ok=True)
    with open(os.path.join(RESULTS, f"multirate_mri{args.tag}.md"), "w") as f:
        f.write(text)
    with open(os.path.join(RESULTS, f"multirate_mri{args.tag}.json"), "w") as f:
        json.dump({"overrides": args.overrides, "dx": args.dx, "window": args.window,
                   "ref_cfl": args.ref_cfl, "mri_cfl": args.mri_cfl,
                   "ranks": args.ranks, "reference_wall_s": ref["wall_s"], "rows": rows}, f,
                  indent=1)


if __name__ == "__main__":
    sys.exit(main())
