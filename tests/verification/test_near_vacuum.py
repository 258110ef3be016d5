"""Gas into near vacuum: the refill of regularisation (fluid/fluid_regularise.c, fluid.refill) and
particle shifting (fluid/fluid_shift.c, fluid.shift).

Case: cases/double_rarefaction.ini, Toro's 123 problem (rho = 1, p = 0.4, u = -2 | +2, gamma
1.4) on a strip of N x 3 cells, usl, refilled and shifted every step (shift = 0.375), merged and
split every 5 steps, light particles merged at every refill (merge_light = 0.125), to t = 0.15. The exact star state is a near vacuum (rho* = 0.0219,
p* = 0.00189, 2.2 % of the initial density): a Lagrangian gas thins there to about one
particle per 45 cells. The control is the bare gas: neither refill nor shifting.

Density measure: the gas's nodal density, sum_p m_p N_i(x_p) / (dx H) with the quadratic
B-spline along x (H the strip height), at the interior nodes, against the exact solution
averaged over [x_i - dx/2, x_i + dx/2]. It is the density the method itself works with (P2G),
it is exact for particles on a regular lattice in uniform flow (the quadratic B-spline's
transform vanishes at the lattice's aliasing frequencies), and unlike the particles' own
density it does not hide an empty gap (an empty node reads 0).

Arguments: `refill` (the ordinary test), `order` (the convergence target), `default` (the
issue's target with the default settings).

refill:
1. Every event conserves mass, momentum and total energy to 1e-13 relative (momentum against
   sqrt(2 M E)), as test_regularise (the same summation-noise argument); refills happened.
   (Shifting moves positions only; test_gas_conservation checks its totals.)
2. At t = 0.15 no node between the outermost particles has zero gas mass, at N = 200 and 800.
   The bare gas leaves empty nodes (the control: measured 51 at N = 200 and 149 at N = 800): the
   check can fail.
3. The case's L1 density error is below the bare gas's at every N (measured at 200 / 800:
   0.0134 / 0.0062 against 0.0447 / 0.0380). With merges and splits every 30 steps instead of 5
   (refill and shifting every step, and no light merges, so that the refills are seen to run
   apart from the merges and splits) too: 0.0200 at 200 cells. That check caught a shift that
   emptied cells: lone particles shifted out fed a cascade of refills, 0.25 at 200 cells.
order:
4. The L1 error falls with refinement at an observed order >= 0.5 from 200 to 800 cells (the
   issue's target). Measured 0.0134, 0.0092, 0.0062 at 200, 400, 800 cells: order 0.56
   (without the light merges 0.0239, 0.0131, 0.0079, order 0.79: larger errors that fall
   faster; the light merges remove the refill chains' particles of 1e-17 of a seeded mass at
   the centre). The margin is thin: perturbed runs (output.interval 0.01 or 0.025, which moves
   the steps onto other times; time.cfl 0.38 or 0.42) gave orders 0.56, 0.46, 0.55 and 0.51
   (L1 at 800 cells 0.0065-0.0073; without the light merges 0.62-0.79, L1 0.0078-0.0094).
   merge_light 0.0625 and 0.25 gave 0.56 and 0.60.
   Without shifting (fluid.shift = 0, refill as in the case) the error falls little: 0.0220 at
   200 cells, 0.0181 at 800 (order 0.14; 0.027-0.029 at every N without the light merges),
   dominated by the rarefaction fans' low-density tails, where the particles cluster a few
   cells apart (nodal densities of 5x the exact value next to near-empty nodes); the run
   prints that control.
default:
5. The issue's acceptance with the default settings (no regularisation, refill, shifting or
   light merges: the case's keys set back to their defaults): no empty node inside the gas at
   200, 400 and 800 cells and an observed order >= 0.5 from 200 to 800. Not met, an expected
   failure: the default gas tears (measured 59 / 117 / 237 empty nodes, L1 0.0484 / 0.0492 /
   0.0509, order -0.04, with the hybrid pressure that fluid.pressure = auto takes here since
   2026-12-03; the particles' pressure: 51 / 99 / 161, L1 0.0447 / 0.0461 / 0.0385, order 0.11). Making refill every step the default was measured to break Sod (L1 at 400 cells
   3.17e-3 -> 1.14e-2: Sod's expanded gas, 1.7 particles per cell, leaves cells empty by
   chance, and their refills misplace density); docs/gas.md "Expansion" has the rest.
"""
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
from riemann import Riemann  # noqa: E402
import shocktube  # noqa: E402

check = mt.Checks("test_near_vacuum")
EXACT = Riemann((1.0, -2.0, 0.4), (1.0, 2.0, 0.4))
# The bare gas, the control: neither refill nor particle shifting.
BARE = ["fluid.refill=false", "fluid.refill_every=0", "fluid.shift=0"]
# The default settings: the case's strong-expansion keys set back to their defaults.
DEFAULTS = ["fluid.regularise_every=0", "fluid.refill_every=0", "fluid.shift=0",
            "fluid.merge_light=0"]
EVENT = re.compile(r"regularise step (\d+): (\d+) refills, (\d+) splits, (\d+) merges; "
                   r"mass (\S+) -> (\S+), momentum \((\S+), (\S+), (\S+)\) -> "
                   r"\((\S+), (\S+), (\S+)\), energy (\S+) -> (\S+)")


