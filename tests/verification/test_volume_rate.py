"""The particle volume rate over the particle's domain (fluid.volume_rate = domain;
fluid/fluid_volume.c) on Toro's strong shock moving across the grid (his test 5: test 3 in a
frame moving at -19.59745, bench/fv_strip.py's toro3_moving) against the same problem at rest,
bs32 at a fixed step (time.cfl 0.99 with fluid.mol_damping = 0.3, the case's settings from
2026-12-02 to 2026-12-04, named on every run), one rank: every figure below is deterministic.

What it checks is the mechanism docs/gas.md describes: with the default point rule the hot
gas that comes to rest on the grid behind the rarefaction carries a J that runs away from its
particles' spacing (the spacing's J is exact to 0.05 %; the particles' J is 3.9 % above it at
400 cells), so its density is 3.7 % low; the domain rule keeps J with the spacing.

Measured (bench/bench_galilean.py, 2026-12-02), L1 of the cell-averaged density as test_sod
takes it, moving / at rest:
  point:  1.310 (200 cells), 1.504 (400)
  domain: 1.244 (200 cells), 1.296 (400)
Checks, for the rule named by the argument (default domain):
  - moving / rest <= 1.27 at 200 cells and <= 1.32 at 400 (measured 1.244, 1.296: 2 % above
    them, for roundoff-level changes elsewhere in the gas; the point rule's 1.310 and 1.504 fail
    both). The issue's target, 1.25 at 400 and 800 cells, is not met: see docs/gas.md.
  - the moving run's left star plateau (the middle half between the fan's tail and the
    contact): the particles' mean J within 1.5 % of the J of their spacing (measured +0.80 %;
    point +3.89 %) and the mean density within 1.5 % of the exact 0.5751 (measured -0.81 %;
    point -3.73 %).
  - at rest the rule costs no accuracy: L1 at most 0.5 % above the point rule's at 200 and
    400 cells (measured 0.8 % and 0.1 % below).
Run with the argument `point` it checks the default rule against the bounds, and the ratio and
plateau checks fail: that is how the test was checked to be able to fail (on a build without
the key every run exits 2).
Every run names fluid.pressure = particle, so that both rules run under one pressure: the
domain rule is outside the hybrid's scope, and auto took the hybrid for the point rule
(2026-12-03), whose L1 at rest, 2.512e-2 / 1.889e-2 at 200 / 400 cells, put the domain rule's
2.606e-2 / 1.961e-2 at 1.037 / 1.038 of it and failed the at-rest check.
Bad input: an unknown fluid.volume_rate is one line naming the key, exit 2.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402

sys.path.insert(0, os.path.join(os.path.abspath(mt.SOURCE), "bench"))
import fv_strip  # noqa: E402

check = mt.Checks("test_volume_rate")
RULE = sys.argv[1] if len(sys.argv) > 1 else "domain"
RATIO_MAX = {200: 1.27, 400: 1.32}


def spacing_J(P):
    """Each particle's J from its neighbours along its row of the strip: half the distance
    between the two, over its initial spacing (V0^(1/2) at 2 x 2 particles per cell)."""
    x, y, V0 = P["x"][:, 0], P["x"][:, 1], P["V0"][:, 0]
    Jg = np.full_like(x, np.nan)
    for row in np.unique(np.round(y, 9)):
        k = np.where(np.abs(y - row) < 1e-9)[0]
        k = k[np.argsort(x[k])]
        Jg[k[1:-1]] = 0.5 * (x[k[2:]] - x[k[:-2]]) / np.sqrt(V0[k[1:-1]])
    return Jg


def measure(problem, N, rule):
    PR = fv_strip.PROBLEMS[problem]
    out = shocktube.run(PR.case, N, "bs32", PR.t, 1,
                        [f"output.interval={PR.t}", f"fluid.volume_rate={rule}",
                         "fluid.pressure=particle", "time.cfl=0.99", "fluid.mol_damping=0.3"]
                        + PR.mpm_overrides(), x0=PR.x0)
    P = mt.particles(mt.snapshots(out)[-1][1], "fluid")
    l1, _, plat = fv_strip.mpm_measure(PR, P, N)
    ex, t = PR.exact, PR.t
    tail = ex.x0 + (ex.u_star - ex.cl * (ex.p_star / ex.pl) ** ((ex.g - 1) / (2 * ex.g))) * t
    a, b = tail, ex.contact_position(t)
    x = P["x"][:, 0]
    k = (x > a + 0.25 * (b - a)) & (x < b - 0.25 * (b - a))
    jg = float(np.nanmean(P["J"][k, 0] / spacing_J(P)[k]) - 1.0)
    print(f"info {problem} {N} cells, {rule}: L1 {l1:.4e}, left plateau {plat[1] * 100:+.2f} %, "
          f"J / spacing J - 1 there {jg * 100:+.2f} %; {mt.cost(out)}")
    return l1, plat[1], jg


for N in (200, 400):
    rest_point = measure("toro3", N, "point")[0]
    rest = measure("toro3", N, RULE)[0] if RULE != "point" else rest_point
    moving, plat, jg = measure("toro3_moving", N, RULE)
    check(moving / rest <= RATIO_MAX[N], f"{N} cells, {RULE}: moving / at rest {moving / rest:.3f} "
          f"(<= {RATIO_MAX[N]}; L1 {moving:.4e} / {rest:.4e})")
    check(rest <= 1.005 * rest_point, f"{N} cells, {RULE}: at rest L1 {rest:.4e} = "
          f"{rest / rest_point:.4f} of the point rule's (<= 1.005)")
    if N == 400:
        check(abs(jg) <= 0.015, f"{N} cells, {RULE}: moving, left plateau J / spacing J - 1 = "
              f"{jg * 100:+.2f} % (within 1.5 %)")
        check(abs(plat) <= 0.015, f"{N} cells, {RULE}: moving, left plateau density "
              f"{plat * 100:+.2f} % from exact (within 1.5 %)")

text = open(mt.case("strong_shock.ini")).read() + "\n[fluid]\nvolume_rate = cells\n"
mt.expect_input_error(check, "unknown fluid.volume_rate", text, "fluid.volume_rate",
                      mt.line_starting(text, "volume_rate = cells"))
sys.exit(check.finish())
