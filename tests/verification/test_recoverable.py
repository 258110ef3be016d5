"""A run that cannot continue stops with one message naming the particle, its position and
the cause, exits non-zero, and leaves the output already written readable.

The ballistic block is thrown at the right wall; once a particle would leave the domain the
RHS reports a recoverable error, the integrator retries with smaller steps (time.max_retries
times), then the run stops. The snapshots written before must still open with h5py and be
listed in a well-formed series.xmf.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_recoverable")


for ranks, method in ((1, "bs32"), (2, "bs32"), (1, "usl"), (2, "usl")):
    out = mt.outdir(f"wall_{method}_np{ranks}")
    p = mt.run(["run", mt.case("ballistic2d.ini"), f"output.dir={out}", "run.progress=false",
                "solid.block.velocity=40 0", "time.t_end=0.2", "output.interval=0.02",
                f"time.method={method}"], ranks=ranks, check=False)
    errors = [l for l in p.stderr.splitlines() if "error:" in l]
    msg = errors[0] if errors else p.stderr.strip()[-300:]
    check(p.returncode != 0, f"{method} np{ranks}: exit status {p.returncode} (non-zero)")
    check(len(errors) == 1 and "particle" in msg and "left the domain" in msg and "(" in msg,
          f"{method} np{ranks}: one message with particle, position and cause: {msg}")
    snaps = mt.snapshots(out)
    ok = len(snaps) >= 2
    for t, path in snaps:
        try:
            mt.particles(path)
        except Exception as e:  # noqa: BLE001
            ok = False
            print("unreadable", path, e)
    check(ok, f"{method} np{ranks}: {len(snaps)} snapshots written before the failure are readable")

sys.exit(check.finish())
