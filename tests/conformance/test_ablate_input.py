"""The ablation harness (bench/ablate.py) refuses bad input before any run, and never tabulates
a partial row of its runs.csv (issue 54, item 6).

1. Every bad input exits 2 with one line on stderr that names the file, key or option and what
   to do, and leaves no results folder: a missing case, a folder, a file that is not a case, a
   misspelt key (mpmfsi check's line relayed), a one-phase case, a case without a probe, an
   override of a key the harness sets, a bad --cfl, a missing binary, one that is not
   executable and one that does not run as mpmfsi.
2. runs.csv cut inside a row (its W_net a million times too large as written): --report-only and
   --replot leave the row out of the table and say so; a resumed sweep runs it again. A row
   whose figures differ from its run's summary.json, or whose run output is gone, is run again.
3. runs.csv is replaced whole: a link named runs.csv is replaced, its target left alone.
4. --repeat 2 with wall times above 1 s (a busy machine): wall_s is the median of the walls
   runs.csv holds, to the last digit (6 digits once lost part of a wall above 1 s).

Parts 2-4 run a stand-in for mpmfsi (a script answering --version, check and run, writing a
summary.json and probes.csv whose figures are known), so nothing here depends on the machine's
speed; about 15 s in all on an idle machine (most of it Python starting and matplotlib).
"""
import csv
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_ablate_input")
SOURCE = os.path.abspath(mt.SOURCE)
ABLATE = os.path.join(SOURCE, "bench", "ablate.py")
BIN = os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN
PANEL = mt.case("shock_panel.ini")
SMALL = ["grid.dx=0.0025", "time.t_end=4e-6"]
work = os.path.abspath(mt.outdir("ablate_input"))
OPTIONS = ["--spatial", "velocity", "--methods", "usl", "--temporal", "monolithic",
           "--ref-cfl", "0.2"]


def ablate(args, binary=BIN, out="results"):
    cmd = [sys.executable, ABLATE] + list(args) + OPTIONS + [
        "--out", os.path.join(work, out), "--scratch", os.path.join(work, out + "_runs"),
        "--binary", binary]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300)


# 1: bad input.
not_exec = os.path.join(work, "not_executable")
with open(not_exec, "w") as f:
    f.write("not a program\n")
BAD = [("a missing case", ["no_such_case.ini"], BIN, "no case file no_such_case.ini"),
       ("a folder as the case", [work], BIN, "is a folder"),
       ("a file that is not a case", [os.path.join(SOURCE, "README.md")], BIN,
        "README.md:3: syntax error"),
       ("a misspelt key", [PANEL] + SMALL + ["time.t_edn=1"], BIN, "'time.t_edn'; did you mean"),
       ("a one-phase case", [mt.case("sod.ini")], BIN, "has only a gas"),
       ("a case without a probe", [mt.case("fsi_box.ini")], BIN, "no [probe.NAME]"),
       ("an override of a key the harness sets", [PANEL] + SMALL + ["time.cfl=0.3"], BIN,
        "the harness sets time.cfl itself"),
       ("a coupling step above 1", [PANEL] + SMALL + ["--cfl", "1.5"], BIN, "--cfl 1.5"),
       ("a missing binary", [PANEL] + SMALL, os.path.join(work, "no_such_mpmfsi"),
        "no executable"),
       ("a binary that is not executable", [PANEL] + SMALL, not_exec, "not an executable file"),
       ("a binary that does not run as mpmfsi", [PANEL] + SMALL, "false",
        "does not run as mpmfsi")]
for what, args, binary, want in BAD:
    p = ablate(args, binary, out="bad")
    lines = p.stderr.strip().splitlines()
    check(p.returncode == 2 and len(lines) == 1 and lines[0].startswith("ablate.py: error: ")
          and want in lines[0] and not os.path.exists(os.path.join(work, "bad")),
          f"{what}: exit {p.returncode}, {len(lines)} line(s): "
          f"{lines[0] if len(lines) == 1 else p.stderr.strip()[-300:]}")

