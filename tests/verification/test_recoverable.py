"""A run that cannot continue stops with one message naming the particle, its position and
the cause, exits non-zero, and leaves the output already written readable.

The ballistic block is thrown at the right wall; once a particle would leave the domain the
RHS reports a recoverable error (naming the face, boundary.x_hi, and that no smaller step
helps), the integrator retries with smaller steps (time.max_retries
times), then the run stops. The snapshots written before must still open with h5py and be
listed in a well-formed series.xmf, and the last accepted state, where the run stopped, is one
more snapshot of the series, which a second message names.
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
    causes = [l for l in errors if "particle" in l]
    msg = causes[0] if causes else p.stderr.strip()[-300:]
    check(p.returncode != 0, f"{method} np{ranks}: exit status {p.returncode} (non-zero)")
    check(len(causes) == 1 and "face boundary.x_hi, which no body may cross" in msg and "(" in msg
          and "A smaller step does not help" in msg,
          f"{method} np{ranks}: one message with particle, position and cause: {msg}")
    snaps = mt.snapshots(out)
    named = [l for l in errors if "series.xmf" in l]
    stop_t = float(named[0].split("t = ")[1].split(",")[0]) if named else -1.0
    # (The message prints the time to 6 digits.)
    at_stop = bool(snaps) and abs(snaps[-1][0] - stop_t) <= 1e-5 * stop_t
    check(len(errors) == 2 and len(named) == 1 and at_stop and 0.0 < stop_t < 0.2,
          f"{method} np{ranks}: the stopped state is the last snapshot (t = {stop_t:.6g}; the "
          f"series ends at {snaps[-1][0] if snaps else None}), named by a second message")
    ok = len(snaps) >= 3
    for t, path in snaps:
        try:
            mt.particles(path)
        except Exception as e:  # noqa: BLE001
            ok = False
            print("unreadable", path, e)
    check(ok, f"{method} np{ranks}: {len(snaps)} snapshots written before the failure are readable")

sys.exit(check.finish())
