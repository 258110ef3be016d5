"""The command line's conventions (app/main.c, app/cli_help.c): what a user types first.

1. --version and `version`: exit 0, stdout "mpmfsi X.Y.Z (git REV)" (REV: a hash, ", dirty"
   with uncommitted changes, or "unknown"), then SUNDIALS, HDF5 and MPI lines.
2. -h, --help and `help`: the usage on stdout, exit 0, "usage:" on the first line (so
   `mpmfsi --help | head` shows it); bare `mpmfsi` is a usage error: the usage on stderr, exit 2.
3. `help COMMAND` and `COMMAND --help` / `-h` print the same per-command help on stdout, exit 0,
   other than the general usage, with the command's arguments, exit codes and examples;
   `run --help` is help, not a case file named --help.
4. An unknown command, `help` of an unknown command and `run` without a case: exit 2, one line
   on stderr naming what was wrong.
5. `keys` lists grid.dx and the instance key probe.*.point; `keys grid` only [grid].
6. Under mpiexec with 2 ranks, help and version print once (rank 0 only).
Each command takes about a second to start MPI, so they run side by side.
"""
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_cli")
COMMANDS = ["run", "check", "restart", "keys", "version", "help"]


def call(args, ranks=1):
    cmd = [mt.BIN] + args
    if ranks > 1:
        cmd = [mt.MPIEXEC, "-n", str(ranks)] + cmd
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


jobs = {
    "--version": ["--version"], "version": ["version"],
    "--help": ["--help"], "-h": ["-h"], "help": ["help"], "bare": [],
    "frob": ["frob"], "help frob": ["help", "frob"], "run": ["run"], "restart": ["restart"],
    "run --help CASE": ["run", "--help", "no_such_case.ini"],
    "keys": ["keys"], "keys grid": ["keys", "grid"], "keys gird": ["keys", "gird"],
}
for c in COMMANDS:
    jobs[f"help {c}"] = ["help", c]
    jobs[f"{c} --help"] = [c, "--help"]
    jobs[f"{c} -h"] = [c, "-h"]
with ThreadPoolExecutor(max_workers=8) as pool:
    futures = {name: pool.submit(call, args) for name, args in jobs.items()}
    futures["mpi --help"] = pool.submit(call, ["--help"], 2)
    futures["mpi --version"] = pool.submit(call, ["--version"], 2)
    r = {name: f.result() for name, f in futures.items()}


def ok(name):
    """Exit 0 with output on stdout only."""
    p = r[name]
    check(p.returncode == 0 and p.stdout.strip() != "" and p.stderr.strip() == "",
          f"`mpmfsi {name}`: exit 0, stdout only (exit {p.returncode}, "
          f"{len(p.stdout)} chars stdout, stderr {p.stderr.strip()[:200]!r})")
    return p.stdout


def usage_error(name, *words):
    """Exit 2, one line on stderr naming each of words, nothing on stdout."""
    p = r[name]
    lines = p.stderr.strip().splitlines()
    check(p.returncode == 2 and len(lines) == 1 and p.stdout == ""
          and all(w in p.stderr for w in words),
          f"`mpmfsi {name}`: exit 2, one stderr line naming {', '.join(words)} "
          f"(exit {p.returncode}, stderr {p.stderr.strip()!r})")


# 1. version
v = ok("--version")
lines = v.splitlines()
check(bool(lines) and re.fullmatch(r"mpmfsi \d+\.\d+\.\d+ \(git ([0-9a-f]{7,40}(, dirty)?|unknown)\)",
                                   lines[0]) is not None,
      f"version line with the git revision: {lines[0] if lines else ''!r}")
for lib, pattern in (("SUNDIALS", r"SUNDIALS \d+\.\d+\.\d+"), ("HDF5", r"HDF5 \d+\.\d+\.\d+"),
                     ("MPI", r"MPI .+ \(MPI standard \d+\.\d+\)")):
    check(any(re.fullmatch(pattern, ln) for ln in lines), f"a {lib} line ({pattern})")
check(ok("version") == v, "`mpmfsi version` prints what --version prints")

# 2. usage
usage = ok("--help")
check(usage.startswith("usage:") and "usage:" in "".join(usage.splitlines(True)[:3]),
      "--help: the first line is the usage (so `| head` shows it)")
for c in COMMANDS:
    check(c in usage, f"the usage names the command {c}")
check(ok("-h") == usage and ok("help") == usage, "-h and help print what --help prints")
p = subprocess.run(f"'{mt.BIN}' --help | head -n 3", shell=True, capture_output=True, text=True,
                   timeout=60)
check(p.returncode == 0 and p.stdout.startswith("usage:"), "`mpmfsi --help | head -n 3` shows the usage")
b = r["bare"]
check(b.returncode == 2 and b.stdout == "" and b.stderr.startswith("usage:"),
      f"bare mpmfsi: the usage on stderr, exit 2 (exit {b.returncode})")

# 3. per-command help
for c in COMMANDS:
    text = ok(f"help {c}")
    check(text != usage and text.startswith(f"usage: mpmfsi {c}"),
          f"help {c}: its own synopsis, not the general usage")
    check("Exit status" in text and "Examples" in text, f"help {c}: exit status and examples")
    check(ok(f"{c} --help") == text and ok(f"{c} -h") == text,
          f"`{c} --help` and `{c} -h` print `help {c}`")
run_help = r["help run"].stdout
check(all(w in run_help for w in ("CASE", "key=value", "output.dir", "summary.json")),
      "help run names its arguments (CASE, key=value) and what it writes")
check("CHECKPOINT" in r["help restart"].stdout, "help restart names CHECKPOINT")
check("--markdown" in r["help keys"].stdout and "SECTION" in r["help keys"].stdout,
      "help keys names SECTION and --markdown")
rh = r["run --help CASE"]
check(rh.returncode == 0 and rh.stdout == run_help and "cannot" not in rh.stderr + rh.stdout,
      f"`run --help CASE` is help, no case is opened (exit {rh.returncode}, "
      f"stderr {rh.stderr.strip()[:200]!r})")

# 4. usage errors
usage_error("frob", "'frob'", "run", "keys")
usage_error("help frob", "'frob'", "run")
usage_error("run", "no case file", "mpmfsi help run")
usage_error("restart", "no checkpoint")
usage_error("keys gird", "'gird'", "grid")

# 5. keys
keys = ok("keys")
listed = [ln.split(" = ")[0] for ln in keys.splitlines() if ln and ln[0] not in " ["]
for k in ("grid.dx", "probe.*.point", "geometry.*.type", "solid.*.E", "coupling.scheme"):
    check(k in listed, f"keys lists {k}")
check(len(listed) == len(set(listed)) and len(listed) > 100, f"keys lists {len(listed)} keys once each")
grid = [ln.split(" = ")[0] for ln in ok("keys grid").splitlines() if ln and ln[0] not in " ["]
check(grid and all(k.startswith("grid.") for k in grid) and "grid.dx" in grid,
      f"keys grid lists only [grid]: {grid}")

# 6. rank 0 only
for name, word in (("mpi --help", "usage:"), ("mpi --version", "SUNDIALS")):
    p = r[name]
    check(p.returncode == 0 and p.stdout.count(word) == 1,
          f"`mpiexec -n 2 mpmfsi {name[4:]}` prints once (exit {p.returncode}, "
          f"{p.stdout.count(word)} times)")

sys.exit(check.finish())
