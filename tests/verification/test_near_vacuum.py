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
5. The issue's acceptance with the default settings (no regularisation, full refill or
   shifting, and light merges only after the refills of holes: a copy of the case without its
   strong-expansion keys; the default refills the holes in the gas, fluid.refill_holes, and the
   hybrid pressure weights its grid part by the share of a node the particles fill,
   fluid.hybrid_fill, both since 2026-12-04; with fluid.merge_light unset the particles lighter
   than 0.125 of their cell's heaviest merge after each refill of holes that made children,
   since 2026-12-06), at 200, 400 and 800 cells:
   a. no empty node inside the gas (measured 0 / 0 / 0); the control, the same runs with
      fluid.refill_holes = false, must leave some (measured 53 / 101 / 201; 55 / 110 / 223
      before the filled share);
   b. the particle density, measured as test_sod and test_strong_shock measure theirs
      (tests/tools/shocktube.py: the particles' m / (V0 J) joined along x and averaged per
      cell), converges at an observed order >= 0.5 from 200 to 800 cells (the issue's target).
      Measured 0.0096 / 0.0049 / 0.0025, order 0.98; the control 0.0125 / 0.0234 / 0.0185, and
      the default before 2026-12-04 (neither change) 0.0185 / 0.0201 / 0.0248, which grows;
   c. the nodal density (the measure above) converges at order >= 0.5: not met, an expected
      failure. Measured 0.0245 / 0.0182 / 0.0190, order 0.19: in the fans, at 3 to 10 times the
      seeded volume, the particle columns stand one to two cells apart, unevenly (a hole is
      refilled only at two cells), and the nodal sum samples that spacing with an error that
      does not shrink as the cells do; shifting (the case's settings, order 0.56) evens it.
      Refill every step is no default: it raised Sod's L1 at 400 cells from 3.17e-3 to
      1.14e-2 (Sod's expanded gas, 1.7 particles per cell, leaves single cells empty by
      chance); docs/gas.md "Expansion" has the rest;
   d. the light merges after the refills of holes halve the steps at 800 cells at the same
      nodal error: at most 0.7 of the steps with fluid.merge_light = 0 (the control) and a nodal
      L1 at most 5 % above its. Measured 1,151 steps against 2,224, nodal L1 0.0190 against
      0.0188 (at 200 / 400 cells 355 / 625 steps against 464 / 966).
"""
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
from riemann import Riemann, cell_profile  # noqa: E402
import shocktube  # noqa: E402

check = mt.Checks("test_near_vacuum")
EXACT = Riemann((1.0, -2.0, 0.4), (1.0, 2.0, 0.4))
# The bare gas, the control: neither refill nor particle shifting.
BARE = ["fluid.refill=false", "fluid.refill_every=0", "fluid.shift=0"]
# The default settings: the case without its strong-expansion keys (unset, not set to 0: an unset
# fluid.merge_light merges the light particles after a refill of holes, and 0 turns that off).
STRONG_KEYS = ("regularise_every", "refill_every", "shift", "merge_light")


def default_case():
    """A copy of the case without its strong-expansion keys, in the working directory."""
    lines = open(mt.case("double_rarefaction.ini")).read().splitlines(keepends=True)
    keep = [ln for ln in lines if ln.split("=")[0].strip() not in STRONG_KEYS]
    if len(lines) - len(keep) != len(STRONG_KEYS):  # the case lost or renamed one of them
        sys.exit(f"test_near_vacuum: double_rarefaction.ini does not set each of {STRONG_KEYS}")
    with open("double_rarefaction_default.ini", "w") as f:
        f.writelines(keep)
    return "double_rarefaction_default.ini"


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
    nodal, particle, empties, control = [], [], [], []
    case = default_case()
    for N in (200, 400, 800):
        for holes in (True, False):
            h = 3.0 / N
            out = mt.outdir(f"near_vacuum_N{N}_default{'' if holes else '_noholes'}")
            mt.run(["run", case, f"output.dir={out}", f"grid.dx={1.0 / N}", f"domain.hi=1 {h}",
                    f"geometry.left.hi=0.5 {h}", f"geometry.right.hi=1 {h}",
                    "run.progress=false"] + ([] if holes else ["fluid.refill_holes=false"]))
            l1, empty = measure(out, N)
            t, path = mt.snapshots(out)[-1]
            P = mt.particles(path, "fluid")
            edges = np.linspace(0.0, 1.0, N + 1)
            prof = cell_profile(P["x"][:, 0], P["rho"][:, 0], edges)
            l1p = float(np.abs(prof - EXACT.cell_averages(edges, t)[0]).sum() / N)
            if not holes:
                control.append(empty)
                print(f"info N = {N}, without the hole refill: {empty} empty nodes, particle "
                      f"L1 {l1p:.4f}, nodal L1 {l1:.4f}")
                continue
            nodal.append(l1), particle.append(l1p), empties.append(empty)
            last = out
            print(f"N = {N}, default settings: particle-density L1 {l1p:.4f}, nodal L1 {l1:.4f}, "
                  f"{empty} empty nodes inside the gas ({mt.cost(out)})")
    check(max(empties) == 0 and min(control) > 0,
          f"default settings: empty nodes inside the gas {empties} at 200 / 400 / 800 cells (must "
          f"be 0); without the hole refill {control} (the control, each must be > 0)")
    order = np.log(particle[0] / particle[2]) / np.log(4.0)
    check(order >= 0.5, f"default settings: particle-density L1 {particle[0]:.4f} / "
          f"{particle[1]:.4f} / {particle[2]:.4f}, observed order 200 -> 800 {order:.2f} (>= 0.5)")
    order = np.log(nodal[0] / nodal[2]) / np.log(4.0)
    check.expect_fail(order >= 0.5,
                      f"default settings: nodal-density L1 {nodal[0]:.4f} / {nodal[1]:.4f} / "
                      f"{nodal[2]:.4f}, observed order 200 -> 800 {order:.2f} (>= 0.5)",
                      "the fans' particle columns stand 1-2 cells apart unevenly; see the header")
    # The light merges after a refill of holes (fluid.merge_light unset): the control turns them
    # off (fluid.merge_light = 0), at 800 cells.
    out = mt.outdir("near_vacuum_N800_default_nolight")
    mt.run(["run", case, f"output.dir={out}", "grid.dx=0.00125", "domain.hi=1 0.00375",
            "geometry.left.hi=0.5 0.00375", "geometry.right.hi=1 0.00375", "run.progress=false",
            "fluid.merge_light=0"])
    l1_off, _ = measure(out, 800)
    steps = [json.load(open(os.path.join(o, "summary.json")))["steps"] for o in (last, out)]
    check(steps[0] <= 0.7 * steps[1] and nodal[2] <= 1.05 * l1_off,
          f"800 cells: {steps[0]} steps with the light merges after the hole refills, {steps[1]} "
          f"without (fluid.merge_light = 0; at most 0.7 of it), nodal L1 {nodal[2]:.4f} against "
          f"{l1_off:.4f} (at most 5 % above)")
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
