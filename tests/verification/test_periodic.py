"""A block flying through a periodic face, end to end (cases/periodic2d.ini).

The strip [0, 2] x [0, 1] is periodic along x, open along y; the block moves at v0 = (2, 0.25)
m/s with no gravity, so it crosses x = 2 and re-enters at x = 0 once in 0.6 s. A pure
translation has no velocity gradient, so every particle follows x0 + v0 t wrapped into
[0, 2), keeps v = v0 and F = I.

1. Serial, bs32: at every snapshot every position equals the wrapped exact one within
   1e-10 m (the ballistic tolerance; the motion is linear in t, integrated exactly, so only
   roundoff remains), velocities equal v0 within 1e-10 m/s, and |F - I| <= 1e-10. A wrong
   halo across the face would give the particles near it a velocity gradient of order
   v0 / dx, i.e. |F - I| of order 1e-2 after one step. At least one snapshot has the block
   split across the face, so the test does exercise it. Once more without sorting
   (run.sort_every=0): then only the wrap tells the integrator that the state changed.
2. Two ranks, split along x (the face is a boundary between the two ranks) and along y (each
   rank wraps onto itself along x): same particle ids and the serial result within 1e-12
   (as in test_ballistic: the same steps, sums in another order), and the exact position.
3. The classic updates (usl, musl, and usl with APIC), serial: the same checks as 1. With
   APIC a wrong halo would also show as a nonzero affine velocity C, hence a change of v.
4. Restart on 1 and 2 ranks: a run that checkpoints at T/2 and a run restarted from that
   checkpoint end bitwise identical (compared by id), as test_restart requires elsewhere.
5. A periodic axis with fewer cells than the shape's ghost layers: one error naming the key.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_periodic")
CASE = mt.case("periodic2d.ini")
LO, HI = np.array([0.0, 0.0]), np.array([2.0, 1.0])
V0 = np.array([2.0, 0.25])
COMMON = ["run.progress=false"]


def wrapped_error(x, x0, t):
    """Largest distance between x and x0 + v0 t, modulo the period along x."""
    e = x - (x0 + np.outer(np.ones(len(x0)), V0) * t)
    e[:, 0] -= (HI[0] - LO[0]) * np.round(e[:, 0] / (HI[0] - LO[0]))
    return float(np.abs(e).max())


def run(name, ranks=1, extra=()):
    out = mt.outdir(name)
    mt.run(["run", CASE, f"output.dir={out}"] + COMMON + list(extra), ranks)
    return out


def exact_motion(out, label):
    snaps = mt.snapshots(out)
    first = mt.particles(snaps[0][1])
    err = verr = ferr = 0.0
    inside, straddles = True, False
    for t, path in snaps:
        p = mt.particles(path)
        if not np.array_equal(p["id"], first["id"]):
            check(False, f"{label}: the particle ids changed at t = {t}")
            return
        err = max(err, wrapped_error(p["x"], first["x"], t))
        verr = max(verr, float(np.abs(p["v"] - V0).max()))
        ferr = max(ferr, float(np.abs(p["F"] - np.eye(2).reshape(-1)).max()))
        inside &= bool(np.all(p["x"] >= LO) and np.all(p["x"] < HI))
        straddles |= bool(p["x"][:, 0].max() - p["x"][:, 0].min() > 0.5 * (HI[0] - LO[0]))
    check(len(snaps) == 7 and abs(snaps[-1][0] - 0.6) < 1e-12,
          f"{label}: {len(snaps)} snapshots up to t = {snaps[-1][0]:.3g}")
    check(err <= 1e-10, f"{label}: max |x - wrapped exact| = {err:.3e} m (tolerance 1e-10)")
    check(verr <= 1e-10, f"{label}: max |v - v0| = {verr:.3e} m/s (tolerance 1e-10)")
    check(ferr <= 1e-10, f"{label}: max |F - I| = {ferr:.3e} (tolerance 1e-10)")
    check(inside, f"{label}: every snapshot position lies in [lo, hi)")
    check(straddles, f"{label}: some snapshot has the block split across the periodic face")


serial = run("periodic_np1")
exact_motion(serial, "serial bs32")
# Without sorting, nothing but the wrap itself tells the integrator that the state moved.
exact_motion(run("periodic_np1_unsorted", 1, ["run.sort_every=0"]), "serial bs32 unsorted")
a = mt.particles(mt.snapshots(serial)[-1][1])

for ranks_key in ("2 1", "1 2"):
    par = run(f"periodic_np2_{ranks_key.replace(' ', 'x')}", 2, [f"grid.ranks={ranks_key}"])
    label = f"2 ranks ({ranks_key.replace(' ', ' x ')})"
    exact_motion(par, label)
    b = mt.particles(mt.snapshots(par)[-1][1])
    same = np.array_equal(a["id"], b["id"])
    check(same, f"{label}: the same {len(a['id'])} particle ids as 1 rank")
    if same:
        diff = max(float(np.abs(a[k] - b[k]).max()) for k in ("x", "v", "F"))
        check(diff <= 1e-12, f"{label}: vs 1 rank, max difference {diff:.3e} (tolerance 1e-12)")

for extra in (["time.method=usl"], ["time.method=musl"],
              ["time.method=usl", "transfer.velocity=apic"]):
    exact_motion(run("periodic_classic", 1, extra), "serial " + " ".join(extra))

T = 0.6
for ranks in (1, 2):
    full = run(f"periodic_full_np{ranks}", ranks, [f"output.checkpoint_interval={T / 2}"])
    ckpt = os.path.join(full, "checkpoint_000001.h5")
    check(os.path.exists(ckpt), f"restart np{ranks}: checkpoint at T/2 written")
    if not os.path.exists(ckpt):
        continue
    rest = mt.outdir(f"periodic_restarted_np{ranks}")
    mt.run(["restart", ckpt, f"output.dir={rest}"], ranks)
    a2 = mt.particles(mt.snapshots(full)[-1][1])
    b2 = mt.particles(mt.snapshots(rest)[-1][1])
    same = abs(b2["time"] - T) < 1e-12 and np.array_equal(a2["id"], b2["id"]) and all(
        np.array_equal(a2[k], b2[k]) for k in ("x", "v", "F"))
    check(same, f"restart np{ranks}: the restarted run ends bitwise identical to the full run")

# A periodic axis shorter than the ghost layers (3 for quadratic) is an input error naming the
# boundary key (here from the command line), before any output.
bad = mt.outdir("periodic_too_short")
p = mt.run(["run", CASE, f"output.dir={bad}/out", "domain.hi=2 0.2", "boundary.y_lo=periodic",
            "boundary.y_hi=periodic"] + COMMON, check=False)
errors = [l for l in p.stderr.splitlines() if l.startswith("error:")]
check(p.returncode == 2 and len(errors) == 1 and "boundary.y_lo" in errors[0]
      and "at least 3 cells" in errors[0] and not os.path.exists(f"{bad}/out"),
      f"2-cell periodic axis: exit {p.returncode}: {errors[0] if errors else p.stderr[-300:]}")

sys.exit(check.finish())
