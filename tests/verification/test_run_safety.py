"""Run safety: an output folder belongs to one run, restarts never mix or silently change
results, absurd runs are refused before they start, a batch run shows progress, SIGTERM and
SIGINT end a run with a checkpoint that restarts, and any rank count that can split the grid
runs it. Each part is a class of failure the issue tracker found (issue 13); every check here
failed on the code before the fix.

1. A second run into a folder that holds a run's results is refused (exit 2) and leaves them
   byte for byte; output.overwrite=true deletes them first (files that are not mpmfsi's stay).
2. Two runs started at once into one folder: the second is refused at once (the lock).
3. Restart of an earlier checkpoint continues in a new folder beside the old one (named after
   the checkpoint), which stays byte for byte; a second such restart is refused; naming the
   old folder as output.dir is refused while later results exist; a named new folder works;
   a copy of a checkpoint in another folder continues there; output.truncate=true cuts the old run back consistently
   (no later snapshot, checkpoint or CSV row is left, the index lists exactly the files) and
   ends bitwise where the straight run ended (usl: no step history; tolerance 0).
4. Restart overrides that cannot be honoured (a density, a new section) are refused, naming
   the keys that may change; an override equal to the stored value and time.t_end are fine.
   A FIFO, a device or a folder given as the checkpoint is refused at once (a FIFO hung).
5. Runaway settings (10^300 s, a snapshot every 1e-9 s) are refused by check and run with the
   estimate and the key; raising the limit key accepts them.
6. With stderr not a terminal, progress lines appear every run.progress_interval seconds.
7. SIGTERM (1 rank, usl) ends the run with exit 3 and a final checkpoint; restarting it ends
   bitwise where the uninterrupted run does (tolerance 0, as 3). SIGINT on 2 ranks too.
8. cases/sod.ini (400 x 3 cells, periodic in y) runs on 4 ranks: the layout puts every rank
   along x instead of failing; where no layout fits, the message names the most ranks that do
   and their layout; a grid too large to index says so (not "not a whole number").
9. An allocation failure (address space capped at 1.5 GB) gives one line that says what to
   change and names no internal variable (skipped under AddressSanitizer, which cannot run
   with a capped address space)."""
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_run_safety")
SOD = mt.case("sod.ini")
QUIET = ["run.progress=false"]
SHORT = ["time.t_end=0.02", "output.interval=0.005"] + QUIET


def listing(d):
    """{name: (size, mtime_ns, bytes)} of the files in d (the lock excluded)."""
    out = {}
    for n in sorted(os.listdir(d)):
        p = os.path.join(d, n)
        if n != ".lock" and os.path.isfile(p):
            with open(p, "rb") as f:
                out[n] = (os.path.getsize(p), os.stat(p).st_mtime_ns, f.read())
    return out


