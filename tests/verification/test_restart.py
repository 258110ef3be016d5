"""Restart: a run to T that checkpoints at T/2, and a run restarted from that checkpoint
and continued to T, end in bitwise identical states (compared by particle id).

Why bitwise: at every checkpoint the running simulation restarts its integrator from the
checkpointed state with the stored next step, exactly as `mpmfsi restart` does, and the
checkpoint keeps each rank's particles in order. For information the test also prints how
far a run without the intermediate checkpoint drifts (the integrator's step history differs,
so agreement there is to the error tolerance, not bitwise). Run on 1 and 2 ranks.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_restart")


case = mt.case("two_disks.ini")
T = 0.6
common = [f"time.t_end={T}", "output.interval=0.1", "run.progress=false", "grid.dx=0.04"]
for ranks in (1, 2):
    for method in ("usl", "musl", "bs32"):
        full, rest, plain = (mt.outdir(f"{x}_{method}_np{ranks}")
                             for x in ("full", "restarted", "plain"))
        mt.run(["run", case, f"output.dir={full}", f"time.method={method}",
                f"output.checkpoint_interval={T / 2}"] + common, ranks)
        ckpt = os.path.join(full, "checkpoint_000001.h5")
        check(os.path.exists(ckpt), f"{method} np{ranks}: checkpoint at T/2 written")
        mt.run(["restart", ckpt, f"output.dir={rest}"], ranks)
        a = mt.particles(mt.snapshots(full)[-1][1])
        b = mt.particles(mt.snapshots(rest)[-1][1])
        check(abs(a["time"] - T) < 1e-12 and abs(b["time"] - T) < 1e-12,
              f"{method} np{ranks}: both runs end at T = {T}")
        same = np.array_equal(a["id"], b["id"]) and all(
            np.array_equal(a[k], b[k]) for k in ("x", "v", "F"))
        check(same, f"{method} np{ranks}: restarted run is bitwise identical to the full run")
        mt.run(["run", case, f"output.dir={plain}", f"time.method={method}"] + common, ranks)
        c = mt.particles(mt.snapshots(plain)[-1][1])
        drift = float(np.abs(a["x"] - c["x"]).max())
        if method in ("usl", "musl"):
            # The classic update has no step history, so an integrator restart must not change
            # it: any difference beyond roundoff means a stage used a stale step size.
            check(drift <= 1e-12, f"{method} np{ranks}: run without the T/2 restart differs by "
                  f"{drift:.3e} m (tolerance 1e-12)")
        else:
            print(f"info {method} np{ranks}: run without the T/2 restart differs by "
                  f"{drift:.3e} m in x (step-size history differs; within rtol)")

sys.exit(check.finish())
