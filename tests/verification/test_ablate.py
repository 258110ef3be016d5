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
"""
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


def sweep(extra):
    cmd = [sys.executable, os.path.join(SOURCE, "bench", "ablate.py"), CASE] + COMMON + extra + [
        "--spatial", "velocity", "--temporal", "monolithic", "--methods", "usl", "--cfl", "0.4",
        "--ref-cfl", "0.2", "--out", res, "--scratch", scratch, "--binary",
        os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN]
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
sys.exit(check.finish())
