"""Cost of the refined gas against its uniform twins (issue 51's benchmarks): for each case the
refined run, the same scene without refinement at level 0's spacing (coarse) and at the finest
level's (fine): particles, steps, RHS evaluations, wall time, user CPU time (which another job on
the shared machine changes far less than the wall time), peak memory, the error the case
measures, and the refinement's overhead (timers restrict, prolong, relevel, regrid) as a share
of the wall time.

Cases (the scenes of tests/verification/test_refine_gas.py):
  stream    2-D strip, periodic along x, slip walls; a static level-1 box; a uniform stream
            (u = 0.5 c) to t = 1.4. Error: the largest deviation of rho, p, v from the stream.
  pulse     cases/refine_pulse.ini: a pulse of amplitude 5e-2 followed by a regridded band.
            Error: the mean |rho - rho_fine| over the band's rows 0.2 < y < 0.4 at t = 1.2,
            binned along x into 60 cells (the fine twin is the reference: its error is 0).
  stream3d  the stream in 3-D (x and z periodic), to t = 0.45.
  sod, sod3, sod4, sod3_usl, sod4_usl, sod4_cost
            cases/sod.ini over 100 level-0 cells, 3 across (periodic in y: every level wraps),
            regridded by the density criterion (refine_scenes.sod_refine) with 2, 3 and 4 levels
            under bs32 (sod, sod3, sod4) and 3 and 4 under the case's usl (sod3_usl, sod4_usl),
            both at the case's fixed time.cfl = 0.9, and with the settings of issue 51's cost
            bar (sod4_cost: refine_scenes.SOD_COST, usl),
            against the uniform twins at the finest spacing on the same strip, with the grid
            pressure the refined run takes (fine) and the default particle pressure
            (fine_particle). Error: the density's L1 on the finest cells (tests/tools/
            shocktube.py, as tests/verification/test_refine_sod.py).

Each run is a separate mpmfsi process under /usr/bin/time (peak resident memory). The runs go
one after another, the twins of a case next to each other, so compare within a case. Writes the
rows as JSON and CSV under --out (default out/bench_refine/) and the page --md (default
bench/results/refine_cost.md).
  /usr/bin/python3 bench/bench_refine.py [--binary build/app/mpmfsi] [--cases stream,pulse,...]
      [--pairs N] [--instructions]
--pairs N times each Sod case's refined run and its fine twin N more times, in turn, and prints
the median and range of the user-time ratio (the machine's speed drifts within minutes: a pair
run back to back shares it); --instructions counts both under cachegrind (about 40 times
slower), the measure the machine's load does not change.
"""
import argparse
import csv
import datetime
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
from refine_scenes import (BOX, BOX_3D, C0, CASE_3D, SOD_COARSE, SOD_COST, case_text,  # noqa: E402
                           sod_refine)
from riemann import Riemann  # noqa: E402

U0 = 0.5 * C0
GAS_STREAM = f"density = 1\npressure = 1\nvelocity = {U0!r} 0"
TIMERS = ("restrict", "prolong", "relevel", "regrid")
# case: (refinement levels, time.method, refinement settings); the case's own usl and the ERK
# pair bs32, both at the case's fixed time.cfl = 0.9; sod4_cost: the settings of issue 51's cost
# bar (refine_scenes.SOD_COST)
SOD_LEVELS = {"sod": (2, "bs32"), "sod3": (3, "bs32"), "sod4": (4, "bs32"),
              "sod3_usl": (3, "usl"), "sod4_usl": (4, "usl")}
SOD_LEVELS = {k: (n, m, sod_refine(n)) for k, (n, m) in SOD_LEVELS.items()}
SOD_LEVELS["sod4_cost"] = (SOD_COST["levels"], "usl",
                           sod_refine(SOD_COST["levels"], SOD_COST["threshold"], SOD_COST["every"]))
DEFAULT_CASES = "stream,pulse,stream3d," + ",".join(SOD_LEVELS)
KEPT_SECTION = "## Settings swept for Sod"