def run(N, refill, debug=False, extra=()):
    h = 3.0 / N
    out = mt.outdir(f"near_vacuum_N{N}_{'refill' if refill else 'none'}{len(extra)}")
    p = mt.run(["run", mt.case("double_rarefaction.ini"), f"output.dir={out}",
                f"grid.dx={1.0 / N}", f"domain.hi=1 {h}", f"geometry.left.hi=0.5 {h}",
                f"geometry.right.hi=1 {h}"] + ([] if refill else BARE) + [
                "run.progress=false"] + (["run.log_level=debug"] if debug else []) + list(extra))
    return out, p


def events(p):
    """The regularisation events of a debug run: step, refills, splits, merges, then mass,
    momentum (3) and total energy before and after."""
    return np.array([[float(v) for v in m.groups()] for m in EVENT.finditer(p.stderr)])


def conservation(ev):
    """The largest relative change per event of mass, momentum and total energy."""
    M, E = ev[:, 4], ev[:, 12]
    dM = float(np.abs(ev[:, 5] - M).max() / M.max())
    dP = float(np.abs(ev[:, 9:12] - ev[:, 6:9]).max() / np.sqrt(2 * M.max() * E.max()))
    dE = float(np.abs(ev[:, 13] - E).max() / E.max())
    return dM, dP, dE


def measure(out, N):
    """(L1 density error, empty nodes between the outermost particles) at the last snapshot."""
    return shocktube.nodal_density(out, N, EXACT)


mode = sys.argv[1] if len(sys.argv) > 1 else "refill"
if mode == "refill":
    out, p = run(200, True, debug=True)
    ev = events(p)
    dM, dP, dE = conservation(ev)
    check(ev[:, 1].sum() > 0, f"{len(ev)} events, {int(ev[:, 1].sum())} refills")
    check(max(dM, dP, dE) <= 1e-13, f"per event, largest change of mass {dM:.1e}, momentum "
          f"{dP:.1e} of sqrt(2 M E), total energy {dE:.1e} (each <= 1e-13)")
    for N in (200, 800):
        with_refill = out if N == 200 else run(N, True)[0]
        l1, empty = measure(with_refill, N)
        l1_0, empty_0 = measure(run(N, False)[0], N)
        if N == 200:
            l1_bare200 = l1_0
        check(empty == 0 and empty_0 > 0, f"N = {N}: {empty} empty nodes inside the gas with "
              f"refill (must be 0), {empty_0} without (the control, must be > 0)")
        check(l1 < l1_0, f"N = {N}: L1 density error {l1:.4f} with refill, {l1_0:.4f} without "
              f"({mt.cost(with_refill)})")
    # fluid.refill_every = 1 with merges and splits every 30 steps: the refills run apart from
    # them, every step, and conserve as before.
    out, p = run(200, True, debug=True, extra=["fluid.regularise_every=30", "fluid.refill_every=1",
                                               "fluid.merge_light=0"])
    ev = events(p)
    off = ev[ev[:, 0] % 30 != 0]
    dM, dP, dE = conservation(ev)
    l1, empty = measure(out, 200)
    check(len(off) > 0 and off[:, 1].sum() > 0 and off[:, 2:4].sum() == 0,
          f"refill_every = 1, regularise_every = 30: {len(off)} events between regularisations, "
          f"{int(off[:, 1].sum())} refills, {int(off[:, 2:4].sum())} splits and merges there "
          f"(must be 0); {len(ev) - len(off)} regularisations")
    check(max(dM, dP, dE) <= 1e-13 and empty == 0,
          f"refill_every = 1: per event mass {dM:.1e}, momentum {dP:.1e}, energy {dE:.1e} "
          f"(each <= 1e-13); {empty} empty nodes inside the gas (must be 0)")
    check(l1 < l1_bare200, f"refill_every = 1, regularise_every = 30: L1 density error {l1:.4f}, "
          f"below the bare gas's {l1_bare200:.4f}")
elif mode == "default":
    errs, empties = [], []
    for N in (200, 400, 800):
        h = 3.0 / N
        out = mt.outdir(f"near_vacuum_N{N}_default")
        mt.run(["run", mt.case("double_rarefaction.ini"), f"output.dir={out}",
                f"grid.dx={1.0 / N}", f"domain.hi=1 {h}", f"geometry.left.hi=0.5 {h}",
                f"geometry.right.hi=1 {h}", "run.progress=false"] + DEFAULTS)
        l1, empty = measure(out, N)
        errs.append(l1), empties.append(empty)
        print(f"N = {N}, default settings: L1 density error {l1:.4f}, {empty} empty nodes inside "
              f"the gas ({mt.cost(out)})")
    order = np.log(errs[0] / errs[2]) / np.log(4.0)
    check.expect_fail(max(empties) == 0 and order >= 0.5,
                      f"default settings: empty nodes inside the gas {empties} at 200 / 400 / 800 "
                      f"cells (must be 0), observed order 200 -> 800 {order:.2f} (>= 0.5)",
                      "no default treatment of near vacuum yet; see the header")
else:
    errs, bare = [], []
    for N in (200, 400, 800):
        out = run(N, True)[0]
        errs.append(measure(out, N)[0])
        print(f"N = {N}: L1 density error {errs[-1]:.4f} ({mt.cost(out)})")
    for N in (200, 800):
        bare.append(measure(run(N, True, extra=["fluid.shift=0"])[0], N)[0])
    order = np.log(errs[0] / errs[2]) / np.log(4.0)
    print(f"info without shifting: L1 {bare[0]:.4f} at 200 cells, {bare[1]:.4f} at 800: order "
          f"{np.log(bare[0] / bare[1]) / np.log(4.0):.2f}")
    check(order >= 0.5, f"observed order of the L1 density error from 200 to 800 cells: "
          f"{order:.2f} (target >= 0.5)")
sys.exit(check.finish())
