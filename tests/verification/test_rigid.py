"""Rigid bodies (material rigid): cases/rigid_push.ini, a rigid piston moving at v = 0.1
pushing into an elastic bar (E = 100, rho = 1, nu = 0, c = 10, height A = 2), bs32, to t = 2 s
(the wave reaches the free end at 2.5 s, so nothing comes back to the piston).

- The piston moves exactly at v: |x - X - v t| <= 1e-12 m (roundoff of adding h v over some
  500 steps to x ~ 4; measured about 2e-14), its velocity stays v and F stays I bitwise.
- The nodes it covers move at v: every node inside the piston's region translated by v t
  has nodal velocity exactly v in every snapshot (the rule assigns it; tolerance 0).
- The bar's momentum grows at the rate rho A c v = 2 N (per unit depth): the contact force
  of a piston driving a compression wave of particle velocity v. Slope of a straight-line
  fit over t in [0.5, 2] within 3 % of it (the front is dispersed and the contact smeared
  over about a cell; neither changes the steady force at the piston; measured 0.26 %), and
  the momentum grows at every snapshot.
- The bar's contact-side particles move with the piston: the first column (X = 4.125,
  two of its three stencil nodes per axis are held) has moved v t within 5 % at t = 2
  (the third node is free and moves a little slower; measured 1.9 %).
- On 2 ranks as on 1, by particle id, every field (classic update, a faster piston
  straddling the rank boundary at x = 16 and crossing it): equal to 1e-13 relative
  (only the order of P2G additions differs; measured 4e-15).
- In 3-D (cross-section 1 x 1, 0.5 s): the piston exact to 1e-12 m, the nodes inside it at v
  exactly, the bar's momentum growing.
- Through a periodic face (x wraps at 8, cases/rigid_push.ini with overrides, v = 0.25,
  3 s): the nodes inside the piston's wrapped region move at v exactly, the bar on the far
  side is pushed (positive momentum), and 2 ranks agree with 1 to 1e-13 (classic update).
- A restart at t = 0.5 continued to 1 ends bitwise where a straight run does (the held
  nodes follow from the restored time).
- Bad input: E or sigma_y given to a rigid body, velocity_field for a rigid body: one error
  line each naming file:line and the key, exit 2, nothing written. (nu and hardening have
  defaults, so they are accepted and ignored.)

- Under the classic updates (usl, musl, and usl with APIC), with an output every step: the
  piston moves exactly at v (1e-12 m), its v and F stay exact, and under APIC its affine
  velocity C stays 0 bitwise.
"""
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

V, RHO, AREA, C = 0.1, 1.0, 2.0, 10.0
PISTON_LO, PISTON_HI = np.array([1.0, 0.0]), np.array([4.0, 2.0])


def piston_exact(out, check, label):
    """The rigid particles against X + v t, v and F = I, in every snapshot."""
    snaps = mt.snapshots(out)
    p0 = mt.particles(snaps[0][1])
    rigid = p0["body"][:, 0] == 0
    X = p0["x"][rigid]
    err, dv, dF = 0.0, 0.0, 0.0
    for t, path in snaps:
        p = mt.particles(path)
        r = p["body"][:, 0] == 0
        err = max(err, float(np.abs(p["x"][r] - X - np.array([V * t, 0.0])).max()))
        dv = max(dv, float(np.abs(p["v"][r] - np.array([V, 0.0])).max()))
        dF = max(dF, float(np.abs(p["F"][r] - np.array([1.0, 0.0, 0.0, 1.0])).max()))
    check(err <= 1e-12, f"{label}: piston |x - X - v t| = {err:.2e} m over {len(snaps)} "
          f"snapshots (tolerance 1e-12)")
    check(dv == 0.0 and dF == 0.0, f"{label}: piston v - (v, 0): {dv:.1e}, F - I: {dF:.1e} "
          "(exactly 0)")
    return snaps


def held_nodes(snaps, lo, hi, v, period=None):
    """Nodes of the lattice inside the box [lo, hi] translated by v t (wrapped along x with
    `period` = (x0, length) if given, counting the owned lattice only) in each snapshot after
    the first: the largest count per snapshot and the largest |v_i - v| over them."""
    worst, held = 0.0, 0
    dim = len(v)
    for t, path in snaps[1:]:
        with h5py.File(path, "r") as f:
            origin, dx = f["grid"].attrs["origin"], np.ravel(f["grid"].attrs["spacing"])
            vi = f["grid/solid/v"][()]  # [nz][ny][nx][dim]
        axes = [origin[d] + dx[min(d, len(dx) - 1)] * np.arange(vi.shape[dim - 1 - d])
                for d in range(dim)]
        X = np.meshgrid(*axes[::-1], indexing="ij")[::-1]  # X[d] has the shape of vi[..., 0]
        inside = np.ones(vi.shape[:-1], dtype=bool)
        for d in range(dim):
            r = X[d] - lo[d] - v[d] * t
            if d == 0 and period:
                r = np.where((X[0] >= period[0]) & (X[0] < period[0] + period[1]),
                             np.mod(r, period[1]), -1.0)
            inside &= (r >= 0) & (r <= hi[d] - lo[d])
        held = max(held, int(inside.sum()))
        worst = max(worst, float(np.abs(vi[inside] - v).max()))
    return held, worst


