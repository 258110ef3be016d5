"""What a user sees while and after a run (coupler/mpm_sim.c progress and summary,
common/mpm_log.c, coupler/mpm_budget.c). Short runs of cases/sod.ini and a coarse, short
cases/supersonic_bar.ini. Checks:

1. run.log in the output folder holds every line rank 0 logged, from the start-up lines (the
   grid, the estimate, which are logged before the folder exists) to the summary, without \\r.
2. A restart in place appends to run.log after a separator naming the checkpoint.
3. The estimate refined after the first steps lies within 30 % of the steps taken (Sod: the
   starting stable step alone gives about a quarter of them, see mpm_budget.h).
4. A console that is not a terminal (a pipe, here; also under mpiexec) receives no \\r.
5. One rank is "1 rank", never "1 ranks".
6. The coupling's energy is put on a scale: the log says what fraction of the energy that
   crossed the interface it is, and summary.json has the same numbers.
7. Under a terminal (util-linux `script`) and mpiexec -n 2, rank 0 draws the live progress
   line (\\r-redrawn, with step, ETA), ended by a newline, and run.log still has no \\r.
"""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_console")
SOD = mt.case("sod.ini")


def raw_run(cmd):
    """Run cmd; its stdout and stderr as text with every \\r kept (text=True would turn \\r
    into \\n: universal newlines)."""
    p = subprocess.run(cmd, capture_output=True, timeout=600, stdin=subprocess.DEVNULL)
    p.stdout, p.stderr = p.stdout.decode(errors="replace"), p.stderr.decode(errors="replace")
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"command failed ({p.returncode}): {' '.join(cmd)}")
    return p


def log_of(out):
    with open(os.path.join(out, "run.log"), newline="") as f:
        return f.read()


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


# ---- 1, 3, 4, 5: a short Sod run, stderr a pipe ------------------------------------------
out = mt.outdir("sod")
p = raw_run([mt.BIN, "run", SOD, f"output.dir={out}", "time.t_end=0.05",
             "run.progress_interval=0.2"])
log, s = log_of(out), summary(out)
check("\r" not in p.stderr, "stderr a pipe: no \\r in it")
for what, pattern in (("the grid line", r"^grid: .*cells of"),
                      ("the estimate line", r"^estimate: about [0-9.e+]+ steps"),
                      ("the refined estimate", r"^estimate after \d+ steps"),
                      ("the summary", r"^done: t = 0\.05, \d+ steps")):
    check(re.search(pattern, log, re.M) is not None, f"run.log holds {what}")
check("\r" not in log, "run.log has no \\r")
lines = [ln for ln in p.stderr.split("\n") if ln.strip()]
check(lines == [ln for ln in log.split("\n") if ln.strip()],
      f"run.log holds the console's lines, in order ({len(lines)} lines)")
check(re.search(r"\b1 ranks\b", p.stderr) is None and "1 rank (1 x 1)" in p.stderr,
      "one rank is logged as '1 rank'")
m = re.search(r"^estimate after \d+ steps: about ([0-9.e+]+) steps", p.stderr, re.M)
est = float(m[1]) if m else float("nan")
check(m is not None and abs(est - s["steps"]) <= 0.3 * s["steps"],
      f"Sod to t = 0.05: refined estimate {est:g} steps, taken {s['steps']} (within 30 %)")

# ---- 2: a restart in place appends ---------------------------------------------------------
ck = os.path.join(out, "checkpoint_final.h5")
p2 = mt.run(["restart", ck, "time.t_end=0.06"])
log2 = log_of(out)
sep = re.search(r"^==== restart from .*checkpoint_final\.h5 \(t = 0\.05, step \d+\), .* UTC ====$",
                log2, re.M)
check(log2.startswith(log) and sep is not None,
      "restart in place: run.log keeps the first run's lines and appends after a separator")
rest = log2[sep.end():] if sep else ""
check(re.search(r"^restarted from .* at t = 0\.05", rest, re.M) is not None
      and re.search(r"^done: t = 0\.06", rest, re.M) is not None,
      "the restart's start-up and summary lines follow the separator")