def run(binary, out, case, overrides, instructions=False):
    """One run: its summary, timers, peak memory (MB), user CPU (s) and output folder; with
    instructions, under cachegrind, its instruction count instead of the times."""
    os.makedirs(out, exist_ok=True)
    cmd = [binary, "run", case, f"output.dir={out}/run", "output.overwrite=true",
           "run.progress=false"] + overrides
    if instructions:
        cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=no",
               f"--cachegrind-out-file={out}/cachegrind.out"] + cmd
    p = subprocess.run(["/usr/bin/time", "-f", "%M %U"] + cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}")
    if instructions:
        refs = [ln for ln in p.stderr.splitlines() if "I   refs:" in ln]
        return {"instructions": int(refs[-1].split()[-1].replace(",", ""))}
    rss_kb, user_s = p.stderr.strip().splitlines()[-1].split()
    rss_mb = int(rss_kb) / 1024.0
    run_dir = os.path.join(out, "run")
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    timers = {}
    with open(os.path.join(run_dir, "timers.csv")) as f:
        for row in csv.DictReader(f):
            timers[row["phase"]] = float(row["mean_s"])
    d = np.genfromtxt(os.path.join(run_dir, "diagnostics.csv"), delimiter=",", names=True)
    return {"steps": int(d["step"][-1]), "rhs": int(d["rhs_evals"][-1]),
            "particles_start": int(d["particles"][0]), "particles_end": int(d["particles"][-1]),
            "particle_steps": summary["particle_steps"], "wall_s": summary["wall_s"],
            "user_s": float(user_s), "rss_mb": rss_mb, "timers": timers, "dir": run_dir}


def final(run_dir):
    return mt.particles(mt.snapshots(run_dir)[-1][1], "fluid")


def stream_error(run_dir, dim):
    p = final(run_dir)
    return float(max(np.abs(p["rho"] - 1).max(), np.abs(p["p"] - 1).max(),
                     np.abs(p["v"][:, 0] - U0).max() / U0,
                     np.abs(p["v"][:, 1:dim]).max() / U0))


def band_density(run_dir, nbins=60):
    p = final(run_dir)
    x, y = p["x"][:, 0], p["x"][:, 1]
    sel = (y > 0.2) & (y < 0.4)
    k = np.minimum((x[sel] / 3 * nbins).astype(int), nbins - 1)
    return (np.bincount(k, p["m"].ravel()[sel], nbins) /
            np.bincount(k, (p["m"] / p["rho"]).ravel()[sel], nbins))


def case_stream(binary, out, dim):
    dx = 0.05 if dim == 2 else 0.075
    refine = BOX.format(x0=0.8, x1=1.2) if dim == 2 else BOX_3D
    rows = {}
    for label, box, h in (("refined", refine, dx), ("coarse", "", dx), ("fine", "", dx / 2)):
        d = os.path.join(out, f"stream{dim}d_{label}")
        os.makedirs(d, exist_ok=True)
        path = os.path.join(d, "case.ini")
        with open(path, "w") as f:
            f.write(case_text(2, 1.4, GAS_STREAM, box, h) if dim == 2 else
                    CASE_3D.format(u0=U0, refine=box, dx=h))
        r = run(binary, d, path, [])
        r["error"] = stream_error(r["dir"], dim)
        rows[label] = r
    return rows


def case_pulse(binary, out):
    case = os.path.join(ROOT, "cases", "refine_pulse.ini")
    rows = {}
    for label, over in (("refined", []), ("coarse", ["refine.levels=1", "refine.criterion=none"]),
                        ("fine", ["refine.levels=1", "refine.criterion=none", "grid.dx=0.025"])):
        rows[label] = run(binary, os.path.join(out, f"pulse_{label}"), case, over)
    ref = band_density(rows["fine"]["dir"])
    for r in rows.values():
        r["error"] = float(np.abs(band_density(r["dir"]) - ref).mean())
    return rows


