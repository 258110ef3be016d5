"""The solid on a static refinement hierarchy (refine.levels = 2; docs/refinement.md).

The bar: a 2-D linear_elastic bar (E = 1, rho = 1, nu = 0, so plane strain is the 1-D bar and
c = 1), 145 long and 2 high, surrounded by empty grid (level 0 at dx = 1; slip faces it never
reaches). Its level-1 box (spacing 0.5) spans x = 75 .. 91 (16 cells) and the bar's whole
height with 3 cells to spare above and below, so that within the bar the coarse-fine interface
is two planes across it and the wave stays 1-D; the box keeps the 3 level-0 cells from the
domain faces the code asks for (the faces are slip walls, which a box may touch: the walls
part below refines a strip between walls).

The pulse: the velocity v = A exp(-((x - 3) / 8)^2) centred on the bar's free left end x = 3
(A = 1e-2, a strain of 5e-3): its left half reflects off the free end at once and the two leave
as one right-running pulse of amplitude A / 2 and half-width 8 coarse cells. Split into the
characteristics of the 1-D bar, R = v - c eps (right-running) and L = v + c eps (left-running;
eps = F_xx - 1), from the particles' v and F binned along x (bins of half a coarse cell,
volume-weighted means), the energy of each is proportional to the sum of its squares. At
t = 116 the pulse has crossed the box (its tail left it at t ~ 113) and the reflections of its
two interfaces travel left, clear of the free end (the entry's is centred on x ~ 30): the
reflected energy fraction is sum L^2 / sum R^2. The same bar on the uniform coarse (dx = 1) and
fine (dx = 0.5) grids gives what dispersion and the free end leave in L without an interface.

Parts (one ctest each):
wave    The reflected fraction of the refined bar (the issue's bar: below 1 %) against its
        twins'; mass and momentum in diagnostics.csv; the total energy against the twins' (the
        drift of all three is the same ~1.4e-3, lost by linear_elastic's small-strain energy
        while the pulse forms at the free end, so the check is on the change while the pulse
        crosses the box); the particle count never changes (solid particles do not split);
        and, on every snapshot of the refined run (output.grid_fields = true), the grid's mass
        and momentum summed over the active nodes of both levels against the particles', with
        nothing on the inactive nodes (part a of the brief; the snapshot at t = 0 precedes every
        deposit and is skipped).
walls   The bar filling a strip between slip walls and ending at a third, the box over its end
        touching all three: the pulse returns from the wall reversed (a fixed end), 1-D.
clamp   A bar standing on a slip wall, clamped at its base and bent by a lateral body force, on 2
        and 3 levels touching the wall: the tip deflection against the uniform grid at the
        finest spacing.
stream  A block translating at 0.5 c across the box, particles crossing the interface both ways:
        velocity, F and displacement stay exact to roundoff.
prestress A block under a uniform initial pressure held by slip walls, a box inside it: the
        particles' quadrature at the box's edges in the solid disturbs the rest state a little
        and boundedly (a limitation, measured and guarded).
usl     The same bar refined and coarse under time.method = usl (FLIP): the reflected fraction
        below the issue's bar, mass and momentum.
restart The refined bar to t = 40, restarted from its checkpoint at t = 20: bit for bit the run
        straight through.
input   Every refusal of a solid on a hierarchy: exit 2, one line naming case.ini:LINE and the
        key.
Able to fail (all measured while building them): without the solid's wall rules on the finer
level the walls part's bar leaves the domain through the wall (the run stops); without the
clamp on the finer levels the clamp part's tip deflects +282 %, and with the first node layer
above the wall held instead of the mirrored pads -3.3 % (the bound is 1.5 %).
Able to fail (both measured while building it): with the solid's deposit and gather kept on
level 0 (solid/solid_refine.c calling the plain kernel) the wave part fails its grid sums (mass
off by 10 %); with the restriction switched off (coupler/mpm_cycle.c) it fails every check but
the particle count (reflected fraction 0.35, energy +400 %), and the stream part its
translation (F - I 0.66).
"""
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

PART = sys.argv[1] if len(sys.argv) > 1 else "wave"
check = mt.Checks(f"test_refine_solid_{PART}")