def errors(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def one_error(p, *words):
    e = errors(p)
    return p.returncode == 2 and len(e) == 1 and all(w in e[0] for w in words)


def final(out, phase="fluid"):
    return mt.particles(mt.snapshots(out)[-1][1], phase)


def bitwise(a, b):
    return np.array_equal(a["id"], b["id"]) and mt.worst_difference(a, b)[0] == 0.0


def index_consistent(out):
    """Snapshot times strictly increasing, every listed file present, no snap file unlisted;
    diagnostics times strictly increasing."""
    snaps = mt.snapshots(out)
    times = [t for t, _ in snaps]
    listed = {os.path.basename(p) for _, p in snaps}
    on_disk = {n for n in os.listdir(out) if re.fullmatch(r"snap_\d+\.h5", n)}
    rows = np.loadtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", skiprows=1, ndmin=2)
    return (all(a < b for a, b in zip(times, times[1:])) and listed == on_disk
            and bool(np.all(np.diff(rows[:, 0]) > 0))), times, rows[-1, 0]


# ---- 1. one folder, one run --------------------------------------------------------------
a = mt.outdir("owned")
mt.run(["run", SOD, f"output.dir={a}"] + SHORT)
before = listing(a)
p = mt.run(["run", SOD, f"output.dir={a}"] + SHORT, check=False)
check(one_error(p, "already holds the results of another run", "output.overwrite=true")
      and listing(a) == before,
      f"second run into a used folder: exit {p.returncode}, {errors(p)[:1]}; the first run's "
      f"{len(before)} files unchanged")
with open(os.path.join(a, "notes.txt"), "w") as f:
    f.write("the user's own file\n")
open(os.path.join(a, "snap_000077.h5"), "w").close()  # a stray result of an older run
p = mt.run(["run", SOD, f"output.dir={a}", "output.overwrite=true", "time.t_end=0.01"]
           + SHORT[1:], check=False)
ok, times, t_last = index_consistent(a)
check(p.returncode == 0 and ok and not os.path.exists(os.path.join(a, "snap_000077.h5"))
      and os.path.exists(os.path.join(a, "notes.txt")) and abs(t_last - 0.01) < 1e-12,
      f"output.overwrite=true: the earlier run's files deleted (stray snap_000077.h5 too), "
      f"notes.txt kept, the new run alone in the index (times {times})")

u = mt.outdir("user_files")
for name, text in (("analysis.csv", "a,b\n1,2\n"), ("notes.tmp", "draft\n"), ("plot.png", "")):
    with open(os.path.join(u, name), "w") as f:
        f.write(text)
p = mt.run(["run", SOD, f"output.dir={u}", "output.overwrite=true"] + SHORT, check=False)
kept = all(os.path.exists(os.path.join(u, n)) for n in ("analysis.csv", "notes.tmp", "plot.png"))
check(p.returncode == 0 and kept,
      "a folder holding only the user's files (analysis.csv, notes.tmp, plot.png) is no run's: "
      "the run goes ahead, even with overwrite, and leaves them")

# ---- 2. the lock -------------------------------------------------------------------------
b = mt.outdir("locked")
first = subprocess.Popen([mt.BIN, "run", SOD, f"output.dir={b}", "time.t_end=0.2"] + QUIET,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
while not os.path.exists(os.path.join(b, "diagnostics.csv")) and first.poll() is None:
    time.sleep(0.02)
t0 = time.time()
p = mt.run(["run", SOD, f"output.dir={b}", "output.overwrite=true"] + SHORT, check=False)
waited = time.time() - t0
out1, err1 = first.communicate(timeout=300)
check(one_error(p, "in use by another mpmfsi run", "pid") and first.returncode == 0
      and index_consistent(b)[0] and index_consistent(b)[2] == 0.2,
      f"concurrent run into the same folder, even with overwrite: refused after {waited:.1f} s "
      f"({errors(p)[:1]}); the first run completed to t = 0.2 with a consistent index")

# ---- 3. restarts and folders -------------------------------------------------------------
USL = ["time.method=usl", "time.t_end=0.04", "output.interval=0.005",
       "output.checkpoint_interval=0.01"] + QUIET
full = mt.outdir("straight")
mt.run(["run", SOD, f"output.dir={full}"] + USL)
ck1 = os.path.join(full, "checkpoint_000001.h5")
before = listing(full)
p = mt.run(["restart", ck1] + QUIET, check=False)
branch = full + "-from-checkpoint_000001"
check(p.returncode == 0 and listing(full) == before and os.path.isdir(branch)
      and bitwise(final(full), final(branch)) and f"continuing in {branch}" in p.stderr,
      f"restart of an earlier checkpoint: continues in {os.path.basename(branch)}, ends bitwise "
      f"where the straight run ends, the original folder byte for byte")
p = mt.run(["restart", ck1] + QUIET, check=False)
check(one_error(p, "already holds the results of another run") and listing(full) == before,
      f"the same restart again: refused, its first result kept: {errors(p)[:1]}")
p = mt.run(["restart", ck1, f"output.dir={full}"] + QUIET, check=False)
check(one_error(p, "later than the checkpoint", "output.dir=", "output.truncate=true")
      and listing(full) == before,
      f"restart of an earlier checkpoint into its own folder, named: refused: {errors(p)[:1]}; "
      f"folder unchanged")
new = mt.outdir("continued")
p = mt.run(["restart", ck1, f"output.dir={new}"] + QUIET, check=False)
check(p.returncode == 0 and listing(full) == before and bitwise(final(full), final(new)),
      "restart into a named new folder: runs, ends bitwise where the straight run ends, and "
      "leaves the original folder byte for byte")
copy_dir = mt.outdir("copy")
shutil.copy(ck1, copy_dir)
p = mt.run(["restart", os.path.join(copy_dir, "checkpoint_000001.h5")] + QUIET, check=False)
check(p.returncode == 0 and listing(full) == before
      and os.path.exists(os.path.join(copy_dir, "series.xmf")),
      "a checkpoint copied into another folder continues there; the original folder unchanged")
cut = mt.outdir("cut")
shutil.rmtree(cut)
shutil.copytree(full, cut)
ref = final(full)
p = mt.run(["restart", os.path.join(cut, "checkpoint_000001.h5"), "output.truncate=true",
            "time.t_end=0.02"] + QUIET, check=False)
ok, times, t_last = index_consistent(cut)
later_ck = [n for n in os.listdir(cut) if n.startswith("checkpoint_0") and n != "checkpoint_000001.h5"]
check(p.returncode == 0 and ok and max(times) <= 0.02 + 1e-15 and abs(t_last - 0.02) < 1e-15
      and later_ck == [] and "deleted" in p.stderr,
      f"output.truncate=true cut the run back to t = 0.01 and ran to 0.02: index {times}, "
      f"diagnostics end at {t_last}, later checkpoints left {later_ck}")
p = mt.run(["restart", os.path.join(cut, "checkpoint_final.h5"), "time.t_end=0.04"] + QUIET,
           check=False)
ok, times, t_last = index_consistent(cut)
check(p.returncode == 0 and ok and bitwise(final(cut), ref),
      f"... and continued in place from its final checkpoint to 0.04: ends bitwise where the "
      f"straight run ends; index {len(times)} snapshots, consistent")

# Overwrite is an intent of one command, not inherited by restarts of its checkpoints.
o1, o2 = mt.outdir("overwriting"), mt.outdir("someone_else")
mt.run(["run", SOD, f"output.dir={o1}", "output.overwrite=true"] + SHORT)
mt.run(["run", SOD, f"output.dir={o2}"] + SHORT)
before2 = listing(o2)
p = mt.run(["restart", os.path.join(o1, "checkpoint_final.h5"), f"output.dir={o2}",
            "time.t_end=0.03"] + QUIET, check=False)
check(one_error(p, "already holds the results of another run") and listing(o2) == before2,
      "a restart of a checkpoint written with output.overwrite=true does not overwrite: refused")
# A restart in place with another checkpoint interval numbers its checkpoints after the last.
c = mt.outdir("renumber")
mt.run(["run", SOD, f"output.dir={c}", "time.t_end=0.01", "output.checkpoint_interval=0.004"]
       + QUIET)
old2 = listing(c)["checkpoint_000002.h5"][2]
p = mt.run(["restart", os.path.join(c, "checkpoint_final.h5"), "time.t_end=0.03",
            "output.checkpoint_interval=0.01"] + QUIET, check=False)
check(p.returncode == 0 and listing(c)["checkpoint_000002.h5"][2] == old2
      and os.path.exists(os.path.join(c, "checkpoint_000003.h5")),
      "restart in place with a new checkpoint interval: checkpoint_000002.h5 (t = 0.008) kept, "
      "the next one is checkpoint_000003.h5")
# A checkpoint reached through a link: its real folder decides; it is never deleted.
link = os.path.join(mt.outdir("link"), "ck.h5")
os.symlink(os.path.abspath(os.path.join(c, "checkpoint_final.h5")), link)
p = mt.run(["restart", link, f"output.dir={c}", "output.overwrite=true", "time.t_end=0.04"]
           + QUIET, check=False)
check(p.returncode == 0 and os.path.exists(os.path.join(c, "checkpoint_000002.h5")),
      "restart through a symbolic link into the checkpoint's real folder continues that run "
      "(nothing deleted, although overwrite was given)")

# ---- 4. restart overrides ----------------------------------------------------------------
o = mt.outdir("overrides")
p = mt.run(["restart", ck1, f"output.dir={o}", "gas.left.density=2"] + QUIET, check=False)
check(one_error(p, "gas.left.density", "cannot change on restart", "time.*, output.*, run.*"),
      f"restart with a new density: {errors(p)[:1]}")
p = mt.run(["restart", ck1, f"output.dir={o}", "gas.left.density=1", "time.t_end=0.02"] + QUIET,
           check=False)
check(p.returncode == 0, f"restart with the stored density and a new t_end: exit {p.returncode}")
o = mt.outdir("overrides_section")
p = mt.run(["restart", ck1, f"output.dir={o}", "probe.tip.point=0.5 0.004"] + QUIET, check=False)
check(p.returncode == 2 and any("probe.tip" in e for e in errors(p)),
      f"restart with a new [probe] section refused: {errors(p)[:1]}")

fifo = os.path.join(mt.outdir("fifo"), "checkpoint.h5")
os.mkfifo(fifo)
for label, path in (("a FIFO", fifo), ("a device", "/dev/zero"), ("a folder", full)):
    try:
        p = subprocess.run([mt.BIN, "restart", path], capture_output=True, text=True, timeout=60)
        ok, what = one_error(p, "not a regular file"), errors(p)[:1]
    except subprocess.TimeoutExpired:
        ok, what = False, "no answer in 60 s"
    check(ok, f"restart from {label} refused at once: {what}")

# ---- 5. runaway runs ---------------------------------------------------------------------
for words, args in ((("steps", "run.max_steps"), ["time.t_end=1e300"]),
                    (("snapshots", "output.max_files"), ["output.interval=1e-9"])):
    for cmd in ("check", "run"):
        o = mt.outdir("runaway")
        p = mt.run([cmd, SOD, f"output.dir={o}"] + args + QUIET, check=False)
        check(one_error(p, "this run would", *words) and not os.listdir(o),
              f"{cmd} {args[0]}: refused before starting: {errors(p)[:1]}")
p = mt.run(["check", SOD, "time.t_end=1e300", "run.max_steps=1e305", "output.max_files=1e305",
            "output.max_gb=1e305"], check=False)
check(p.returncode == 0, "check with run.max_steps, output.max_files and output.max_gb raised "
      "accepts it")

# ---- 6. progress without a terminal ------------------------------------------------------
o = mt.outdir("progress")
p = mt.run(["run", SOD, f"output.dir={o}", "time.t_end=0.2", "run.progress_interval=0.1"])
n = len(re.findall(r"^(?:info: )?progress: step \d+, t = ", p.stderr, re.M))
check(n >= 2, f"stderr not a terminal: {n} progress lines at 0.1 s intervals")


# ---- 7. signals --------------------------------------------------------------------------
def interrupt(ranks, sig, name):
    o = mt.outdir(name)
    cmd = [mt.BIN, "run", SOD, f"output.dir={o}", "time.method=usl", "time.t_end=0.2"] + QUIET
    if ranks > 1:
        cmd = [mt.MPIEXEC, "-n", str(ranks)] + cmd
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    diag = os.path.join(o, "diagnostics.csv")
    while proc.poll() is None:
        if os.path.exists(diag) and os.path.getsize(diag) > 20000:
            break
        time.sleep(0.01)
    if ranks > 1:  # as a batch scheduler does: every task gets the signal
        subprocess.run(["pkill", f"-{sig.name[3:]}", "-f", f"output.dir={o}"], check=False)
    else:
        proc.send_signal(sig)
    out, err = proc.communicate(timeout=300)
    return o, proc.returncode, err


for ranks, sig in ((1, signal.SIGTERM), (2, signal.SIGINT)):
    straight = mt.outdir(f"uninterrupted_{ranks}")
    mt.run(["run", SOD, f"output.dir={straight}", "time.method=usl", "time.t_end=0.2"] + QUIET,
           ranks)
    o, rc, err = interrupt(ranks, sig, f"signal_{ranks}")
    ck = os.path.join(o, "checkpoint_final.h5")
    m = re.search(r"stopped by (\w+) at t = ([0-9.e+-]+)", err)
    expect_rc = 3 if ranks == 1 else None  # mpiexec reports its own status
    check(m is not None and m.group(1) == sig.name and float(m.group(2)) < 0.2
          and os.path.exists(ck) and (expect_rc is None or rc == expect_rc),
          f"{sig.name} on {ranks} rank(s): exit {rc}, "
          f"{m.group(0) if m else err.strip()[-200:]}, final checkpoint written")
    p = mt.run(["restart", ck] + QUIET, ranks, check=False)
    ok, times, _ = index_consistent(o)
    check(p.returncode == 0 and ok and bitwise(final(o), final(straight)),
          f"... restarted in place to t = 0.2: ends bitwise where the uninterrupted {ranks}-rank run does")

# ---- 8. rank layout and grid size --------------------------------------------------------
o = mt.outdir("four_ranks")
p = mt.run(["run", SOD, f"output.dir={o}", "time.t_end=0.01"] + QUIET, 4, check=False)
check(p.returncode == 0 and "4 ranks (4 x 1)" in p.stderr,
      f"sod on 4 ranks: exit {p.returncode}, layout "
      f"{re.search(r'[0-9]+ ranks [(][^)]*[)]', p.stderr).group(0) if p.returncode == 0 else errors(p)[:1]}")
p = mt.run(["check", SOD, "grid.dx=0.1", "domain.hi=1 0.3"], 5, check=False)
check(p.returncode == 2 and "run on at most 3 ranks (grid.ranks = 3 1)" in p.stderr,
      f"10 x 3 cells on 5 ranks (no layout fits): the message names the layout to use: "
      f"{[l for l in p.stderr.splitlines() if l.startswith('error:')][:1]}")
p = mt.run(["check", SOD, "grid.dx=1e-12"], check=False)
check(one_error(p, "grid.dx", "more than", "can index") and "whole number" not in p.stderr,
      f"a grid too large to index: {errors(p)[:1]}")

# ---- 9. out of memory --------------------------------------------------------------------
with open(mt.BIN, "rb") as f:
    asan = b"__asan_init" in f.read()
if asan:
    print("skip out-of-memory message: an AddressSanitizer build cannot run with a capped "
          "address space")
else:
    import resource

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (1536 << 20, 1536 << 20))

    o = mt.outdir("oom")
    p = subprocess.run([mt.BIN, "run", SOD, f"output.dir={o}", "grid.dx=5e-5"] + QUIET,
                       capture_output=True, text=True, preexec_fn=cap, timeout=300)
    e = errors(p)
    check(p.returncode in (1, 2) and len(e) == 1 and "out of memory" in e[0]
          and "grid.dx" in e[0] and not re.search(r"for [a-z_>-]+\b", e[0]),
          f"allocation failure: exit {p.returncode}, {e[:1] or p.stderr.strip()[-200:]}")

sys.exit(check.finish())
