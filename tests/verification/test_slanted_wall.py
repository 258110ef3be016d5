"""Uniform Mach 2.5 flow along a slip wall at 0, 10 and 30 degrees to the grid
(cases/slanted_wall.ini, dx = 0.02, least_squares with fluid.wall_blend = 1): the exact solution
is the free stream everywhere, so every disturbance is the wall treatment's error where the grid
cuts the wall (at 0 degrees the wall lies on the grid line y = 0.1, the flow runs along x and
the top face is a slip wall too, so that no open face runs parallel to the flow).

Measured at every snapshot from t = 0.75 on (t = 0.75 and 1.0: 1.9 and 2.5 passages of the flow
through the unit domain, well after the flow has passed the wall's start) over the particles with
0.2 < x < 0.8 and y < 0.85 (away from the inflow and the outflows), the first layer on the wall
included:
- stability: the run reaches t_end (ghost blows up at every angle: its total energy grows a
  thousandfold by t = 0.68, 0.67 and 0.70 at 0, 10 and 30 degrees; printed, not checked, as a
  regression record of why least_squares exists);
- no particle crosses the wall;
- the wall layer (within 1 cell of the wall): its mean pressure within 1.5 % of the free
  stream's (measured 0.10 %, 0.02 % and 0.22 % at 0, 10 and 30 degrees at t = 1);
- the largest velocity deviation |v - v_inf| / |v_inf| within 1 % (the issue's tolerance;
  measured 0.02 %, 0.16-0.17 % and 0.16-0.19 %);
- the largest pressure deviation |p - 1| within 1 % (the issue's tolerance; measured 0.16 %,
  0.48-0.55 % and 0.52-0.53 %);
- the RMS pressure deviation within 1.5 % (measured 0.10 %, 0.17 % and 0.24 %: a regression
  guard, not an issue figure).
Without the blend (fluid.wall_blend = 0, the default elsewhere; printed, not checked) the worst
particles sit on the rows just outside the fitted band: velocity 1.01 % and 1.43 %, pressure
2.49 % and 4.22 % at 10 and 30 degrees (this test's expected failure until 2026-11-29).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_slanted_wall")
CASE = mt.case("slanted_wall.ini")


def overrides(angle):
    a = math.radians(angle)
    t, u, v = math.tan(a), 2.5 * math.cos(a), 2.5 * math.sin(a)
    return [f"obstacle.wall.vertices=-0.2 {0.1 - 0.2 * t:.12g} 1.2 {0.1 + 1.2 * t:.12g} "
            "1.2 -0.2 -0.2 -0.2", f"gas.air.velocity={u:.15g} {v:.15g}",
            f"freestream.velocity={u:.15g} {v:.15g}"] + (["boundary.y_hi=slip"] if angle == 0
                                                          else [])


def deviations(out, a, t_from):
    """Per snapshot from t_from on: t, the signed distances, the window, dv, dp."""
    for t, path in mt.snapshots(out):
        if t < t_from - 1e-9:
            continue
        P = mt.particles(path, "fluid")
        x, y, v, p = P["x"][:, 0], P["x"][:, 1], P["v"], P["p"][:, 0]
        d = (y - 0.1 - x * math.tan(a)) * math.cos(a)
        s = (x > 0.2) & (x < 0.8) & (y < 0.85)
        dv = np.hypot(v[s, 0] - 2.5 * math.cos(a), v[s, 1] - 2.5 * math.sin(a)) / 2.5
        yield t, d, s, p, dv, np.abs(p[s] - 1.0)


for angle in (0, 10, 30):
    a = math.radians(angle)
    ghost = mt.outdir(f"slanted_{angle}_ghost")
    p = mt.run(["run", CASE, f"output.dir={ghost}", "run.progress=false",
                "fluid.wall_treatment=ghost"] + overrides(angle), check=False)
    print(f"{angle} deg, ghost: exit {p.returncode}: "
          f"{(p.stderr.strip().splitlines() or [''])[-1][:160]}")
    if angle:
        sharp = mt.outdir(f"slanted_{angle}_sharp")
        mt.run(["run", CASE, f"output.dir={sharp}", "run.progress=false",
                "fluid.wall_blend=0"] + overrides(angle))
        *_, dv, dp = list(deviations(sharp, a, 1.0))[-1]
        print(f"{angle} deg, no blend: largest velocity deviation {100 * dv.max():.2f} %, "
              f"pressure {100 * dp.max():.2f} % (t = 1)")
    out = mt.outdir(f"slanted_{angle}")
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"] + overrides(angle))
    t_end = mt.snapshots(out)[-1][0]
    check(abs(t_end - 1.0) < 1e-9, f"{angle} deg: least_squares reaches t = {t_end:g}")
    for t, d, s, p, dv, dp in deviations(out, a, 0.75):
        if abs(t - 1.0) < 1e-9:
            check(float(d.min()) >= 0.0, f"{angle} deg: no particle crosses the wall (closest "
                  f"{float(d.min()) / 0.02:.2f} cells)")
            layer = s & (d < 0.02)
            dl = abs(float(p[layer].mean()) - 1.0)
            check(dl <= 0.015, f"{angle} deg: the wall layer's mean pressure {100 * dl:.2f} % "
                  f"from the free stream's (<= 1.5 %) over {layer.sum()} particles")
            rms = float(np.sqrt((dp ** 2).mean()))
            check(rms <= 0.015, f"{angle} deg: RMS pressure deviation {100 * rms:.2f} % (<= 1.5 "
                  f"%) over {s.sum()} particles")
        check(dv.max() <= 0.01, f"{angle} deg, t = {t:g}: largest velocity deviation "
              f"{100 * dv.max():.2f} % (<= 1 %), at {d[s][np.argmax(dv)] / 0.02:.2f} cells from "
              f"the wall")
        check(dp.max() <= 0.01, f"{angle} deg, t = {t:g}: largest pressure deviation "
              f"{100 * dp.max():.2f} % (<= 1 %), at {d[s][np.argmax(dp)] / 0.02:.2f} cells from "
              f"the wall")

sys.exit(check.finish())
