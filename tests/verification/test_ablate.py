"""The ablation harness (bench/ablate.py) measures every run against the reference it says it
uses, and never against a stale one. The shock-loaded panel is the scene: its case file sets
coupling.time = multirate, which the harness's reference inherited until 2026-11-29 (every
"monolithic reference" of the panel's sweeps was a multirate run). Coarse and short (dx = 2.5 mm,
4 us: a few hundred steps).

1. The reference is monolithic: its probes.csv is the one a run of the case with
   coupling.time = monolithic, time.method = usl and the reference's time.cfl writes, to the
   last digit (a multirate run takes other steps and writes other rows).
2. The same sweep again reuses the reference and the finished row: nothing is run.
3. The same sweep with one more override runs the reference again (the overrides changed) and
   redoes the row measured against the old one.
4. --repeat 2 makes a second round: the finished row is run once more (the same steps), runs.csv
   keeps both wall times and reports their median, to the last digit whatever the wall times (on
   a busy machine, where the run took over 1 s, the 6 digits the harness kept of each wall lost
   one, and this check failed; tests/conformance/test_ablate_input.py checks walls above 10 s).
5. ablation.md gives each multirate run's cost at equal error: monolithic's wall time
   interpolated log-log to its error between the monolithic runs that bracket it (or
   extrapolated, marked, by at most 1.5x in error), and the ratio. Checked on made-up rows whose
   answers are known (--report-only: nothing runs).
6. --replot redraws ablation.png from runs.csv alone (the made-up rows; nothing runs, no
   reference needed), and a sweep given no --out writes under out/ablate/<case>/, never into
   the tracked bench/results/.
"""
import csv
import math
import statistics
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_ablate")
SOURCE = os.path.abspath(mt.SOURCE)
CASE = mt.case("shock_panel.ini")
COMMON = ["grid.dx=0.0025", "time.t_end=4e-6", "run.progress=false"]
work = os.path.abspath(mt.outdir("ablate"))
res, scratch = os.path.join(work, "results"), os.path.join(work, "runs")


def sweep(extra, options=("--temporal", "monolithic", "--cfl", "0.4")):
    cmd = [sys.executable, os.path.join(SOURCE, "bench", "ablate.py"), CASE] + COMMON + extra + [
        "--spatial", "velocity", "--methods", "usl", "--ref-cfl", "0.2", "--out", res,
        "--scratch", scratch, "--binary",
        os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN] + list(options)
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"ablate.py failed ({p.returncode})")
    return p.stdout


def probes(folder):
    with open(os.path.join(folder, "probes.csv")) as f:
        return f.read()


sweep([])
ref = os.path.join(scratch, "reference-velocity")
mono = mt.outdir("ablate_monolithic")
mt.run(["run", CASE, f"output.dir={mono}", "output.interval=1e9", "coupling.scheme=velocity",
        "coupling.time=monolithic", "time.method=usl", "time.cfl=0.2"] + COMMON)
multi = mt.outdir("ablate_multirate")
mt.run(["run", CASE, f"output.dir={multi}", "output.interval=1e9", "coupling.scheme=velocity",
        "time.method=usl", "time.cfl=0.2"] + COMMON)
same, other = probes(ref) == probes(mono), probes(ref) != probes(multi)
check(same and other, f"the reference is the monolithic run to the last digit ({same}; the "
      f"case's own multirate differs: {other}; {len(probes(ref).splitlines()) - 1} rows)")
again = sweep([])
check("reference for" not in again and "[1/1]" not in again,
      "the same sweep again runs nothing (the reference and the row are current)")
changed = sweep(["fluid.regularise_every=0"])
check("reference for velocity" in changed and "run again" in changed and "[1/1]" in changed,
      "one more override: the reference is run again and the row measured against the old one "
      "is redone")


def rows():
    with open(os.path.join(res, "runs.csv")) as f:
        return {r["name"]: r for r in csv.DictReader(f)}


NAME = "velocity-monolithic-usl-0.4"
steps = rows()[NAME]["steps"]
twice = sweep(["fluid.regularise_every=0", "--repeat", "2"])
r = rows()[NAME]
walls = [float(w) for w in r["walls"].split(";")]
check("[round 2, 1/1]" in twice and "[1/1]" not in twice and len(walls) == 2
      and float(r["wall_s"]) == statistics.median(walls)
      and r["steps"] == steps,
      f"--repeat 2: the finished row runs once more ({r['walls']} s, median {r['wall_s']} s; "
      f"{r['steps']} steps both times)")