from refine_scenes import (SOLID_AMP as AMP, SOLID_BOX as BOX, SOLID_LENGTH as LENGTH,  # noqa: E402
                           SOLID_WIDTH as WIDTH, SOLID_X0 as X0, solid_bar as bar)

T_WAVE = 116.0


def run(name, text):
    return mt.run_text(name, text)


def diagnostics(out):
    return np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)


def characteristics(p):
    """L = v + eps and R = v - eps (c = 1), volume-weighted means over bins of half a coarse
    cell along the bar."""
    nb = int(2 * LENGTH)
    x = p["x"][:, 0]
    k = np.clip(((x - X0) / LENGTH * nb).astype(int), 0, nb - 1)
    F = p["F"]
    vol = p["V0"].ravel() * (F[:, 0] * F[:, 3] - F[:, 1] * F[:, 2])
    w = np.bincount(k, vol, nb)
    v = np.bincount(k, vol * p["v"][:, 0], nb) / w
    eps = np.bincount(k, vol * (F[:, 0] - 1), nb) / w
    return v + eps, v - eps


def reflected_fraction(out, split=None):
    """sum L^2 / sum R^2 at the last snapshot; with split, also the parts of it from x < split
    and x >= split."""
    L, R = characteristics(mt.particles(mt.snapshots(out)[-1][1]))
    whole = float((L ** 2).sum() / (R ** 2).sum())
    if split is None:
        return whole
    k = int((split - X0) * 2)
    return whole, float((L[:k] ** 2).sum() / (R ** 2).sum()), float((L[k:] ** 2).sum() /
                                                                    (R ** 2).sum())


def grid_sums(path):
    """Relative differences of the grid's mass and momentum (active nodes of both levels) from
    the particles', and the largest mass on an inactive node."""
    with h5py.File(path, "r") as f:
        mass = f["solid/m"][()].sum()
        mom = (f["solid/m"][()] * f["solid/v"][()]).sum(axis=0)
        gm, gp, stray = 0.0, np.zeros(2), 0.0
        for lv in range(2):
            g = f[f"levels/{lv}"]
            m = (f["grid/solid/m"] if lv == 0 else g["solid/m"])[()]
            v = (f["grid/solid/v"] if lv == 0 else g["solid/v"])[()]
            act = g["active"][()].astype(bool)
            gm += m[act].sum()
            gp += (m[act][:, None] * v[act]).sum(axis=0)
            stray = max(stray, np.abs(m[~act]).max() if (~act).any() else 0.0)
    return abs(gm - mass) / mass, np.abs(gp - mom).max() / np.abs(mom).max(), stray


