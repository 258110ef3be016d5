"""Woodward-Colella Mach 3 wind tunnel with a forward-facing step (cases/forward_step.ini).

The hard case of the gas module: a strong bow shock, its reflections off the upper wall and the
step, and the expansion round the step's corner into a near vacuum. The acceptance is
robustness: the run reaches t = 4 with every particle's density and pressure positive and
finite (checked at every snapshot, every 0.5), and the density image is written (`long`,
dx = 1/80, the resolution of the classic figures' coarsest grid: 240 x 80 cells). The default
selection runs the first unit of time at dx = 1/40 with the same checks, as a guard.
Also checked: the bow shock stands ahead of the step face (x < 0.6) on the lower wall and the
gas ahead of it keeps the inflow state (rho 1.4 within 1 %), which a boundary or obstacle error
would break.
"""
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

LONG = "long" in sys.argv[1:]
check = mt.Checks("test_forward_step" + ("_long" if LONG else ""))
DX, T_END = (0.0125, 4.0) if LONG else (0.025, 1.0)
out = mt.outdir("forward_step")
p = mt.run(["run", mt.case("forward_step.ini"), f"output.dir={out}", f"grid.dx={DX}",
            f"time.t_end={T_END}", "run.progress=false"], check=False, timeout=3300)
check(p.returncode == 0, f"dx = {DX}: the run reaches t = {T_END:g} (exit {p.returncode}) "
      f"{p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ''}")
snaps = mt.snapshots(out)
check(abs(snaps[-1][0] - T_END) < 1e-9, f"last snapshot at t = {snaps[-1][0]:g}")
worst_rho, worst_p, finite = np.inf, np.inf, True
for t, path in snaps:
    P = mt.particles(path, "fluid")
    finite &= all(np.isfinite(P[k]).all() for k in ("x", "v", "rho", "p", "e", "J"))
    worst_rho, worst_p = min(worst_rho, P["rho"].min()), min(worst_p, P["p"].min())
check(finite and worst_rho > 0 and worst_p > 0,
      f"every snapshot finite, smallest density {worst_rho:.3g} and pressure {worst_p:.3g} > 0")
P = mt.particles(snaps[-1][1], "fluid")
x, y, rho = P["x"][:, 0], P["x"][:, 1], P["rho"][:, 0]
low = y < 0.1
jump = x[low & (rho > 2.1)]  # behind the bow shock (ahead of it rho = 1.4)
stand = float(jump.min()) if jump.size else np.nan
check(stand < 0.6, f"t = {T_END:g}: the bow shock stands at x = {stand:.3f} on the lower wall, "
      f"ahead of the step face at 0.6")
ahead = x < stand - 4 * DX
check(abs(float(rho[ahead & low].mean()) / 1.4 - 1) < 0.01,
      f"t = {T_END:g}: ahead of it rho = {float(rho[ahead & low].mean()):.4f} (1.4 within 1 %)")
if LONG:
    png = os.path.join(out, "forward_step_rho.png")
    tool = os.path.join(mt.SOURCE, "tools", "plot_fields.py")
    r = subprocess.run([sys.executable, tool, out, str(len(snaps) - 1), "--field", "rho",
                        "--out", png], capture_output=True, text=True)
    check(r.returncode == 0 and os.path.getsize(png) > 0, f"density image {png}: {r.stdout.strip()}")
sys.exit(check.finish())
