"""Gas pulled away from a slip wall: the particle densities under the strong-expansion settings.

Case: cases/wall_rarefaction.ini, gas at rho = 1, p = 0.4 leaving a slip wall at x = 0 at
u = +2, the right half of Toro's 123 problem (cases/double_rarefaction.ini, whose centre plane is
a slip wall by symmetry), usl to t = 0.15, on a strip of N/2 x 3 cells over [0, 0.5] (N the
cells per unit length, as in test_near_vacuum). The exact density is that of the double
rarefaction about x = 0 (tests/tools/riemann.py, x0 = 0): a fan from the wall into a near vacuum
at rest against it, rho* = 0.0219 (2.2 % of the initial density).

The strong-expansion settings are those of cases/double_rarefaction.ini (refill every step,
merges and splits every 5 steps, shifting, light merges), read from its [fluid] section, as
docs/gas.md "Expansion" gives them; the control is the default gas before 2026-12-04 (none of
them, no hole refill, the hybrid unweighted: fluid.refill_holes = false, fluid.hybrid_fill = 0).

Measures, at t = 0.15: each particle's density m / (V0 J) (the `rho` output) over the exact
density at its position; the nodal density with the quadratic B-spline folded about the wall
(the particles' images at -x counted, as the code folds its own deposits at a domain face; nodes
0 .. N/2 - 2, node 0 weighted by half a cell), its L1 error against the exact cell averages, and
its empty nodes short of the outermost particle.

Checks, at N = 200 and 400:
1. With the strong-expansion settings at most 7.5 % of the particles are outside a factor 2 of
   the exact density and none is outside a factor 5. Measured: 2.3 % / 1.2 % outside a factor
   2, densities 0.36-1.69 / 0.42-1.86 of the exact one. The near vacuum is chaotic: perturbed
   runs (output.interval 0.01 or 0.025 instead of 0.05, which moves the steps onto other
   times; time.cfl 0.38 or 0.42) gave 0.45-5.6 % outside a factor 2 and 0.27-3.8 times the
   exact density. Without the light merges (fluid.merge_light = 0, the settings before they
   joined them) the same five runs gave 8.8-17.6 % outside a factor 2 and 0.06-11.4 times the
   exact density: the check fails there (7.5 %: between the largest new 5.6 % and the smallest
   old 8.8 %; factor 5: beyond the new extremes, 3.8, and inside most old ones).
2. With those settings the nodal L1 error is no worse than the control's (the issue's
   acceptance; measured 0.0072 / 0.0051 against 0.0259 / 0.0253) and no node inside the gas is
   empty (the control leaves 29 / 54). The control takes the hybrid pressure (fluid.pressure =
   auto since 2026-12-03); with the particles' pressure it gave 0.0224 / 0.0230 and 26 / 50
   empty nodes (the strong settings' shifting keeps them on the particles' pressure).
3. The issue's target, every particle within a factor 2 of the exact density, is not reached:
   an expected failure. The particles outside it are the near vacuum's next to the wall (x <
   0.05), 0.36-0.5 of the exact density, where the gas, at rest in the exact solution, moves
   towards the wall at up to 0.5 (its sound speed there is 0.35) and the particle pressures
   scatter from 0.2 to 16 times the exact one. Not the merges' heat (with the merges' kinetic
   energy loss not turned into heat, a diagnostic run: 2.5 % / 0.7 % outside a factor 2).
   Neither larger light merges (0.25, 0.5), splits below 3 or 4 particles per cell, a smaller
   step (time.cfl 0.2), the light-node rule nor the neighbourhood step brought it to zero at
   both resolutions (the best: 1.5 % / 0.2 % with fluid.regularise_min = 4). With snapshots
   every 0.005 (200 cells) the share outside a factor 2 grows from 0.3 % at t = 0.005 to 13 %
   at t = 0.09 and falls to 5 % at 0.15; from t = 0.03 to 0.095 the particles in the wall's
   cell are below 1/100 of the exact density, the gas where the exact one is at rest moves
   away from the wall at 1.6-1.8 until t = 0.05 and back towards it at up to 1.5 at t = 0.085:
   the wall node is at rest while its neighbour keeps nearly the gas's speed, fed by refills at
   their donors' velocity. A diagnostic run that refilled no cell beside the wall (or none of
   the two nearest) removed the low densities (the lowest 0.54-0.69 of the exact one) but
   left particles there that never expanded (J about 1, up to 50 times the exact density;
   12 % / 6 % outside a factor 2): in the wall's cell a particle's volume follows the nodal
   divergence, which the wall node at rest and the particles' own mix set, not its
   neighbours' density. No fix is in the code.
4. The default gas (since 2026-12-04 it refills the holes in the gas, fluid.refill_holes, and the
   hybrid pressure weights its grid part by the share of a node the particles fill,
   fluid.hybrid_fill): no empty node inside the gas, and a nodal L1 error no worse than the
   default before (the control: fluid.refill_holes = false, fluid.hybrid_fill = 0, run here).
   Measured: 0 / 0 empty nodes (the control 29 / 54), nodal L1 0.0116 / 0.0095 against 0.0259 /
   0.0253; its particles 2.9 % / 0.7 % outside a factor 2 of the exact density (0.42-6.7 /
   0.72-3.1 of it; the control 3.8 % / 6.2 %, 0.26-1.5 / 0.016-1.0). Every particle within a
   factor 2 with the default gas (the issue's target): not reached, an expected failure; those
   outside are the wall's first three particle columns, expanded 15-20 fold where the exact gas
   is 45 fold (at 800 cells 0.4 %, 0.80-3.2).
"""
import configparser
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
from riemann import Riemann  # noqa: E402
from shocktube import bspline2  # noqa: E402

