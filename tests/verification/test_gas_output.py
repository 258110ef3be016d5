"""Gas output fields and restart (cases/sod.ini at 100 cells, to t = 0.1).

1. Every snapshot (the one at t = 0 included) carries the fluid output fields, consistent with
   the state fields of the same particles: rho = m / (V0 J), p = (gamma - 1) rho e,
   mach = |v| / sqrt(gamma p / rho), T = p / (rho R), s = R / (gamma - 1) ln(p / rho^gamma),
   for a non-default gamma (1.3) and R (300), to 1e-12 relative (the same formulas in another
   order of operations; a wrong constant or formula is off by percents). The t = 0 snapshot
   also shows the seeded state: rho and p equal the [gas] values exactly on each side.
2. Restart: a run that checkpoints at t = 0.05 and the run restarted from that checkpoint end
   bitwise identical (by particle id, every field), for usl (whose lagged strain rate is
   state) and bs32 (where it is a field the checkpoint carries).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_gas_output")
GAMMA, R = 1.3, 300.0
N, H = 100, 0.03
COMMON = ["run.progress=false", f"grid.dx={1.0 / N}", f"domain.hi=1 {H}",
          f"geometry.left.hi=0.5 {H}", f"geometry.right.hi=1 {H}", "time.t_end=0.1",
          "output.interval=0.05"]


def run(name, extra, ranks=1):
    out = mt.outdir(name)
    mt.run(["run", mt.case("sod.ini"), f"output.dir={out}"] + COMMON + list(extra), ranks)
    return out


def rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


out = run("gas_fields", [f"fluid.gamma={GAMMA}", f"fluid.R={R}"])
snaps = mt.snapshots(out)
check(len(snaps) == 3, f"{len(snaps)} snapshots (t = 0, 0.05, 0.1)")
worst = 0.0
for t, path in snaps:
    P = mt.particles(path, "fluid")
    rho = P["m"][:, 0] / (P["V0"][:, 0] * P["J"][:, 0])
    p = (GAMMA - 1) * rho * P["e"][:, 0]
    c = np.sqrt(GAMMA * p / rho)
    expect = {"rho": rho, "p": p, "mach": np.linalg.norm(P["v"], axis=1) / c,
              "T": p / (rho * R), "s": R / (GAMMA - 1) * np.log(p / rho ** GAMMA)}
    for k, v in expect.items():
        worst = max(worst, rel(P[k][:, 0], v) if np.abs(v).max() > 0 else float(np.abs(P[k]).max()))
    if t == 0.0:
        left = P["x"][:, 0] < 0.5
        seeded = (np.all(P["rho"][left, 0] == 1.0) and np.all(P["rho"][~left, 0] == 0.125)
                  and np.allclose(P["p"][left, 0], 1.0, rtol=1e-15, atol=0)
                  and np.allclose(P["p"][~left, 0], 0.1, rtol=1e-15, atol=0))
        check(seeded, "t = 0: rho and p are the seeded states (1, 1) | (0.125, 0.1)")
check(worst <= 1e-12, f"output fields vs the state, every snapshot: largest relative difference "
      f"{worst:.1e} (<= 1e-12)")

for method in ("usl", "bs32"):
    for ranks in (1, 2):
        full = run(f"gas_full_{method}_np{ranks}",
                   [f"time.method={method}", "output.checkpoint_interval=0.05"], ranks)
        ckpt = os.path.join(full, "checkpoint_000001.h5")
        if not os.path.exists(ckpt):
            check(False, f"{method} np{ranks}: checkpoint at t = 0.05 written")
            continue
        rest = mt.outdir(f"gas_restarted_{method}_np{ranks}")
        mt.run(["restart", ckpt, f"output.dir={rest}", "run.progress=false"], ranks)
        a = mt.particles(mt.snapshots(full)[-1][1], "fluid")
        b = mt.particles(mt.snapshots(rest)[-1][1], "fluid")
        same = abs(b["time"] - 0.1) < 1e-12 and all(
            np.array_equal(a[k], b[k]) for k in a if k != "time")
        check(same, f"{method} np{ranks}: the restarted run ends bitwise identical to the full run")

sys.exit(check.finish())
