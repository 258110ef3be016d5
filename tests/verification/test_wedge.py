"""Mach 2.5 flow over a 15 degree wedge (cases/wedge.ini): an attached oblique shock.

theta-beta-M theory for gamma = 1.4, M = 2.5, theta = 15 deg: shock angle 36.94 deg, pressure
ratio 2.468 across it. The flow is measured at t = 1.2 (three passages through the domain:
steady to the eye and in the figures below, which change by < 0.1 % between t = 0.9 and 1.2).

- Shock: in every column of width dx between x = 0.45 and 0.95 (away from the foot, where the
  staircase of the obstacle bends the shock for a few cells, and from the exit), the height
  where p crosses (p1 + p2) / 2, from the top down, linearly interpolated between particles;
  a straight-line fit gives the angle.
- Pressure ratio: the mean particle pressure between the wedge (3 cells above it) and the
  shock (3 cells below it) over the same x range, over the free-stream pressure 1.
- Force on the wedge (obstacles.csv, mean over the last 200 steps): the ramp inside the domain
  carries p2 on a length 0.8 / cos 15, so theory gives Fy = -0.8 p2 = -1.974 per unit span.

Acceptance (`long`, dx = 0.005, 3 minutes): angle within 1 deg of 36.94, ratio within 3 % of
2.468 (the issue's tolerances; measured 37.16 deg and +0.38 %), Fy within 5 % (-2.7 %). The
default (`fast`, dx = 0.01) is a regression guard with the measured figures of that resolution
inside its tolerances: angle within 1.5 deg (35.92 deg, -1.02), ratio within 3 % (-0.06 %), and
the same flow on 2 ranks as on 1 (at t = 0.3, by particle id, 1e-11 relative: the fields agree
to 7e-13, the lagged divergence divv, a difference quotient of nodal velocities, to 1.8e-12).
Fx is printed, not checked: it also takes the overpressure the staircase makes at the foot
(+13 % at dx = 0.005).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

LONG = "long" in sys.argv[1:]
check = mt.Checks("test_wedge" + ("_long" if LONG else ""))
CASE = mt.case("wedge.ini")
DX = 0.005 if LONG else 0.01
BETA, RATIO, THETA, FOOT = 36.94, 2.468, 15.0, 0.2

out = mt.outdir("wedge")
mt.run(["run", CASE, f"output.dir={out}", f"grid.dx={DX}", "run.progress=false"])
P = mt.particles(mt.snapshots(out)[-1][1], "fluid")
x, y, p = P["x"][:, 0], P["x"][:, 1], P["p"][:, 0]
tan_w = math.tan(math.radians(THETA))
above = y > (x - FOOT) * tan_w
mid = 0.5 * (1.0 + RATIO)
xs, ys = [], []
for xb in np.arange(0.45, 0.95, DX):
    s = above & (x >= xb) & (x < xb + DX)
    order = np.argsort(-y[s])
    yy, pp = y[s][order], p[s][order]
    k = int(np.argmax(pp > mid))
    if k == 0:
        continue
    xs.append(xb + DX / 2)
    ys.append(yy[k - 1] + (mid - pp[k - 1]) * (yy[k] - yy[k - 1]) / (pp[k] - pp[k - 1]))
slope, icpt = np.polyfit(xs, ys, 1)
beta = math.degrees(math.atan(slope))
tol_beta = 1.0 if LONG else 1.5
check(abs(beta - BETA) <= tol_beta,
      f"dx = {DX}: shock angle {beta:.2f} deg (theory {BETA}, tolerance {tol_beta} deg) over "
      f"{len(xs)} columns; the fitted shock meets y = 0 at x = {-icpt / slope:.3f} (foot 0.2)")
between = ((x > 0.45) & (x < 0.95) & (y > (x - FOOT) * tan_w + 3 * DX)
           & (y < slope * x + icpt - 3 * DX))
ratio = float(p[between].mean())
check(abs(ratio / RATIO - 1) <= 0.03,
      f"dx = {DX}: pressure ratio {ratio:.4f} (theory {RATIO}, {100 * (ratio / RATIO - 1):+.2f} %, "
      f"tolerance 3 %) over {between.sum()} particles, spread {float(p[between].std()):.3f}")
ahead = (x > 0.45) & (x < 0.95) & (y > slope * x + icpt + 3 * DX)
check(abs(float(p[ahead].mean()) - 1) <= 0.03,
      f"dx = {DX}: the free stream ahead of the shock keeps p = {float(p[ahead].mean()):.4f} "
      f"(1 within 3 %)")

rows = np.genfromtxt(os.path.join(out, "obstacles.csv"), delimiter=",", names=True,
                     dtype=None, encoding=None)
fx, fy = float(np.mean(rows["Fx"][-200:])), float(np.mean(rows["Fy"][-200:]))
fy_theory = -0.8 * RATIO
print(f"force on the wedge: Fx = {fx:.4f} (theory {0.8 * tan_w * RATIO:.4f}), Fy = {fy:.4f}")
if LONG:
    check(abs(fy / fy_theory - 1) <= 0.05,
          f"Fy = {fy:.4f} (theory {fy_theory:.4f}, {100 * (fy / fy_theory - 1):+.1f} %, tolerance "
          f"5 %)")
else:
    mt.check_ranks_agree(check, CASE, ["time.t_end=0.3"], "wedge_ranks", tol=1e-11, phase="fluid")

sys.exit(check.finish())