def case_sod(binary, out, name, levels, method, refine, pairs=0, instructions=False):
    """The Sod runs of case `name`; then, with pairs, the refined run and its fine twin timed
    in turn that many times more (user CPU: the ratio of each pair), and with instructions
    both counted under cachegrind."""
    fine = SOD_COARSE * 2 ** (levels - 1)
    exact = Riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), gamma=1.4, x0=0.5)
    case = os.path.join(ROOT, "cases", "sod.ini")
    height = 3.0 / SOD_COARSE
    runs = {"refined": (SOD_COARSE, refine), "coarse": (SOD_COARSE, []),
            "fine": (fine, ["fluid.pressure=grid", "fluid.pressure_relax=4"]),
            "fine_particle": (fine, [])}

    def one(label, **kw):
        N, extra = runs[label]
        over = [o for o in shocktube.overrides(N, method, 0.2, height=height)
                if not o.startswith("run.progress")] + ["output.interval=0.2"]
        return run(binary, os.path.join(out, f"{name}_{label}"), case, over + extra, **kw)

    rows = {}
    for label in runs:
        rows[label] = one(label)
        rows[label]["error"] = shocktube.measure(rows[label]["dir"], fine, exact, 0.2)[0]
    ratios = []
    for k in range(pairs):
        ratios.append(one("refined")["user_s"] / one("fine")["user_s"])
        print(f"{name} pair {k + 1}: user time refined / fine {ratios[-1]:.3f}", flush=True)
    if ratios:
        rows["refined"]["pairs"] = ratios
    if instructions:
        for label in ("refined", "fine"):
            rows[label]["instructions"] = one(label, instructions=True)["instructions"]
            print(f"{name} {label}: {rows[label]['instructions']:,} instructions", flush=True)
    return rows


ERRORS = {"stream": "largest deviation of rho, p, v (relative)",
          "stream3d": "largest deviation of rho, p, v (relative)",
          "pulse": "mean |rho - rho_fine| over the band's rows (fine: the reference)",
          **{name: "L1 of the density on the finest cells (fine: grid pressure, as refined)"
             for name in SOD_LEVELS}}