# 2-4: a stand-in for mpmfsi. Its wall times are above 10 s with 8 digits, its coupling work
# (W_net) a known small number.
FAKE = r'''#!/usr/bin/python3
import json, os, sys, time
a = sys.argv[1:]
if a[:1] == ["--version"]:
    print("mpmfsi stand-in")
    sys.exit(0)
if a[:1] == ["check"]:
    print("[run]\n[solid.s]\n[gas.g]\n[probe.p]")
    sys.exit(0)
kv = dict(x.split("=", 1) for x in a[2:])
cfl = float(kv["time.cfl"])
os.makedirs(kv["output.dir"], exist_ok=True)
with open(os.path.join(kv["output.dir"], "probes.csv"), "w") as f:
    f.write("t,p_ux\n0,0\n1,%r\n" % (1e-3 * (1 + cfl * cfl)))
summary = {"steps": round(1 / cfl), "rhs_evals": round(1 / cfl), "coupling_work": -8.75e-07,
           "coupling_imbalance": 1e-16, "wall_s": float("%.6f" % (10 + time.time() % 1))}
with open(os.path.join(kv["output.dir"], "summary.json"), "w") as f:
    json.dump(summary, f)
'''
fake = os.path.join(work, "fake_mpmfsi")
with open(fake, "w") as f:
    f.write(FAKE)
os.chmod(fake, 0o755)
SWEEP = [PANEL, "--cfl", "0.4", "0.2"]
res = os.path.join(work, "results")
table = os.path.join(res, "runs.csv")
CUT = "velocity-monolithic-usl-0.2"


def sweep(*extra):
    p = ablate(SWEEP + list(extra), fake)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"ablate.py with the stand-in failed ({p.returncode})")
    return p.stdout


def rows():
    with open(table, newline="") as f:
        return {r["name"]: r for r in csv.DictReader(f)}


def table_line(name):
    with open(os.path.join(res, "ablation.md")) as f:
        return next((x for x in f if x.startswith(f"| {name} |")), "")


sweep()
with open(table, newline="") as f:
    text = f.read()
cut = text.index("-8.75e-07", text.index(CUT)) + len("-8.75e-0")
with open(table, "w", newline="") as f:
    f.write(text[:cut])  # W_net reads -8.75 now: 10^7 times the run's
report = sweep("--report-only")
line = table_line(CUT)
check(not line and f"({CUT}): a partial or damaged row" in report and "not tabulated" in report,
      f"runs.csv cut inside a row: --report-only leaves it out of the table "
      f"({line.strip() or 'no row'}; {report.splitlines()[0]})")
p = subprocess.run([sys.executable, ABLATE, "--replot", res], capture_output=True, text=True,
                   timeout=300)
check(p.returncode == 0 and "from 1 stable run(s)" in p.stdout and "not tabulated" in p.stdout,
      f"--replot draws the whole row only ({p.stdout.strip().splitlines()[-1]})")
resumed = sweep()
r = rows()[CUT]
check("run again" in resumed and f"] {CUT}: ok" in resumed and float(r["W_net"]) == -8.75e-07
      and "-8.75e-07 |" in table_line(CUT),
      f"a resumed sweep runs the cut row again (W_net {r['W_net']} J, as its run gave)")
# A row with a wrong figure (a whole line), a row whose run output is gone, and runs.csv a link
# to a file elsewhere (3), in one resumed sweep.
OTHER = "velocity-monolithic-usl-0.4"
target = os.path.join(work, "elsewhere.csv")
with open(table, newline="") as f:
    text = "".join(x.replace("-8.75e-07", "-8.75e-01") if x.startswith(CUT) else x
                   for x in f.read().splitlines(True))
with open(target, "w", newline="") as f:
    f.write(text)
os.remove(table)
os.symlink(target, table)
os.remove(os.path.join(work, "results_runs", OTHER, "summary.json"))
again = sweep()
check(f"({CUT}): a partial or damaged row (its figures differ" in again
      and f"({OTHER}): a partial or damaged row (its run's output" in again
      and f"] {CUT}: ok" in again and f"] {OTHER}: ok" in again
      and all(float(x["W_net"]) == -8.75e-07 for x in rows().values()),
      "a row whose figures differ from its run's summary.json, and one whose run output is gone, "
      "are run again")
with open(target, newline="") as f:
    kept = f.read()
check(kept == text and not os.path.islink(table) and len(rows()) == 2,
      "a link named runs.csv is replaced whole; its target is left alone")

# 4: --repeat 2 at wall times above 10 s.
twice = sweep("--repeat", "2")
exact = []
for name, r in rows().items():
    walls = [float(w) for w in r["walls"].split(";")]
    exact.append(len(walls) == 2 and float(r["wall_s"]) == statistics.median(walls)
                 and min(walls) > 10)
check("[round 2, 2/2]" in twice and len(exact) == 2 and all(exact),
      f"--repeat 2 at walls above 10 s: wall_s is the median of the walls held, to the last "
      f"digit ({'; '.join(r['walls'] + ' -> ' + r['wall_s'] for r in rows().values())})")
sys.exit(check.finish())
