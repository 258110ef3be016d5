"""Messages and counts across a restart and a signal (issue 54, item 7).

1. time.method switches on restart (cases/sod.ini, the gas, whose particle fields differ
   between the classic updates and the ERK pairs): usl -> bs32 and bs32 -> usl both restart
   and reach t_end (before: refused with a field-layout message that never named
   time.method), and the switched run's density lies within the usl/bs32 difference of both
   straight runs (relative L1 by particle id).
2. rhs_evals in diagnostics.csv continues across a restart (usl: one evaluation a step, so the
   restarted run's last row equals the uninterrupted run's); a checkpoint without the stored
   count (an older one: the attribute deleted) continues from its step count.
3. SIGHUP stops a run as SIGTERM does: exit 3, "stopped by SIGHUP", checkpoint_final.h5
   written and restartable (before: the default action killed the run, exit -1, no
   checkpoint).
"""
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_messages_run")
QUIET = ["run.progress=off"]
SOD = mt.case("sod.ini")


def last_state(o):
    with h5py.File(mt.snapshots(o)[-1][1]) as f:
        i = np.argsort(f["fluid/id"][:])
        return f["fluid/id"][:][i], f["fluid/rho"][:, 0][i]


def diag(o):
    return np.genfromtxt(os.path.join(o, "diagnostics.csv"), delimiter=",", names=True)


def l1(a, b):
    return float(np.abs(a - b).mean() / np.abs(b).mean())


# ---- 1. time.method switches on restart -------------------------------------------------------
straight = {}
for m in ("usl", "bs32"):
    straight[m] = mt.outdir(f"sod_{m}")
    mt.run(["run", SOD, f"output.dir={straight[m]}", f"time.method={m}", "time.t_end=0.1"] + QUIET)
spread = l1(last_state(straight["usl"])[1], last_state(straight["bs32"])[1])
for a, b in (("usl", "bs32"), ("bs32", "usl")):
    o = mt.outdir(f"switch_{a}_{b}")
    mt.run(["run", SOD, f"output.dir={o}", f"time.method={a}", "time.t_end=0.05"] + QUIET)
    p = mt.run(["restart", os.path.join(o, "checkpoint_final.h5"), "time.t_end=0.1",
                f"time.method={b}"] + QUIET, check=False)
    err = [l for l in p.stderr.splitlines() if l.startswith("error:")]
    ok = p.returncode == 0
    ids, rho = last_state(o) if ok else (None, None)
    ids_b, rho_b = last_state(straight[b])
    d_b = l1(rho, rho_b) if ok and np.array_equal(ids, ids_b) else float("inf")
    d_a = l1(rho, last_state(straight[a])[1]) if ok else float("inf")
    check(ok and d_b <= spread and d_a <= 1.5 * spread,
          f"restart switching time.method {a} -> {b}: exit {p.returncode}"
          f"{' ' + err[0][:200] if err else ''}; density vs straight {b} {d_b:.2e}, vs straight "
          f"{a} {d_a:.2e} (the two straight runs differ by {spread:.2e})")

# ---- 2. rhs_evals continues -------------------------------------------------------------------
B = mt.case("ballistic2d.ini")
U = ["time.method=usl", "time.t_end=0.2"] + QUIET
full = mt.outdir("rhs_full")
mt.run(["run", B, f"output.dir={full}"] + U)
whole = diag(full)
for old in (False, True):
    o = mt.outdir("rhs_restart_old" if old else "rhs_restart")
    mt.run(["run", B, f"output.dir={o}", "time.t_end=0.1"] + U[:1] + QUIET)
    ck = os.path.join(o, "checkpoint_final.h5")
    with h5py.File(ck, "a") as f:
        stored = f.attrs.get("rhs_evals")
        if old and stored is not None:
            del f.attrs["rhs_evals"]
    mt.run(["restart", ck, "time.t_end=0.2"] + QUIET)
    d = diag(o)
    k = int(np.argmax(d["t"] > 0.1 + 1e-12))  # the first row after the restart
    steps_then = d["step"][k - 1]
    want = steps_then if old else d["rhs_evals"][k - 1]
    check(d["rhs_evals"][k] == want + 1 and d["rhs_evals"][-1] == whole["rhs_evals"][-1]
          and (old or stored is not None),
          f"{'a checkpoint without rhs_evals (from its step count ' + str(int(steps_then)) + ')' if old else 'rhs_evals stored (' + str(stored) + ')'}: "
          f"rows at the restart {int(d['rhs_evals'][k - 1])} -> {int(d['rhs_evals'][k])}, last "
          f"{int(d['rhs_evals'][-1])} (uninterrupted run: {int(whole['rhs_evals'][-1])})")

# ---- 3. SIGHUP acts as SIGTERM ----------------------------------------------------------------
o = mt.outdir("sighup")
cmd = [mt.BIN, "run", SOD, f"output.dir={o}", "time.method=usl", "time.t_end=0.2"] + QUIET
proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                        restore_signals=True)
dpath = os.path.join(o, "diagnostics.csv")
while proc.poll() is None and not (os.path.exists(dpath) and os.path.getsize(dpath) > 20000):
    time.sleep(0.01)
proc.send_signal(signal.SIGHUP)
out, err = proc.communicate(timeout=300)
ck = os.path.join(o, "checkpoint_final.h5")
stopped = [l for l in err.splitlines() if "stopped by" in l]
check(proc.returncode == 3 and stopped and "stopped by SIGHUP" in stopped[0] and os.path.exists(ck),
      f"SIGHUP: exit {proc.returncode}, {stopped[0][:120] if stopped else err.strip()[-200:]}, "
      f"checkpoint_final.h5 {'written' if os.path.exists(ck) else 'missing'}")
p = mt.run(["restart", ck] + QUIET, check=False) if os.path.exists(ck) else None
check(p is not None and p.returncode == 0, f"... and the run restarts from it to t = 0.2: exit "
      f"{p.returncode if p else None}")

sys.exit(check.finish())