def main_push(check):
    out = mt.outdir("rigid_push")
    mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}", "run.progress=false"])
    snaps = piston_exact(out, check, "bs32")

    held, worst = held_nodes(snaps, PISTON_LO, PISTON_HI, np.array([V, 0.0]))
    check(held > 0 and worst == 0.0, f"nodes inside the moving piston ({held} per snapshot): "
          f"|v_i - v| = {worst:.1e} (exactly 0)")

    # momentum of the bar
    p0 = mt.particles(snaps[0][1])
    X = p0["x"]
    ts, P, first = [], [], []
    col = (p0["body"][:, 0] == 1) & (np.abs(X[:, 0] - X[p0["body"][:, 0] == 1, 0].min()) < 1e-9)
    for t, path in snaps:
        p = mt.particles(path)
        bar = p["body"][:, 0] == 1
        ts.append(t)
        P.append(float((p["m"][bar, 0] * p["v"][bar, 0]).sum()))
        first.append(float((p["x"] - X)[col, 0].mean()))
    ts, P = np.array(ts), np.array(P)
    sel = ts >= 0.5
    slope = np.polyfit(ts[sel], P[sel], 1)[0]
    expect = RHO * AREA * C * V
    check(abs(slope / expect - 1) < 0.03, f"bar momentum rate {slope:.4f} N, rho A c v = "
          f"{expect:.4f} ({100 * (slope / expect - 1):+.2f} %, tolerance 3 %); P(2 s) = {P[-1]:.4f}")
    check(bool(np.all(np.diff(P) > 0)), "bar momentum grows at every snapshot: "
          + " ".join(f"{x:.3f}" for x in P))
    ratio = first[-1] / (V * ts[-1])
    check(abs(ratio - 1) < 0.05, f"contact column (X = {X[col, 0][0]:.3f}) moved {ratio:.4f} v t "
          "at t = 2 (tolerance 5 %)")


def main_periodic(check):
    """A piston crossing a periodic face (x in [0, 8) wraps) into the bar on the far side."""
    args = ["domain.hi=8 2", "boundary.x_lo=periodic", "boundary.x_hi=periodic",
            "geometry.piston.lo=6 0", "geometry.piston.hi=8 2", "geometry.bar.lo=0.5 0",
            "geometry.bar.hi=5 2", "solid.piston.velocity=0.25 0", "time.t_end=3",
            "output.interval=0.5", "run.progress=false"]
    out = mt.outdir("rigid_periodic")
    mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}"] + args)
    snaps = mt.snapshots(out)
    held, worst = held_nodes(snaps, [6.0, 0.0], [8.0, 2.0], np.array([0.25, 0.0]), (0.0, 8.0))
    check(held > 0 and worst == 0.0, f"periodic: nodes inside the wrapped piston ({held} per "
          f"snapshot): |v_i - v| = {worst:.1e} (exactly 0)")
    p = mt.particles(snaps[-1][1])
    bar = p["body"][:, 0] == 1
    P = float((p["m"][bar, 0] * p["v"][bar, 0]).sum())
    check(P > 0, f"periodic: the bar, pushed through the face from t = 2 s, has momentum {P:.4f} "
          "> 0 at t = 3 s")
    finals = []
    for ranks, split in ((1, "1 1"), (2, "2 1")):
        out = mt.outdir(f"rigid_periodic_np{ranks}")
        mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}", f"grid.ranks={split}",
                "time.method=usl", "output.grid_fields=false"] + args, ranks)
        finals.append(mt.particles(mt.snapshots(out)[-1][1]))
    same = np.array_equal(finals[0]["id"], finals[1]["id"])
    worst = mt.worst_difference(*finals)[0] if same else float("inf")
    check(worst <= 1e-13, f"periodic, 2 ranks vs 1 (usl): same ids {same}, fields agree to "
          f"{worst:.1e} relative (tolerance 1e-13)")