# 5: a table of made-up rows (no run), reported with --report-only against the reference above.
made_up = os.path.join(work, "made_up")
os.makedirs(made_up)
FIELDS = ["name", "spatial", "temporal", "variant", "method", "cfl", "status", "wall_s", "steps",
          "rhs_evals", "err_max", "err_rms", "err_rel", "W_net", "W_rel", "imbalance", "message",
          "walls"]
ROWS = [("monolithic", "", 0.4, 1e-4, 10.0), ("monolithic", "", 0.2, 5e-5, 20.0),
        ("monolithic", "", 0.1, 2.5e-5, 40.0),
        ("multirate", "held", 0.4, 1.2e-4, 2.0),  # beyond the coarsest by 1.2x: extrapolated
        ("multirate", "held", 0.2, 1e-4 / math.sqrt(2), 2.0),  # between 0.4 and 0.2
        ("multirate", "held", 0.1, 1e-3, 1.0)]  # 10x beyond: no figure
with open(os.path.join(made_up, "runs.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=FIELDS)
    w.writeheader()
    for temporal, variant, cfl, err, wall in ROWS:
        name = f"velocity-{temporal}{'-' + variant if variant else ''}-usl-{cfl:g}"
        w.writerow(dict(name=name, spatial="velocity", temporal=temporal, variant=variant,
                        method="usl", cfl=cfl, status="ok", wall_s=wall, steps=1, rhs_evals=1,
                        err_max=err, err_rms=err, err_rel=err, W_net=0, W_rel="", imbalance=0,
                        message="", walls=f"{wall:g}"))
subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "ablate.py"), CASE] + COMMON
               + ["fluid.regularise_every=0", "--spatial", "velocity", "--methods", "usl",
                  "--ref-cfl", "0.2", "--out", made_up, "--scratch", scratch, "--report-only",
                  "--temporal", "monolithic", "multirate", "--skip-variants", "interpolated", "lag",
                  "mristep", "--cfl", "0.4", "0.2", "0.1", "--binary",
                  os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN], check=True,
               capture_output=True, timeout=600)
with open(os.path.join(made_up, "ablation.md")) as f:
    md = f.read()
want = ["| velocity-multirate-held-usl-0.4 | 0.00012 | 2.00 | 8.3 (extrapolated) | 4.17 |",
        "| velocity-multirate-held-usl-0.2 | 7.07e-05 | 2.00 | 14.1 | 7.07 |",
        "| velocity-multirate-held-usl-0.1 | 0.001 | 1.00 | beyond monolithic's errors (2.5e-05 "
        "to 0.0001) by more than 1.5x | |"]
missing = [x for x in want if x not in md]
check(not missing, "the cost at equal error of made-up multirate rows: monolithic's time "
      "interpolated log-log to their errors (t ~ 1/error between the made-up monolithic rows: "
      "14.1 s at 1e-4/sqrt 2, 7.07x), extrapolated and marked at 1.2x beyond (4.17x), none at 10x"
      + (f"; missing: {missing}" if missing else ""))
# 6: --replot, and where results go without --out (--report-only: nothing runs).
png = os.path.join(made_up, "ablation.png")
os.remove(png)
p = subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "ablate.py"), "--replot",
                    made_up], capture_output=True, text=True, timeout=600)
check(p.returncode == 0 and os.path.getsize(png) > 10000 and "from 6 stable run(s)" in p.stdout,
      f"--replot redraws ablation.png from the 6 made-up rows ({p.stdout.strip()}{p.stderr})")
default = os.path.join(SOURCE, "out", "ablate", "shock_panel")
tracked = os.path.join(SOURCE, "bench", "results", "ablate_shock_panel", "ablation.md")
before = os.path.getmtime(tracked) if os.path.exists(tracked) else None
subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "ablate.py"), CASE] + COMMON
               + ["--spatial", "velocity", "--methods", "usl", "--temporal", "monolithic",
                  "--report-only", "--binary",
                  os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN],
               check=True, capture_output=True, timeout=600)
after = os.path.getmtime(tracked) if os.path.exists(tracked) else None
check(os.path.exists(os.path.join(default, "ablation.md")) and before == after,
      f"without --out the results go to {default}, and bench/results/ is left alone")
sys.exit(check.finish())
