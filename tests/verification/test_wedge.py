"""Mach 2.5 flow over a 15 degree wedge (cases/wedge.ini): an attached oblique shock, under both
wall treatments side by side (fluid.wall_treatment = ghost, the code's default, and
least_squares, the case's since 2026-12-02).

theta-beta-M theory for gamma = 1.4, M = 2.5, theta = 15 deg: shock angle 36.94 deg, pressure
ratio 2.468 across it, post-shock speed 2.154 (c1 = 1). The flow is measured at t = 1.2 (three
passages through the domain: steady to the eye and in the figures below, which change by
< 0.1 % between t = 0.9 and 1.2).

- Shock: in every column of width dx between x = 0.45 and 0.95 (away from the foot, where the
  staircase of the obstacle bends the shock for a few cells, and from the exit), the height
  where p crosses (p1 + p2) / 2, from the top down, linearly interpolated between particles;
  a straight-line fit gives the angle.
- Pressure ratio: the mean particle pressure between the wedge and the shock (3 cells below
  it) over the same x range, over the free-stream pressure 1. ghost leaves the 3 cells above
  the wedge out (its wall layer is slow and hot); least_squares counts every particle.
- First layer: the particles within dx / 2 of the ramp (ppc = 2) over the same x range, their
  mean speed against the post-shock speed (least_squares; ghost's is printed).
- Force on the wedge (obstacles.csv, mean over the last 200 steps): the ramp inside the domain
  carries p2 on a length L = 0.8 / cos 15, so theory gives Fx = p2 L sin 15 = 0.5284 and
  Fy = -p2 L cos 15 = -1.974 per unit span.

Tolerances: the issue's. Angle within 1 deg (ghost at dx = 0.01: 1.5 deg, the measured error of
that resolution inside it), ratio within 3 %, first layer within 3 %, ramp force within 2 % of
p2 L in both components (the issue's words: each component's error against p2 times the ramp
length; least_squares, and ghost at dx = 0.005). Until 2026-11-27 the check was stricter, each
component within 2 % of its own theoretical value, so Fx, a quarter of p2 L, was held to 0.5 %
of it; at dx = 0.01 Fx then sat at +1.97 % of p2 L sin and went to +2.00 % when the
least-squares fit's energy change was spread over the whole gas (fluid_wall_ls.h). Both figures
are printed.
Measured (dx = 0.005, `long`; dx = 0.01, the default):
  least_squares  angle 36.93 / 37.03 deg, ratio +0.46 % / +0.78 % with no cell skipped, first
                 layer +1.5 % / +0.10 %, Fx -0.21 % / +2.00 % of p2 L sin (-0.05 % / +0.52 % of
                 p2 L), Fy -0.25 % / -0.38 % of p2 L cos (+0.24 % / +0.37 % of p2 L), no
                 particle inside the ramp (before the energy spreading: ratio -0.01 % / +0.50 %,
                 first layer +1.3 % / +0.05 %, Fx -0.10 % / +1.97 %, Fy -0.41 % / -0.45 %);
  ghost          angle 36.99 / 37.04 deg, ratio +0.22 % / +0.17 % (3 cells skipped), first
                 layer at 0.93 / 0.95 of the post-shock speed, Fx +0.85 % / +2.12 % of p2 L sin
                 (+0.22 % / +0.55 % of p2 L), Fy -1.05 % / -2.18 % of p2 L cos (+1.01 % / +2.11 %
                 of p2 L), no particle inside the ramp (2026-12-05, since held nodes coast under
                 the classic update: fluid/fluid_obstacle.h, Nodes).
ghost at dx = 0.005 (`ghost_long`) checks the same figures, its lift, the ramp force within 2 %
of p2 L and no particle inside the ramp. `ghost_light_long` runs the same with the light-node
rule (fluid.light_node_mass = 0.05, the main job's value): angle 36.98 deg, ratio +0.21 %, Fx
+0.38 % and Fy +0.69 % of p2 L, first layer at 0.97.
Before 2026-12-05 the held nodes at the ramp stopped (an impulse under usl that FLIP carried into
the first layer, which moved at 0.17 of the post-shock speed): gas gathered in the ramp's foot
(27-97 particles, some at up to 130 p2), bent the shock (36.33 deg at dx = 0.01, meeting y = 0 at
x = 0.04 instead of the foot, Fx +25 % of p2 L sin), and at dx = 0.005 blew up at t = 0.886
(an expected failure then; with the light-node rule it completed, Fx +14.6 %).
The default also checks the same flow on 2 ranks as on 1 under both treatments (at t = 0.3, by
particle id, 1e-11 relative: the fields agree to about 1e-12; the lagged divergence divv, a
difference quotient of nodal velocities, sets the tolerance).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

LIGHT = "ghost_light_long" in sys.argv[1:]
GHOST = "ghost_long" in sys.argv[1:] or LIGHT
LONG = "long" in sys.argv[1:] or GHOST
check = mt.Checks("test_wedge" + ("_ghost_light_long" if LIGHT else "_ghost_long" if GHOST
                                  else "_long" if LONG else ""))
CASE = mt.case("wedge.ini")
DX = 0.005 if LONG else 0.01
BETA, RATIO, THETA, FOOT = 36.94, 2.468, 15.0, 0.2

U2, P2 = 2.1542, 2.4669  # post-shock speed and pressure of theta-beta-M (p1 = 1, c1 = 1)
L_RAMP = 0.8 / math.cos(math.radians(THETA))  # the ramp inside the domain


def measure(label, extra, skip, tol_beta, tol_ratio):
    """Run the case, check the shock angle, the pressure ratio (skip cells above the wedge left
    out) and the free stream; return the particles and the mean forces of the last 200 steps."""
    out = mt.outdir("wedge" + ("_" + label if label != "ghost" else ""))
    r = mt.run(["run", CASE, f"output.dir={out}", f"grid.dx={DX}", "run.progress=false"] + extra,
               check=False)
    if r.returncode != 0:
        first = next((ln for ln in r.stderr.splitlines() if ln.startswith("error")), r.stderr)
        check(False, f"{label}, dx = {DX}: the run completes to t = 1.2 ({first})")
        return None
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
    check(abs(beta - BETA) <= tol_beta,
          f"{label}, dx = {DX}: shock angle {beta:.2f} deg (theory {BETA}, tolerance {tol_beta} "
          f"deg) over {len(xs)} columns; the fitted shock meets y = 0 at x = "
          f"{-icpt / slope:.3f} (foot 0.2)")
    between = ((x > 0.45) & (x < 0.95) & (y > (x - FOOT) * tan_w + skip * DX)
               & (y < slope * x + icpt - 3 * DX))
    ratio = float(p[between].mean())
    check(abs(ratio / RATIO - 1) <= tol_ratio,
          f"{label}, dx = {DX}: pressure ratio {ratio:.4f} (theory {RATIO}, "
          f"{100 * (ratio / RATIO - 1):+.2f} %, tolerance {100 * tol_ratio:g} %) over "
          f"{between.sum()} particles from {skip} cells above the wedge, spread "
          f"{float(p[between].std()):.3f}")
    ahead = (x > 0.45) & (x < 0.95) & (y > slope * x + icpt + 3 * DX)
    check(abs(float(p[ahead].mean()) - 1) <= 0.03,
          f"{label}, dx = {DX}: the free stream ahead of the shock keeps p = "
          f"{float(p[ahead].mean()):.4f} (1 within 3 %)")
    rows = np.genfromtxt(os.path.join(out, "obstacles.csv"), delimiter=",", names=True,
                         dtype=None, encoding=None)
    fx, fy = float(np.mean(rows["Fx"][-200:])), float(np.mean(rows["Fy"][-200:]))
    fx_t, fy_t = P2 * L_RAMP * math.sin(math.radians(THETA)), -P2 * L_RAMP * math.cos(
        math.radians(THETA))
    print(f"{label}: force on the wedge Fx = {fx:.4f} ({100 * (fx / fx_t - 1):+.2f} % of "
          f"p2 L sin; {100 * (fx - fx_t) / (P2 * L_RAMP):+.2f} % of p2 L), Fy = {fy:.4f} "
          f"({100 * (fy / fy_t - 1):+.2f} % of -p2 L cos; {100 * (fy - fy_t) / (P2 * L_RAMP):+.2f} "
          f"% of p2 L)")
    d = (y - (x - FOOT) * tan_w) * math.cos(math.radians(THETA))
    first = (x > 0.45) & (x < 0.95) & (d < DX / 2)  # the first layer: ppc = 2 per cell
    speed = float(np.hypot(P["v"][first, 0], P["v"][first, 1]).mean()) if first.any() else 0.0
    print(f"{label}: first layer ({first.sum()} particles within dx/2 of the ramp) at "
          f"{speed / U2:.4f} of the post-shock speed; deepest particle {float(d[x > 0.25].min()):+.4f}"
          f" from the ramp")
    return ((fx / fx_t - 1, fy / fy_t - 1), ((fx - fx_t) / (P2 * L_RAMP), (fy - fy_t) / (P2 * L_RAMP)),
            speed / U2, first.sum(), float(d[x > 0.25].min()))


def check_ramp(label, res):
    """The ramp force within 2 % of p2 L in each component and no particle inside the ramp."""
    _, (ex, ey), _, _, deepest = res
    check(deepest >= 0, f"{label}: no particle inside the ramp (deepest {deepest:+.4f})")
    check(abs(ex) <= 0.02 and abs(ey) <= 0.02,
          f"{label}: ramp force off by Fx {100 * ex:+.2f} %, Fy {100 * ey:+.2f} % of p2 times the "
          "ramp length (tolerance 2 % each)")


# ghost (the default): the measured figures of each resolution inside the tolerances; at
# dx = 0.005 under `ghost_long` and `ghost_light_long` only, with the ramp force and no particle
# inside the ramp as for least_squares.
if GHOST or not LONG:
    res = measure("ghost", ["fluid.wall_treatment=ghost"] + (["fluid.light_node_mass=0.05"] if LIGHT
                                                              else []), 3,
                  1.0 if LONG else 1.5, 0.03)
    if GHOST:
        if res:
            fy_g = res[0][1]
            check(abs(fy_g) <= 0.05, f"ghost: Fy {100 * fy_g:+.1f} % of -p2 L cos (tolerance 5 %)")
            check_ramp("ghost", res)
        sys.exit(check.finish())
# least_squares: the acceptance with no cell skipped at the wall.
res = measure("least_squares", ["fluid.wall_treatment=least_squares"], 0, 1.0, 0.03)
if res:
    speed, nfirst = res[2], res[3]
    check(nfirst > 0 and abs(speed - 1) <= 0.03,
          f"least_squares: the first layer moves at {speed:.4f} of the post-shock speed "
          "(within 3 %)")
    check_ramp("least_squares", res)
if not LONG:
    mt.check_ranks_agree(check, CASE, ["time.t_end=0.3", "fluid.wall_treatment=ghost"],
                         "wedge_ranks", tol=1e-11, phase="fluid")
    mt.check_ranks_agree(check, CASE, ["time.t_end=0.3", "fluid.wall_treatment=least_squares"],
                         "wedge_ranks_ls", tol=1e-11, phase="fluid")

sys.exit(check.finish())