def main_3d(check):
    """The push in 3-D: a 1 x 1 cross-section, the piston moving along x at v."""
    v = np.array([V, 0.0, 0.0])
    out = mt.outdir("rigid_3d")
    mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}", "domain.dim=3",
            "domain.lo=0 0 0", "domain.hi=12 1 1", "boundary.z_lo=slip", "boundary.z_hi=slip",
            "geometry.piston.lo=1 0 0", "geometry.piston.hi=4 1 1", "geometry.bar.lo=4 0 0",
            "geometry.bar.hi=11 1 1", "solid.piston.velocity=0.1 0 0", "time.t_end=0.5",
            "run.progress=false"])
    snaps = mt.snapshots(out)
    p0 = mt.particles(snaps[0][1])
    rigid = p0["body"][:, 0] == 0
    err, P = 0.0, []
    for t, path in snaps:
        p = mt.particles(path)
        err = max(err, float(np.abs(p["x"][rigid] - p0["x"][rigid] - v * t).max()))
        bar = p["body"][:, 0] == 1
        P.append(float((p["m"][bar, 0] * p["v"][bar, 0]).sum()))
    held, worst = held_nodes(snaps, [1.0, 0.0, 0.0], [4.0, 1.0, 1.0], v)
    check(err <= 1e-12 and held > 0 and worst == 0.0 and all(np.diff(P) > 0),
          f"3-D: piston |x - X - v t| = {err:.1e} m, {held} nodes inside it at v to {worst:.1e} "
          f"(exactly 0), bar momentum growing: {' '.join(f'{x:.4f}' for x in P)}")


def main_ranks(check):
    args = ["time.method=usl", "time.t_end=1", "geometry.piston.lo=13 0",
            "geometry.piston.hi=16 2", "geometry.bar.lo=16 0", "solid.piston.velocity=0.5 0",
            "output.grid_fields=false", "run.progress=false"]
    finals = []
    for ranks, split in ((1, "1 1"), (2, "2 1")):
        out = mt.outdir(f"rigid_np{ranks}")
        mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}", f"grid.ranks={split}"] +
               args, ranks)
        finals.append(mt.particles(mt.snapshots(out)[-1][1]))
    a, b = finals
    same = np.array_equal(a["id"], b["id"])
    check(same, f"2 ranks vs 1: the same {len(a['id'])} particle ids")
    if same:
        worst, fields = mt.worst_difference(a, b)
        check(worst <= 1e-13, f"2 ranks vs 1: fields {', '.join(fields)} agree to {worst:.1e} "
              "relative (tolerance 1e-13)")


def main_bad_input(check):
    base = open(mt.case("rigid_push.ini")).read()
    piston = "velocity = 0.1 0\n"
    assert piston in base
    for name, new, key in (("E given to a rigid body", piston + "E = 1e6\n", "solid.piston.E"),
                           ("sigma_y given to a rigid body", piston + "sigma_y = 1e3\n",
                            "solid.piston.sigma_y"),
                           ("velocity_field for a rigid body", "velocity_field = 0.1; 0\n",
                            "solid.piston.velocity_field")):
        text = base.replace(piston, new)
        line = text[:text.index(new) + len(new)].count("\n")  # the last line of `new`
        mt.expect_input_error(check, name, text, key, line)


def main_restart(check):
    same, worst, fields = mt.restart_difference(mt.case("rigid_push.ini"),
                                                ["output.grid_fields=false"], 1.0, "rigid")
    check(same and worst == 0.0, f"restart at t = 0.5 and continue to 1 vs a straight run: "
          f"{', '.join(fields)} differ by {worst:.1e} (bitwise: the piston's nodes follow from "
          "the restored time)")


def main_classic(check):
    for method, transfer in (("usl", "flip"), ("musl", "flip"), ("usl", "apic")):
        out = mt.outdir(f"rigid_{method}_{transfer}")
        mt.run(["run", mt.case("rigid_push.ini"), f"output.dir={out}", f"time.method={method}",
                f"transfer.velocity={transfer}", "time.t_end=0.1", "output.interval=0.01",
                "output.grid_fields=false", "run.progress=false"])
        snaps = piston_exact(out, check, f"{method}, {transfer}, an output every 0.01 s")
        if transfer == "apic":
            worst = 0.0
            for _, path in snaps:
                p = mt.particles(path)
                worst = max(worst, float(np.abs(p["C"][p["body"][:, 0] == 0]).max()))
            check(worst == 0.0, f"{method}, apic: piston C = {worst:.1e} (exactly 0)")


check = mt.Checks("test_rigid")
main_push(check)
main_classic(check)
main_3d(check)
main_ranks(check)
main_periodic(check)
main_restart(check)
main_bad_input(check)
sys.exit(check.finish())
