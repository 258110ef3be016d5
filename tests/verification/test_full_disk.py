"""A full disk never hangs a run (issue 54): on 1, 2 and 3 ranks (3 oversubscribed), a run whose
output folder fills up during a snapshot or checkpoint ends within a bounded time with exit 1
and one error line that names the file, says the disk is full and names the last complete
checkpoint; no half-written file is left under a final name; and that checkpoint restarts on
a disk with room.

The full disk is a small tmpfs in a private mount namespace (`unshare -m`) where this process
may mount one (root with CAP_SYS_ADMIN), and otherwise an LD_PRELOAD shim
(tests/tools/fulldisk_shim.c) that gives the output folder a budget of 4 KiB pages, shared by
the ranks, past which writes fail with ENOSPC: the test never skips. Before the fix, 2 ranks
hung in HDF5's close (rank 0 in MPI_File_close, rank 1 at HDF5's sync point) under both, and
3 ranks under the shim exited 0 with checkpoints Open MPI had silently not written. Last, the
watchdog (the last resort where blocks cannot be reserved) is shown to end such a hang.

`python3 test_full_disk.py SHIM [tmpfs|shim]` (SHIM: the shim library; the second argument
forces one kind of full disk)."""
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

import h5py

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

# A checkpoint every 1 s and snapshots about 32 kB each; a write reserves about 100 kB more
# while it runs, and series.xmf grows by about 4 kB a snapshot. On a tmpfs, with a snapshot
# every 0.1 s, the first checkpoint completes from about 700 kB and the second needs about
# 1070 kB: 880 kB sits in the middle of the window where the disk fills during a snapshot after
# the first checkpoint, about 170 kB from either side. (A snapshot every 0.5 s on 360 kB left
# a window 20 kB wide, which closed on another machine.) The shim counts its own pages and
# reservations: with a snapshot every 0.5 s, budgets from 700 kB to 1400 kB all fill during a
# snapshot after a checkpoint.
RUN = {"tmpfs": ["output.interval=0.1"], "shim": ["output.interval=0.5"]}
RUN = {k: v + ["output.checkpoint_interval=1", "time.t_end=10", "run.progress=false"]
       for k, v in RUN.items()}
SIZE = {"tmpfs": "880k", "shim": 880 * 1024}
TIMEOUT = 90  # a hang becomes a failure: the run itself takes a few seconds
WATCHDOG = "30"  # mpm_iowatch.h: the last resort, which this test must never need


def env(extra=None):
    e = dict(os.environ)
    e.update({"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
              "OMPI_MCA_rmaps_base_oversubscribe": "1",
              "OMPI_MCA_btl_vader_single_copy_mechanism": "none",
              "MPMFSI_IO_WATCHDOG": WATCHDOG})
    e.update(extra or {})
    return e


def command(ranks, out, args):
    cmd = [mt.BIN, "run", mt.case("axial_bar.ini"), f"output.dir={out}"] + args
    return ([mt.MPIEXEC, "-n", str(ranks)] + cmd) if ranks > 1 else cmd


def tmpfs_works(tmp):
    mnt = os.path.join(tmp, "probe")
    os.makedirs(mnt, exist_ok=True)
    p = subprocess.run(["unshare", "-m", "sh", "-c",
                        f"mount -t tmpfs -o size=64k tmpfs {shlex.quote(mnt)}"],
                       capture_output=True, text=True)
    return p.returncode == 0, (p.stderr or p.stdout).strip()


def run_tmpfs(ranks, work, args=RUN["tmpfs"], size=SIZE["tmpfs"]):
    """The run on a tmpfs of size; its output folder is copied to work/out afterwards (the
    mount vanishes with its namespace). (exit status, seconds, output)."""
    mnt = os.path.join(work, "mnt")
    os.makedirs(mnt)
    inner = shlex.join(command(ranks, os.path.join(mnt, "out"), args))
    m, w = shlex.quote(mnt), shlex.quote(work)
    script = (f"mount -t tmpfs -o size={size} tmpfs {m} || exit 99; "
              f"timeout -s KILL {TIMEOUT} {inner}; rc=$?; cp -a {m}/out {w}/out; exit $rc")
    t0 = time.time()
    p = subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True, text=True,
                       env=env())
    return p.returncode, time.time() - t0, p.stdout + p.stderr


