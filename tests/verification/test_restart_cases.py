"""Every case in cases/ restarts: each is run for a few steps with a checkpoint halfway, the
checkpoint is restarted to the same end, and the two final states are compared by particle id,
phase by phase, field by field.

Tolerance 0 (bitwise): at every checkpoint the running simulation restarts its integrator from
the checkpointed state with the stored next step, exactly as `mpmfsi restart` does, so both
runs do the same arithmetic in the same order (see test_restart.py).

The length of each run: 6 times the stable step of the starting state, which `mpmfsi check`
reports, so every case costs a handful of steps whatever its own t_end. Snapshots are off except the last, which is what is compared.

`python3 test_restart_cases.py [NAME ...]` restarts only the named cases."""
import glob
import os
import re
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_restart_cases")
COMMON = ["run.progress=false", "run.log_level=warn"]


def first_step(path):
    """The stable step of the case's starting state, as `mpmfsi check` estimates it."""
    p = mt.run(["check", path, "run.log_level=info"])
    m = re.search(r"starting stable step ([0-9.eE+-]+) s", p.stderr)
    if not m:
        raise SystemExit(f"{path}: check gives no step estimate:\n{p.stderr}")
    return float(m.group(1))


def final_state(out):
    """{phase: particles()} of the last snapshot of a run."""
    path = mt.snapshots(out)[-1][1]
    with h5py.File(path, "r") as f:
        phases = [k for k in f if isinstance(f[k], h5py.Group) and "id" in f[k]]
    return {ph: mt.particles(path, ph) for ph in phases}


def restart_case(path):
    name = os.path.splitext(os.path.basename(path))[0]
    h = first_step(path)
    T = 6 * h
    common = [f"time.t_end={T!r}", f"output.interval={T!r}"] + COMMON
    full, rest = mt.outdir(f"{name}_full"), mt.outdir(f"{name}_restarted")
    mt.run(["run", path, f"output.dir={full}", f"output.checkpoint_interval={T / 2!r}"] + common)
    ckpt = os.path.join(full, "checkpoint_000001.h5")
    p = mt.run(["restart", ckpt, f"output.dir={rest}"] + common, check=False)
    if p.returncode != 0:
        check(False, f"{name}: restart failed ({p.returncode}): {p.stderr.strip()[-300:]}")
        return
    a, b = final_state(full), final_state(rest)
    same_phases = sorted(a) == sorted(b)
    worst, detail = 0.0, []
    for ph in sorted(a):
        if ph not in b or not np.array_equal(a[ph]["id"], b[ph]["id"]):
            worst = float("inf")
            detail.append(f"{ph}: ids differ")
            continue
        w, _ = mt.worst_difference(a[ph], b[ph])
        worst = max(worst, w)
        detail.append(f"{ph} {len(a[ph]['id'])} particles")
    check(same_phases and worst == 0.0,
          f"{name}: restarted at t = {T / 2:.3g} s and run to {T:.3g} s, final state "
          f"{'bitwise identical' if worst == 0 else f'differs by {worst:.2e}'} to the straight run "
          f"({', '.join(detail)})")


cases = sorted(glob.glob(os.path.join(mt.SOURCE, "cases", "*.ini")))
if len(sys.argv) > 1:
    cases = [c for c in cases if os.path.splitext(os.path.basename(c))[0] in sys.argv[1:]]
check(len(cases) > 0, f"{len(cases)} cases to restart")
for c in cases:
    restart_case(c)
sys.exit(check.finish())
