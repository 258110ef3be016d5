"""Uniform Mach 2.5 flow along a slip wall at 10 and 30 degrees to the grid
(cases/slanted_wall.ini, dx = 0.02): the exact solution is the free stream everywhere, so every
disturbance is the wall treatment's error where the grid cuts the wall obliquely.

Measured at t = 1.0 (2.5 passages of the flow through the unit domain) over the particles with
0.2 < x < 0.8 and y < 0.85 (away from the inflow and the two outflows), the first layer on the
wall included:
- stability: the run reaches t_end (ghost, the default treatment, blows up on both: its total
  energy grows a thousandfold by t = 0.63 at 10 degrees and t = 0.08-0.58 at 30 degrees, before
  and after the obstacles' work was booked as heat; printed, not checked, as a regression
  record of why least_squares exists);
- no particle crosses the wall;
- the largest velocity deviation |v - v_inf| / |v_inf| within 1 % (the issue's tolerance;
  measured 0.53 % at 10 degrees and 1.30 % at 30: not met at 30, see below);
- the largest pressure deviation |p - 1| within 1 % (the issue's tolerance; measured 5.0 % and
  4.9 %, a few particles in the fitted band, 0.7-1.5 cells from the wall: not met);
- the RMS pressure deviation within 1.5 % (measured 0.87 % and 0.92 %: the bulk of the flow
  is uniform; not an issue figure, a regression guard at the measured level with a margin of
  half of it).
With the argument `max` only the two largest deviations are checked: that test is registered as
an expected failure (the issue's 1 % on the worst particle is not reached).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

MAX = "max" in sys.argv[1:]
check = mt.Checks("test_slanted_wall" + ("_max" if MAX else ""))
CASE = mt.case("slanted_wall.ini")


def overrides(angle):
    a = math.radians(angle)
    t, u, v = math.tan(a), 2.5 * math.cos(a), 2.5 * math.sin(a)
    return [f"obstacle.wall.vertices=-0.2 {0.1 - 0.2 * t:.12g} 1.2 {0.1 + 1.2 * t:.12g} "
            "1.2 -0.2 -0.2 -0.2", f"gas.air.velocity={u:.15g} {v:.15g}",
            f"freestream.velocity={u:.15g} {v:.15g}"]


for angle in (10, 30):
    a = math.radians(angle)
    if not MAX:
        ghost = mt.outdir(f"slanted_{angle}_ghost")
        p = mt.run(["run", CASE, f"output.dir={ghost}", "run.progress=false",
                    "fluid.wall_treatment=ghost"] + overrides(angle), check=False)
        print(f"{angle} deg, ghost: exit {p.returncode}: "
              f"{(p.stderr.strip().splitlines() or [''])[-1][:160]}")
    out = mt.outdir(f"slanted_{angle}")
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"] + overrides(angle))
    t, path = mt.snapshots(out)[-1]
    P = mt.particles(path, "fluid")
    x, y, v, p = P["x"][:, 0], P["x"][:, 1], P["v"], P["p"][:, 0]
    d = (y - 0.1 - x * math.tan(a)) * math.cos(a)
    s = (x > 0.2) & (x < 0.8) & (y < 0.85)
    dv = np.hypot(v[s, 0] - 2.5 * math.cos(a), v[s, 1] - 2.5 * math.sin(a)) / 2.5
    dp = np.abs(p[s] - 1.0)
    if MAX:
        check(dv.max() <= 0.01, f"{angle} deg: largest velocity deviation {100 * dv.max():.2f} % "
              f"(<= 1 %), at {d[s][np.argmax(dv)] / 0.02:.2f} cells from the wall")
        check(dp.max() <= 0.01, f"{angle} deg: largest pressure deviation {100 * dp.max():.2f} % "
              f"(<= 1 %), at {d[s][np.argmax(dp)] / 0.02:.2f} cells from the wall")
        continue
    check(abs(t - 1.0) < 1e-9, f"{angle} deg: least_squares reaches t = {t:g}")
    check(float(d.min()) >= 0.0, f"{angle} deg: no particle crosses the wall (closest "
          f"{float(d.min()) / 0.02:.2f} cells)")
    rms = float(np.sqrt((dp ** 2).mean()))
    check(rms <= 0.015, f"{angle} deg: RMS pressure deviation {100 * rms:.2f} % (<= 1.5 %) over "
          f"{s.sum()} particles; largest {100 * dp.max():.2f} %, velocity RMS "
          f"{100 * float(np.sqrt((dv ** 2).mean())):.2f} % and largest {100 * dv.max():.2f} %")

sys.exit(check.finish())