check = mt.Checks("test_wall_rarefaction")
EXACT = Riemann((1.0, -2.0, 0.4), (1.0, 2.0, 0.4), x0=0.0)
KEYS = ("regularise_every", "refill_every", "shift", "merge_light")


def strong_settings():
    """The double rarefaction's strong-expansion settings, as command-line keys."""
    ini = configparser.ConfigParser(inline_comment_prefixes=("#",))
    ini.read(mt.case("double_rarefaction.ini"))
    missing = [k for k in KEYS if k not in ini["fluid"]]
    if missing:  # the scene would silently lose a setting the bounds were measured with
        sys.exit(f"test_wall_rarefaction: double_rarefaction.ini lacks fluid.{missing[0]}")
    return [f"fluid.{k}={ini['fluid'][k]}" for k in KEYS]


def run(N, extra, tag):
    h = 3.0 / N
    out = mt.outdir(f"wall_rarefaction_N{N}_{tag}")
    mt.run(["run", mt.case("wall_rarefaction.ini"), f"output.dir={out}", f"grid.dx={1.0 / N}",
            f"domain.hi=0.5 {h}", f"geometry.all.hi=0.5 {h}", "run.progress=false"] + extra)
    return out


def measure(out, N):
    """(particle density over the exact one, nodal L1 error, empty nodes inside the gas)."""
    t, path = mt.snapshots(out)[-1]
    P = mt.particles(path, "fluid")
    x, m = P["x"][:, 0], P["m"][:, 0]
    ratio = P["rho"][:, 0] / EXACT.sample(x, t)[0]
    dx = 1.0 / N
    nodes = np.arange(0, int(round(0.5 / dx)) - 1)
    xx, mm = np.concatenate([x, -x]), np.concatenate([m, m])
    rho = np.zeros(len(nodes))
    base = np.floor(xx / dx + 0.5).astype(int)
    for off in (-1, 0, 1):
        j = base + off
        ok = (j >= 0) & (j <= nodes[-1])
        np.add.at(rho, j[ok], (bspline2(xx / dx - j) * mm)[ok])
    rho /= dx * 3 * dx
    xi = nodes * dx
    ref = EXACT.cell_averages(np.concatenate([xi - dx / 2, [xi[-1] + dx / 2]]), t)[0]
    weight = np.where(nodes == 0, 0.5 * dx, dx)
    l1 = float(np.sum(np.abs(rho - ref) * weight))
    return ratio, l1, int(np.sum((rho == 0) & (xi < x.max())))


strong = strong_settings()
print("strong-expansion settings: " + " ".join(strong))
CONTROL = ["fluid.refill_holes=false", "fluid.hybrid_fill=0"]  # the default before 2026-12-04
for N in (200, 400):
    r0, l1_0, empty_0 = measure(run(N, CONTROL, "control"), N)
    out = run(N, [], "default")
    rd, l1_d, empty_d = measure(out, N)
    out_d = float(np.mean((rd < 0.5) | (rd > 2.0)))
    check(empty_d == 0 and empty_0 > 0 and l1_d <= l1_0,
          f"N = {N}, default gas: {empty_d} empty nodes inside the gas (must be 0; the default "
          f"before {empty_0}, must be > 0), nodal L1 {l1_d:.4f} (no worse than the default "
          f"before, {l1_0:.4f}) ({mt.cost(out)})")
    check.expect_fail(out_d == 0.0,
                      f"N = {N}, default gas: every particle within a factor 2 of the exact "
                      f"density ({100 * out_d:.1f} % outside, {rd.min():.3g}-{rd.max():.3g})",
                      "the wall's first particle columns expand too little; see the header")
    out = run(N, strong, "strong")
    r, l1, empty = measure(out, N)
    out2 = float(np.mean((r < 0.5) | (r > 2.0)))
    print(f"info N = {N}, the default before: {100 * np.mean((r0 < 0.5) | (r0 > 2.0)):.1f} % of the "
          f"particles outside a factor 2, densities {r0.min():.3g}-{r0.max():.3g} of the exact; "
          f"nodal L1 {l1_0:.4f}, {empty_0} empty nodes")
    check(r.min() >= 0.2 and r.max() <= 5.0 and out2 <= 0.075,
          f"N = {N}, strong-expansion settings: densities {r.min():.3g}-{r.max():.3g} of the exact "
          f"(within 1/5 .. 5), {100 * out2:.1f} % of {len(r)} particles outside a factor 2 "
          f"(<= 7.5 %) ({mt.cost(out)})")
    check(l1 <= l1_0 and empty == 0,
          f"N = {N}, strong-expansion settings: nodal L1 {l1:.4f} (the default before {l1_0:.4f}: "
          f"no worse), {empty} empty nodes inside the gas (must be 0)")
    check.expect_fail(out2 == 0.0,
                      f"N = {N}: every particle within a factor 2 of the exact density "
                      f"({100 * out2:.1f} % outside)",
                      "the near vacuum next to the wall moves and scatters; see the header")
sys.exit(check.finish())