def part_wave():
    runs = {"refined": run("refine_solid_wave", bar(T_WAVE, BOX, interval=T_WAVE / 4,
                                                    extra="grid_fields = true\n")),
            "coarse": run("refine_solid_coarse", bar(T_WAVE, "")),
            "fine": run("refine_solid_fine", bar(T_WAVE, "", dx=0.5))}
    frac, drift = {}, {}
    for label, out in runs.items():
        d = diagnostics(out)
        frac[label] = reflected_fraction(out)
        drift[label] = abs(d["total"] - d["total"][0]).max() / d["total"][0]
        print(f"info {label}: {mt.cost(out)}; reflected energy fraction {frac[label]:.3e}; "
              f"total energy drift {drift[label]:.3e}")
    # The bar. Measured 3.7e-4 (coarse twin 2.1e-5, fine 1.5e-6): the fine-to-coarse
    # exit reflects the part of the pulse the coarse grid cannot carry, the entry far less.
    check(frac["refined"] <= 1e-2, f"reflected energy fraction {frac['refined']:.2e} <= 1e-2 "
          f"(the issue's bar; coarse twin {frac['coarse']:.1e}, fine {frac['fine']:.1e})")
    # Where it comes from: the entry's reflection is centred on x ~ 30 at t = 116, the exit's
    # on x ~ 64 (2 x_interface - 3 - t); split halfway.
    _, entry, leave = reflected_fraction(runs["refined"], 47.0)
    print(f"info refined: reflected fraction from x < 47 (the entry at x = 74.5) {entry:.2e}, "
          f"from x >= 47 (the exit at x = 91.5) {leave:.2e}")
    out = runs["refined"]
    d = diagnostics(out)
    dm = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
    dp = abs(d["px"] - d["px"][0]).max() / abs(d["px"][0])
    # Mass: constant particle masses summed in another order; momentum: a free bar's internal
    # forces sum to zero node by node, so what is left is the sums' roundoff (measured 6e-15).
    check(dm <= 1e-12 and dp <= 1e-12, f"mass drift {dm:.1e}, momentum drift {dp:.1e} <= 1e-12")
    # Energy: all three lose ~1.4e-3 while the pulse forms at the free end (t < 16; the same on
    # both grids and at time.rtol = 1e-9: not the interface, but linear_elastic's small-strain
    # energy, which its force, sigma : L with V0, conserves only to the order of the strain;
    # neo_hookean drifts 5e-5 here). What the crossing does is the change from t = 40 (the pulse
    # formed, 30 cells before the box) to the end: measured +2.4e-5 of the initial energy
    # refined, -6.6e-5 coarse and -3.4e-5 fine (bs32's slow loss).
    # 1e-4 fails on an interface that gains or loses a quarter of the reflected energy.
    window = {}
    for label, o in runs.items():
        dd = diagnostics(o)
        k = np.searchsorted(dd["t"], 40.0)
        window[label] = (dd["total"][-1] - dd["total"][k]) / dd["total"][0]
    check(abs(window["refined"]) <= 1e-4, f"total energy change from t = 40 to {T_WAVE:g}: "
          f"{window['refined']:.1e} <= 1e-4 in size (coarse twin {window['coarse']:.1e}, fine "
          f"{window['fine']:.1e}; drifts from t = 0: refined {drift['refined']:.2e}, coarse "
          f"{drift['coarse']:.2e}, fine {drift['fine']:.2e})")
    counts = set(d["particles"].astype(int))
    check(len(counts) == 1, f"solid particles never split or merge: counts {sorted(counts)}")
    worst = [0.0, 0.0, 0.0]
    snaps = mt.snapshots(out)[1:]  # the first, at t = 0, precedes every deposit
    for _, path in snaps:
        worst = [max(a, b) for a, b in zip(worst, grid_sums(path))]
    # Mass: a sum of ~1500 terms, 1e-12 relative; momentum likewise (the grid's v is m v / m).
    check(worst[0] <= 1e-12 and worst[1] <= 1e-12 and worst[2] == 0.0,
          f"grid mass and momentum on the active nodes against the particles', {len(snaps)} "
          f"snapshots: mass {worst[0]:.1e}, momentum {worst[1]:.1e} (<= 1e-12), inactive nodes "
          f"{worst[2]:.1e} (want 0)")


def part_stream():
    """A block 25 x 2 translating at 0.5 c across the box: level-0 particles enter the level-1
    region and level-1 particles leave it, each keeping its mass and volume. The composite
    basis is a partition of unity whose gradients sum to zero, so the stress-free translation
    stays exact: every velocity, F and displacement at roundoff."""
    u0, t_end = 0.5, 40.0
    text = bar(t_end, BOX).replace(f"lo = {X0} 6\nhi = {LENGTH + X0} 8", "lo = 60 6\nhi = 85 8")
    text = text.replace(f"velocity_field = {AMP}*exp(-((x-{X0})/{WIDTH})^2); 0",
                        f"velocity = {u0} 0")
    out = run("refine_solid_stream", text)
    snaps = mt.snapshots(out)
    p0, p = (mt.particles(snaps[k][1]) for k in (0, -1))
    lv0, lv = p0["level"].ravel(), p["level"].ravel()
    dv = np.abs(p["v"] - [u0, 0]).max() / u0
    dF = np.abs(p["F"] - [1, 0, 0, 1]).max()
    dx = np.abs(p["x"] - p0["x"] - [u0 * p["time"], 0]).max()
    print(f"info {mt.cost(out)}; particles that changed level: {int((lv0 != lv).sum())} of "
          f"{len(lv)} ({int(((lv0 == 1) & (lv == 0)).sum())} left level 1)")
    # Roundoff: measured 5e-17 in v, 9e-17 in F and 1.1e-12 in x (positions ~100 summed over
    # 300 steps). Without the restriction (coupler/mpm_cycle.c) F - I reaches 0.66.
    check(((lv0 == 0) & (lv == 1)).any() and ((lv0 == 1) & (lv == 0)).any(),
          "particles crossed the interface both ways")
    check(dv <= 1e-12 and dF <= 1e-12 and dx <= 1e-10,
          f"uniform translation across the levels: velocity {dv:.1e} (relative), F - I {dF:.1e}"
          f" (<= 1e-12), displacement {dx:.1e} (<= 1e-10)")