# ---- 4, 5 under mpiexec, 6: the coupling's scale --------------------------------------------
out = mt.outdir("bar")
p = raw_run([mt.MPIEXEC, "-n", "2", mt.BIN, "run", mt.case("supersonic_bar.ini"),
             f"output.dir={out}", "grid.dx=0.004", "time.t_end=0.0001", "output.snapshots=false"])
s = summary(out)
check("\r" not in p.stderr and re.search(r"\b2 ranks\b", p.stderr) is not None,
      "mpiexec -n 2, stderr a pipe: no \\r, '2 ranks'")
m = re.search(r"energy created by the coupling (\S+) J \((\S+) % of the (\S+) J that crossed "
              r"the interface, (\S+) % of the solid's peak energy (\S+) J, (\S+) % of the total "
              r"energy (\S+) J\)", p.stderr)
check(m is not None, "the coupling energy is logged with its scale: "
      + (m[0] if m else "no such line"))
ok = (m is not None and s["coupling_crossed"] > 0 and s["solid_energy_peak"] > 0
      and abs(s["coupling_work_of_crossed"] - s["coupling_work"] / s["coupling_crossed"]) < 1e-5
      * max(1, abs(s["coupling_work_of_crossed"]))
      and abs(float(m[2]) / 100 - s["coupling_work_of_crossed"]) <= 0.01 * abs(
          s["coupling_work_of_crossed"]) + 1e-9
      and abs(s["coupling_work"]) <= s["coupling_crossed"])
check(ok, f"summary.json: coupling_work {s['coupling_work']:.4g} J of coupling_crossed "
      f"{s['coupling_crossed']:.4g} J (ratio {s['coupling_work_of_crossed']:.3g}), "
      f"solid_energy_peak {s['solid_energy_peak']:.4g} J")

# ---- 7: the live line under a terminal -----------------------------------------------------
script = shutil.which("script")
if not script:
    print("skip the live line: util-linux `script` is not installed")
else:
    out = mt.outdir("live")
    cmd = [mt.MPIEXEC, "-n", "2", mt.BIN, "run", SOD, f"output.dir={out}", "time.t_end=0.2",
           "run.progress_interval=0.2"]
    # script gives the command a pseudo-terminal: mpiexec's stderr is a terminal, rank 0's a
    # pipe to mpiexec.
    p = raw_run([script, "-qec", shlex.join(cmd), "/dev/null"])
    text = p.stdout.replace("\r\n", "\n")  # the terminal's own line ends
    draws = re.findall(r"\rstep \d+[^\r\n]*ETA[^\r\n]*", text)
    check(p.returncode == 0 and len(draws) >= 2,
          f"under a terminal and mpiexec -n 2: {len(draws)} live progress draws with ETA "
          f"(at least 2; the last: {draws[-1].strip() if draws else '-'})")
    end = text.rfind("\rstep ")
    check(end >= 0 and re.match(r"\rstep [^\r\n]*\n", text[end:]) is not None
          and re.search(r"^done: t = 0\.2,", text[end:], re.M) is not None,
          "the live line is ended by a newline before the summary")
    # The same terminal, but one rank (no launcher) with stderr sent to a file: no \r there.
    single = mt.outdir("single")
    err = os.path.join(single, "stderr.txt")
    raw_run([script, "-qec", shlex.join([mt.BIN, "run", SOD, f"output.dir={single}",
                                         "time.t_end=0.01"]) + " 2> " + shlex.quote(err),
             "/dev/null"])
    with open(err, "rb") as f:
        text = f.read()
    check(b"\r" not in text and b"done: " in text,
          "under a terminal, one rank with stderr to a file: no \\r in the file")
    live_log = log_of(out) if os.path.exists(os.path.join(out, "run.log")) else "\r"
    check("\r" not in live_log and re.search(r"^done: ", live_log, re.M) is not None,
          "under a terminal, run.log still has no \\r and holds the summary")

sys.exit(check.finish())