def run_shim(ranks, work, shim, args=RUN["shim"]):
    """The run under the shim with a budget of SIZE bytes for work/out."""
    out = os.path.join(os.path.realpath(work), "out")
    os.makedirs(out)
    extra = {"LD_PRELOAD": shim, "MPMFSI_FULLDISK_DIR": out,
             "MPMFSI_FULLDISK_BYTES": str(SIZE["shim"]),
             "MPMFSI_FULLDISK_COUNTER": os.path.join(os.path.realpath(work), "pages"),
             # the sanitizer build: the shim is loaded before the sanitizer's runtime
             "ASAN_OPTIONS": os.environ.get("ASAN_OPTIONS", "") + ":verify_asan_link_order=0"}
    t0 = time.time()
    try:
        p = subprocess.run(command(ranks, out, args), capture_output=True, text=True,
                           env=env(extra), timeout=TIMEOUT)
        rc, text = p.returncode, p.stdout + p.stderr
    except subprocess.TimeoutExpired as e:
        rc, text = "timeout", str(e.stdout or "") + str(e.stderr or "")
    return rc, time.time() - t0, text


def check_run(check, kind, ranks, rc, seconds, text, out, what="snapshot"):
    errors = [l for l in text.splitlines() if l.startswith("error:")]
    line = errors[0] if errors else text[-500:]
    print(f"     {kind}, {ranks} rank(s): exit {rc} after {seconds:.1f} s: {line}")
    check(rc == 1 and seconds < TIMEOUT, f"{kind}, {ranks} rank(s): the run ends with exit 1 "
          f"within {TIMEOUT} s (exit {rc}, {seconds:.1f} s)")
    named = line.split("earlier checkpoints are intact: ")[-1].strip() if errors else ""
    check(len(errors) == 1 and "no space left on device" in line and "watchdog" not in line
          and f"cannot write the {what}" in line
          and named.endswith(".h5") and "HDF5-DIAG" not in text,
          f"{kind}, {ranks} rank(s): one error line, naming the {what}, the full disk and the "
          "last checkpoint in the output folder (no watchdog, no HDF5 trace)")
    # (the line names it in the folder the run wrote to: a tmpfs is copied out afterwards)
    intact = os.path.join(out, os.path.basename(named)) if named else ""
    check(os.path.basename(intact).startswith("checkpoint_") and os.path.isfile(intact),
          f"{kind}, {ranks} rank(s): the named checkpoint {os.path.basename(intact)} exists")
    left = sorted(f for f in os.listdir(out) if f.endswith(".tmp"))
    check(not left, f"{kind}, {ranks} rank(s): no half-written file left ({left})")
    try:
        listed = [p for _, p in mt.snapshots(out)]
        missing = [p for p in listed if not os.path.isfile(p)]
    except Exception as e:  # noqa: BLE001 - any failure to read the index is the finding
        listed, missing = [], [str(e)]
    check((listed or what != "snapshot") and not missing,
          f"{kind}, {ranks} rank(s): series.xmf lists {len(listed)} "
          f"snapshot(s), all present ({missing})")
    return intact