PRESTRESS = """[run]
name = refine_solid_prestress

[domain]
dim = 2
lo = 0 0
hi = 20 12

[grid]
dx = 1

[boundary]
x_lo = slip
x_hi = slip
y_lo = slip
y_hi = slip

[time]
t_end = 200

[output]
interval = 10

[geometry.all]
type = box
lo = 0 0
hi = 20 12

[solid.block]
geometry = all
material = linear_elastic
density = 1
E = 1
nu = 0.3
initial_pressure = 1e-3
{refine}"""


def part_prestress():
    """A block filling a box of slip walls under a uniform initial pressure (1e-3 E, held by the
    walls: at rest, in equilibrium), with a level-1 box whose edges and corners lie inside the
    solid. The particles' one-point quadrature of the composite basis is not exact where the
    box's edges meet in the solid (as for the gas's particle pressure, docs/refinement.md):
    the block does not stay at rest to roundoff, as its unrefined twin does, but the
    disturbance stays small and bounded (elastic waves, no growth)."""
    box = "[refine]\nlevels = 2\n\n[refine.box]\nlevel = 1\nlo = 7 4\nhi = 13 8\n"
    peak = {}
    for label, refine in (("refined", box), ("unrefined", "")):
        out = run(f"refine_solid_prestress_{label}", PRESTRESS.format(refine=refine))
        v, dF = [], []
        for _, path in mt.snapshots(out):
            p = mt.particles(path)
            v.append(np.abs(p["v"]).max())
            dF.append(np.abs(p["F"] - p["F"][0]).max())
        peak[label] = (max(v), max(dF), max(v[:len(v) // 2]), max(v[len(v) // 2:]))
        d = diagnostics(out)
        de = abs(d["total"] - d["total"][0]).max() / d["total"][0]
        print(f"info {label}: {mt.cost(out)}; largest |v| {peak[label][0]:.2e} (t <= 100: "
              f"{peak[label][2]:.2e}, after: {peak[label][3]:.2e}), |F - F0| {peak[label][1]:.2e},"
              f" total energy drift {de:.1e}")
    # Measured (ppc 2): |v| 7.1e-6 (0.6 % of c eps0, c = 1.16, eps0 ~ 1e-3), |F - F0| 1.6e-5
    # (1.6 % of the prestrain), the same before and after t = 100; 4x less with ppc = 4 (the
    # midpoint rule's h^2). The bounds, 3x the measured, fail on a growing disturbance (the
    # gas's particle pressure grew six-fold per unit time) or a worse quadrature.
    r = peak["refined"]
    check(r[0] <= 2e-5 and r[1] <= 5e-5 and r[3] <= 2 * r[2],
          f"prestressed block at rest across the box: |v| {r[0]:.1e} <= 2e-5, |F - F0| "
          f"{r[1]:.1e} <= 5e-5 over t = 200, not growing (second half {r[3]:.1e} against the "
          f"first {r[2]:.1e}); unrefined |v| {peak['unrefined'][0]:.1e}")


T_END_WALL = 190.0  # the pulse, reflected at x = 148 from t ~ 145, is centred on x ~ 103


def strip(t_end, refine, dx=1.0):
    """The bar between slip walls: the domain as high as the bar (2 level-0 cells) and ending
    at its right end, so that the walls are its faces; with `refine`, the box spans the strip
    and touches three walls."""
    text = bar(t_end, refine, dx=dx)
    return (text.replace(f"hi = {LENGTH + 2 * X0} 14", f"hi = {LENGTH + X0} 2")
            .replace(f"lo = {X0} 6", f"lo = {X0} 0").replace(f"hi = {LENGTH + X0} 8",
                                                             f"hi = {LENGTH + X0} 2"))


def part_walls():
    """The pulse along the bar filling a strip between slip walls (cases/axial_bar.ini's set-up)
    and ending at the right wall, the level-1 box over its last 18 cells touching that wall and
    both sides: the finer level folds and mirrors its nodes beyond the walls as level 0 does
    (mpm_hier_walls), so the pulse reflects from the wall as from a fixed end (its velocity
    reversed, all its energy left-running) and the wave stays 1-D."""
    box = "[refine]\nlevels = 2\n\n[refine.box]\nlevel = 1\nlo = 130 0\nhi = 148 2\n"
    runs = {"refined": run("refine_solid_walls", strip(T_END_WALL, box)),
            "coarse": run("refine_solid_walls_coarse", strip(T_END_WALL, "")),
            "fine": run("refine_solid_walls_fine", strip(T_END_WALL, "", dx=0.5))}
    res = {}
    for label, out in runs.items():
        L, R = characteristics(mt.particles(mt.snapshots(out)[-1][1]))
        v = (L + R) / 2
        vy = max(np.abs(mt.particles(path)["v"][:, 1]).max() for _, path in mt.snapshots(out))
        res[label] = (float((R ** 2).sum() / (L ** 2).sum()), v, vy)
        print(f"info {label}: {mt.cost(out)}; after the wall: right-running energy over "
              f"left-running {res[label][0]:.2e}, velocity min {v.min():.3e} max {v.max():.3e};"
              f" largest |v_y| {vy:.1e}")
    ref, fine = res["refined"], res["fine"]
    # A fixed end reverses the velocity: the returned pulse is -A/2 = -5e-3 at its peak
    # (measured -4.67e-3; coarse twin -4.62e-3, fine -4.99e-3), and a pulse that left the wall
    # runs left only (measured 6.4e-4 of its energy the wrong way, mostly from crossing the
    # box twice, as the wave part's 3.7e-4; coarse 1.3e-5, fine 1.4e-6; the bound is the
    # issue's 1 %). Without the finer level's wall rules for the solid the bar's end passes
    # through the wall and the run stops.
    check(ref[0] <= 1e-2 and ref[1].min() < -0.45 * AMP,
          f"walls: the pulse returns from the wall reversed, {ref[1].min():.2e} (want below "
          f"{-0.45 * AMP:.1e}), right-running energy {ref[0]:.1e} <= 1e-2 of the left-running "
          f"(coarse twin {res['coarse'][0]:.1e}, fine {fine[0]:.1e})")
    # A slip wall leaves the tangential velocity free and the bar (nu = 0) has no transverse
    # force: v_y stays at roundoff of the pulse's 1e-2 on both levels.
    check(ref[2] <= 1e-13, f"walls: largest |v_y| {ref[2]:.1e} <= 1e-13 (the wave stays 1-D; "
          f"coarse twin {res['coarse'][2]:.1e})")
    # A wall does no work: the total energy from t = 40 (the pulse formed at the free end, see
    # the wave part) to the end changes as little as on the uniform grids (bs32's slow loss),
    # through the box, the wall and back. 1e-4, as the wave part's bound.
    window = {}
    for label, o in runs.items():
        d = diagnostics(o)
        k = np.searchsorted(d["t"], 40.0)
        window[label] = (d["total"][-1] - d["total"][k]) / d["total"][0]
    check(abs(window["refined"]) <= 1e-4, f"walls: total energy change from t = 40 to "
          f"{T_END_WALL:g}: {window['refined']:.1e} <= 1e-4 in size (coarse twin "
          f"{window['coarse']:.1e}, fine {window['fine']:.1e})")


CANTILEVER = """[run]
name = refine_solid_clamp

[domain]
dim = 2
lo = 0 0
hi = 21 10

[grid]
dx = {dx}

[boundary]
x_lo = slip
x_hi = slip
y_lo = slip
y_hi = slip

[physics]
gravity = 0.1 0
damping = 8

[time]
t_end = 3
method = usl

[output]
interval = 3

[geometry.bar]
type = box
lo = 10 0
hi = 11 5

[geometry.base]
type = box
lo = 10 -1e-6
hi = 11 0

[solid.bar]
geometry = bar
material = linear_elastic
density = 1
E = 1e4
nu = 0

[clamp.base]
geometry = base
{refine}"""


def tip_deflection(out):
    """The mean x displacement of the bar's top particle row at the last snapshot."""
    snaps = mt.snapshots(out)
    x0, x1 = mt.particles(snaps[0][1])["x"], mt.particles(snaps[-1][1])["x"]  # (sorted by id)
    top = x0[:, 1] > x0[:, 1].max() - 0.3
    return float((x1 - x0)[top, 0].mean())


def part_clamp():
    """The main job's arrangement without the gas: a bar standing on the y_lo slip wall, clamped
    at its base ([clamp.base] below the wall, as cases/supersonic_bar.ini), bent by a lateral
    body force and damped to rest (t = 3 is 12 decay times of the damping and 2 periods of the
    first bending mode), with the finer levels around the bar touching the wall. On a finer
    level the wall lies between two node layers: the clamp mirrors the layer beyond it with
    every component negated (zero velocity on the wall), as level 0 holds its wall node. The
    tip deflection against the uniform grid at the finest spacing."""
    two = ("[refine]\nlevels = 2\n\n[refine.box]\nlevel = 1\nlo = 8 0\nhi = 13 7\n")
    three = ("[refine]\nlevels = 3\n\n[refine.a]\nlevel = 1\nlo = 7 0\nhi = 14 8\n\n"
             "[refine.b]\nlevel = 2\nlo = 9 0\nhi = 12 6\n")
    tip = {}
    for label, dx, refine in (("coarse", 0.5, ""), ("2 levels", 0.5, two),
                              ("fine 0.25", 0.25, ""), ("3 levels", 0.5, three),
                              ("fine 0.125", 0.125, "")):
        out = run("refine_solid_clamp_" + label.replace(" ", "_"),
                  CANTILEVER.format(dx=dx, refine=refine))
        tip[label] = tip_deflection(out)
        print(f"info {label}: {mt.cost(out)}; tip deflection {tip[label]:.5f}")
    # Euler-Bernoulli: q L^4 / (8 E I) = 1.5 rho g H^4 / (E w^2) = 9.375e-3 (a stubby bar,
    # H / w = 5: Timoshenko's shear adds ~3 %).
    print(f"info Euler-Bernoulli 9.375e-3; the uniform grids {tip['coarse']:.5f} (0.5), "
          f"{tip['fine 0.25']:.5f} (0.25), {tip['fine 0.125']:.5f} (0.125)")
    # Measured -0.6 % (2 levels) and -0.2 % (3 levels) from the uniform twin at the finest
    # spacing, where the coarse grid is +5 % off. Holding the finer level's first node layer
    # above the wall instead (level 0's rule taken literally) stiffened the root: -3.3 %.
    for levels, twin in (("2 levels", "fine 0.25"), ("3 levels", "fine 0.125")):
        rel = tip[levels] / tip[twin] - 1
        check(abs(rel) <= 0.015, f"clamp: {levels} tip deflection {tip[levels]:.5f}, "
              f"{rel:+.1%} from the uniform grid at its finest spacing (|.| <= 1.5 %; the "
              f"coarse grid {tip['coarse'] / tip[twin] - 1:+.1%})")
    # The same 2-level run with the whole scene 0.15 higher (the floor at y = 0.15, where the
    # midpoint of two level-1 nodes missed the wall by a rounding step and the clamp caught
    # nothing, +282 %, until the wall's own coordinate was taken): the same tip to roundoff.
    up = (CANTILEVER.format(dx=0.5, refine=two.replace("lo = 8 0", "lo = 8 0.15")
                            .replace("hi = 13 7", "hi = 13 7.15"))
          .replace("lo = 0 0\nhi = 21 10", "lo = 0 0.15\nhi = 21 10.15")
          .replace("lo = 10 0\nhi = 11 5", "lo = 10 0.15\nhi = 11 5.15")
          .replace("lo = 10 -1e-6\nhi = 11 0\n", "lo = 10 0.149999\nhi = 11 0.15\n"))
    shifted = tip_deflection(run("refine_solid_clamp_shifted", up))
    check(abs(shifted / tip["2 levels"] - 1) <= 1e-6, f"clamp: the scene 0.15 higher, 2 levels: "
          f"tip deflection {shifted:.5f} against {tip['2 levels']:.5f} (the same to 1e-6)")


def part_usl():
    """The same bar under the classic update (time.method = usl, FLIP): the reflected fraction
    against the coarse twin's, and mass and momentum."""
    usl = "[time]\nt_end = {0}\nmethod = usl".format(T_WAVE)
    runs = {"refined": run("refine_solid_usl", bar(T_WAVE, BOX).replace(
                f"[time]\nt_end = {T_WAVE}", usl)),
            "coarse": run("refine_solid_usl_coarse", bar(T_WAVE, "").replace(
                f"[time]\nt_end = {T_WAVE}", usl))}
    frac = {label: reflected_fraction(out) for label, out in runs.items()}
    for label, out in runs.items():
        print(f"info {label}: {mt.cost(out)}; reflected energy fraction {frac[label]:.3e}")
    # Measured 5.8e-5 against the coarse twin's 1.5e-4 (the refined run takes the fine level's
    # step, which the classic update's error follows); the bar.
    check(frac["refined"] <= 1e-2, f"usl: reflected energy fraction {frac['refined']:.2e} <= "
          f"1e-2 (coarse twin {frac['coarse']:.1e})")
    d = diagnostics(runs["refined"])
    dm = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
    dp = abs(d["px"] - d["px"][0]).max() / abs(d["px"][0])
    check(dm <= 1e-12 and dp <= 1e-12, f"usl: mass drift {dm:.1e}, momentum drift {dp:.1e} "
          f"<= 1e-12")


def part_restart():
    text = bar(40, BOX)
    out = mt.outdir("refine_solid_restart")
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(text)
    same, worst, _ = mt.restart_difference(path, [], 40, "refine_solid_restart")
    check(same and worst == 0.0, f"restarted at t = 20: worst difference {worst:.1e} (want 0)")


def part_input():
    refined = bar(1, BOX)
    body = "[solid.bar]\n"
    cases = [
        ("time.method = musl", refined.replace("t_end = 1", "t_end = 1\nmethod = musl"),
         "time.method", "method = musl", "not carried"),
        ("bulk viscosity", refined.replace(body, body + "bulk_viscosity_linear = 0.06\n").replace(
            "t_end = 1", "t_end = 1\nmethod = usl"),
         "solid.bar.bulk_viscosity_linear", "bulk_viscosity_linear", "not carried"),
        ("rigid body", refined.replace("material = linear_elastic", "material = rigid").replace(
            "E = 1\nnu = 0\n", "").replace(f"velocity_field = {AMP}*exp(-((x-{X0})/{WIDTH})^2); 0",
                                            "velocity = 0 0"),
         "solid.bar.material", "material = rigid", "not carried"),
        ("odd ppc", refined.replace(body, body + "ppc = 3\n"), "solid.bar.ppc", "ppc = 3",
         "even"),
        ("traction in the box", refined + "\n[geometry.band]\ntype = box\nlo = 80 7.6\n"
         "hi = 82 8\n\n[traction.top]\ngeometry = band\nvalue = 0 -1e-3\n",
         "traction.top.geometry", "geometry = band", "level-0 particles only"),
        ("dynamic regrid", refined.replace("levels = 2", "levels = 2\ncriterion = density\n"
                                           "threshold = 0.01").replace(
            "\n[refine.box]\nlevel = 1\nlo = 75 3\nhi = 91 11\n", ""),
         "refine.criterion", "criterion = density", "static boxes"),
        ("box near a closed face", refined.replace("y_lo = slip", "y_lo = none").replace(
            "lo = 75 3", "lo = 75 2"), "refine.box.lo", "lo = 75 2", "act on level 0 only"),
    ]
    gas = ("\n[geometry.air]\ntype = box\nlo = 110 9\nhi = 140 13\n\n[gas.air]\n"
           "geometry = air\ndensity = 1\npressure = 1\n")
    cases.append(("a gas beside the solid in a box that spans no periodic axis",
                  refined.replace("[refine]", gas + "\n[refine]"), "refine.box.lo", "lo = 75 3",
                  "periodic axis"))
    for name, text, key, start, words in cases:
        mt.expect_input_error(check, name, text, key, mt.line_starting(text, start), words)


if PART == "wave":
    part_wave()
elif PART == "stream":
    part_stream()
elif PART == "prestress":
    part_prestress()
elif PART == "walls":
    part_walls()
elif PART == "clamp":
    part_clamp()
elif PART == "usl":
    part_usl()
elif PART == "restart":
    part_restart()
elif PART == "input":
    part_input()
else:
    raise SystemExit(f"unknown part {PART}")
sys.exit(check.finish())