def write_rows(out, stem, rows):
    """rows (a list of flat dicts with the same keys) as out/stem.json and out/stem.csv."""
    with open(os.path.join(out, stem + ".json"), "w") as f:
        json.dump(rows, f, indent=1)
    with open(os.path.join(out, stem + ".csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def head_commit():
    """The short hash of the checkout's HEAD (for the results page)."""
    return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()


def page(results, commit, command):
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = ["# Cost of the refined gas against its uniform twins", "",
             f"Made by `{command}` at commit {commit}, {now}, on a shared 2-core machine "
             "(compare within a case: its runs went one after another). One rank. Wall time "
             "from each run's summary (the step loop), user CPU time (the whole process, set-up "
             "included) and peak memory from /usr/bin/time. The overhead columns are "
             "the refinement's timers as a share of the run's wall time (restrict and prolong "
             "run inside the grid and transfer phases, relevel, the particles' splits and merges, "
             "inside post_step, regrid between steps).", ""]
    for name, rows in results.items():
        lines += [f"## {name}", "", f"Error: {ERRORS[name]}.", "",
                  "| run | particles (start / end) | steps | RHS | wall s | user s | peak MB | "
                  "error | restrict | prolong | relevel | regrid |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
        for label, r in rows.items():
            t = r["timers"]
            share = [f"{100 * t.get(k, 0.0) / r['wall_s']:.1f} %" for k in TIMERS]
            lines.append(f"| {label} | {r['particles_start']} / {r['particles_end']} | "
                         f"{r['steps']} | {r['rhs']} | {r['wall_s']:.2f} | {r['user_s']:.2f} | "
                         f"{r['rss_mb']:.0f} | "
                         f"{r['error']:.2e} | " + " | ".join(share) + " |")
        ref, fine = rows["refined"], rows["fine"]
        lines += ["", f"Refined against fine: {ref['wall_s'] / fine['wall_s']:.2f}× the wall "
                  f"time, {ref['user_s'] / fine['user_s']:.2f}× the user CPU time, "
                  f"{ref['particle_steps'] / fine['particle_steps']:.2f}× the "
                  f"particle-steps, {ref['rss_mb'] / fine['rss_mb']:.2f}× the peak memory", ""]
        if name.startswith("sod"):
            lines[-2] += f", {ref['error'] / fine['error']:.3f}× the error"
        lines[-2] += "."
        if "pairs" in ref:
            q = ref["pairs"]
            lines.insert(-1, f"User CPU time refined over fine, {len(q)} pairs timed in turn: "
                         f"median {np.median(q):.3f}, {min(q):.3f} to {max(q):.3f}.")
        if "instructions" in ref:
            lines.insert(-1, f"Instructions (cachegrind): refined {ref['instructions']:,}, fine "
                         f"{fine['instructions']:,}, a ratio of "
                         f"{ref['instructions'] / fine['instructions']:.3f}.")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "app", "mpmfsi"))
    ap.add_argument("--cases", default=DEFAULT_CASES)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_refine"))
    ap.add_argument("--md", default=os.path.join(ROOT, "bench", "results", "refine_cost.md"))
    ap.add_argument("--pairs", type=int, default=0,
                    help="Sod cases: time the refined run and its fine twin in turn N times more")
    ap.add_argument("--instructions", action="store_true",
                    help="Sod cases: count both runs' instructions under cachegrind (slow)")
    a = ap.parse_args()
    os.environ["MPMFSI_BIN"] = a.binary
    results = {}
    for name in a.cases.split(","):
        if name == "stream":
            results[name] = case_stream(a.binary, a.out, 2)
        elif name == "stream3d":
            results[name] = case_stream(a.binary, a.out, 3)
        elif name == "pulse":
            results[name] = case_pulse(a.binary, a.out)
        elif name in SOD_LEVELS:
            results[name] = case_sod(a.binary, a.out, name, *SOD_LEVELS[name], pairs=a.pairs,
                                     instructions=a.instructions)
        else:
            raise SystemExit(f"unknown case {name}: choose among {DEFAULT_CASES}")
        for label, r in results[name].items():
            print(f"{name} {label}: {r['steps']} steps, {r['wall_s']:.2f} s ({r['user_s']:.2f} s user), {r['rss_mb']:.0f} MB,"
                  f" error {r['error']:.2e}", flush=True)
    os.makedirs(a.out, exist_ok=True)
    flat = [dict(case=n, run=label,
                 **{k: v for k, v in r.items()
                    if k not in ("timers", "dir", "pairs", "instructions")},
                 pairs=" ".join(f"{q:.4f}" for q in r.get("pairs", [])),
                 instructions=r.get("instructions", ""),
                 **{f"t_{k}": r["timers"].get(k, 0.0) for k in TIMERS})
            for n, rows in results.items() for label, r in rows.items()]
    write_rows(a.out, "refine_cost", flat)
    commit = head_commit()
    command = "/usr/bin/python3 bench/bench_refine.py" + (
        f" --cases {a.cases}" if a.cases != DEFAULT_CASES else "") + (
        f" --pairs {a.pairs}" if a.pairs else "") + (" --instructions" if a.instructions else "")
    # The sweep of Sod's settings below the generated tables is measured by hand (the page says
    # when): keep it, which the docs link to.
    kept = ""
    if os.path.exists(a.md):
        with open(a.md) as f:
            text = f.read()
        at = text.find(KEPT_SECTION)
        kept = "\n" + text[at:] if at >= 0 else ""
    with open(a.md, "w") as f:
        f.write(page(results, commit, command) + "\n" + kept)
    print(f"wrote {a.md}")


if __name__ == "__main__":
    main()