def check_restart(check, kind, ranks, intact, work):
    """Restart from the intact checkpoint on a disk with room (a copy in the build tree)."""
    if not intact or not os.path.isfile(intact):
        check(False, f"{kind}, {ranks} rank(s): no checkpoint to restart from")
        return
    roomy = os.path.join(work, "roomy")
    os.makedirs(roomy)
    ck = shutil.copy(intact, roomy)
    with h5py.File(ck, "r") as f:
        t = float(f.attrs["t"])
    cmd = [mt.BIN, "restart", ck, f"output.dir={os.path.join(roomy, 'out')}",
           f"time.t_end={t + 0.5}", "output.interval=0.5", "run.progress=false"]
    if ranks > 1:
        cmd = [mt.MPIEXEC, "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=env(), timeout=TIMEOUT)
    done = os.path.isfile(os.path.join(roomy, "out", "checkpoint_final.h5"))
    check(p.returncode == 0 and done, f"{kind}, {ranks} rank(s): the restart from "
          f"{os.path.basename(ck)} (t = {t:g}) on a disk with room runs to t = {t + 0.5:g} "
          f"(exit {p.returncode})"
          + ("" if p.returncode == 0 else ": " + (p.stdout + p.stderr)[-300:]))


def other_writers(check, kind, tmp, shim):
    """2 ranks, the other collective writers: a checkpoint (no snapshots), and a CSV file
    that rank 0 writes (no snapshots, no checkpoint until the end; tmpfs only: stdio's writes
    go past an LD_PRELOAD shim)."""
    work = os.path.join(tmp, f"{kind}_checkpoint_np2")
    os.makedirs(work)
    args = RUN[kind] + ["output.snapshots=false"]
    rc, seconds, text = (run_tmpfs(2, work, args, "480k") if kind == "tmpfs"
                         else run_shim(2, work, shim, args))
    out = os.path.join(work, "out")
    if os.path.isdir(out):
        intact = check_run(check, kind + " (checkpoints only)", 2, rc, seconds, text, out,
                           "checkpoint")
        check_restart(check, kind + " (checkpoints only)", 2, intact, work)
    else:
        check(False, f"{kind} (checkpoints only): no output folder (exit {rc}): {text[-300:]}")
    if kind != "tmpfs":
        print("     skip the CSV writer under the shim: stdio's writes go past LD_PRELOAD")
        return
    work = os.path.join(tmp, "tmpfs_csv_np2")
    os.makedirs(work)
    args = ["output.snapshots=false", "output.checkpoint_interval=100", "time.t_end=60",
            "run.progress=false"]
    rc, seconds, text = run_tmpfs(2, work, args, "40k")
    errors = [l for l in text.splitlines() if l.startswith("error:")]
    print(f"     tmpfs, CSV, 2 ranks: exit {rc} after {seconds:.1f} s: "
          f"{errors[0] if errors else text[-300:]}")
    check(rc == 1 and len(errors) == 1 and "cannot write the diagnostics" in errors[0]
          and "no space left on device" in errors[0] and "no checkpoint" in errors[0],
          f"tmpfs, diagnostics.csv, 2 ranks: exit 1 with one line naming the file and the full "
          f"disk ({seconds:.1f} s)")


def watchdog(check, tmp, shim):
    """The last resort (mpm_iowatch.h): a file system that cannot reserve blocks and fails a
    write although its free space looked sufficient (the shim without reservations, like a
    quota). 2 ranks then diverge inside HDF5's close; the watchdog must end the run."""
    work = os.path.join(tmp, "watchdog_np2")
    os.makedirs(work)
    out = os.path.join(os.path.realpath(work), "out")
    os.makedirs(out)
    extra = {"LD_PRELOAD": shim, "MPMFSI_FULLDISK_DIR": out, "MPMFSI_FULLDISK_NO_RESERVE": "1",
             "MPMFSI_FULLDISK_BYTES": str(SIZE["shim"]),
             "MPMFSI_FULLDISK_COUNTER": os.path.join(os.path.realpath(work), "pages"),
             "MPMFSI_IO_WATCHDOG": "5",
             "ASAN_OPTIONS": os.environ.get("ASAN_OPTIONS", "") + ":verify_asan_link_order=0"}
    t0 = time.time()
    try:
        p = subprocess.run(command(2, out, RUN["shim"]), capture_output=True, text=True, env=env(extra),
                           timeout=TIMEOUT)
        rc, text = p.returncode, p.stdout + p.stderr
    except subprocess.TimeoutExpired:
        rc, text = "timeout", ""
    seconds = time.time() - t0
    errors = [l for l in text.splitlines() if l.startswith("error:")]
    print(f"     no reservation, 2 ranks: exit {rc} after {seconds:.1f} s: "
          f"{errors[0] if errors else text[-300:]}")
    check(rc == 1 and len(errors) == 1 and "earlier checkpoints are intact" in errors[0],
          f"no reservation, 2 ranks: the run ends with exit 1 and one error line within "
          f"{TIMEOUT} s ({seconds:.1f} s; watchdog 5 s)")


def main():
    shim = os.path.abspath(sys.argv[1])
    check = mt.Checks("full disk")
    tmp = tempfile.mkdtemp(prefix="fulldisk_", dir=".")
    ok, why = tmpfs_works(tmp)
    kind = sys.argv[2] if len(sys.argv) > 2 else ("tmpfs" if ok else "shim")
    if kind == "tmpfs" and not ok:
        raise SystemExit(f"cannot mount a tmpfs here: {why}")
    print(f"     full disk: {kind}" + ("" if ok else f" (no tmpfs: {why})"))
    for ranks in (1, 2, 3):
        work = os.path.join(tmp, f"{kind}_np{ranks}")
        os.makedirs(work)
        rc, seconds, text = (run_tmpfs(ranks, work) if kind == "tmpfs"
                             else run_shim(ranks, work, shim))
        out = os.path.join(work, "out")
        if not os.path.isdir(out):
            check(False, f"{kind}, {ranks} rank(s): no output folder (exit {rc}): {text[-300:]}")
            continue
        intact = check_run(check, kind, ranks, rc, seconds, text, out)
        check_restart(check, kind, ranks, intact, work)
    other_writers(check, kind, tmp, shim)
    watchdog(check, tmp, shim)
    return check.finish()


if __name__ == "__main__":
    sys.exit(main())
