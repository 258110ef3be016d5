"""Turek & Hron CSM1 (validation/turek_hron_csm1.csv; cases/csm1.ini): static deflection of
the CSM3 bar under gravity, reached by mass-proportional damping (alpha = 14 1/s, critical
for the first mode; the case file gives the argument).

Tip A. A is the material point (0.6, 0.2), the centre of the free end. No particle sits
there: the nearest ones lie dx / (2 ppc) inside the end face, dx / (2 ppc) above and below
the mid-line. Each of these two is carried to A by a first-order Taylor step with its own
deformation gradient, x_A = x_p + F_p (X_A - X_p), and the two estimates are averaged; being
symmetric about the mid-line, the average also cancels the second-order term across the
thickness. (The bare mean displacement of the pair is off by the tip rotation, 0.27 rad,
times dx / 4: 0.3 mm or 0.5 % at dx = 5 mm; printed for comparison.)

Convergence to the static state, checked for every run over the last 0.3 s (three snapshot
intervals):
- the tip moved by less than 2e-4 of its displacement. The slowest transient left decays by
  a factor 0.3 to 0.8 per 0.3 s (measured), so what remains after t_end is at most a few
  times this, far below the 2 % tolerance (the stopping error must not eat the tolerance);
- the kinetic energy is below 1e-8 of the strain energy (measured 1e-9 or less). With the
  pure FLIP update this would not be reachable: particle velocity modes that P2G does not
  see keep about 1e-4 of the strain energy on the bar's surface particles and the grid
  damping cannot remove them; the case blends in 5 % PIC, which removes them and moves the
  static tip by 0.03 % (measured at dx = 5 and 2.5 mm).

Default (fast) selection:
1. dx = 10 mm (2 cells through the thickness), t_end = 6 s (the coarse grid settles more
   slowly): the convergence criteria above, and tip uy within 15 % of the reference. The
   grid is coarse (measured +8.9 % at 10 mm): this checks the machinery (gravity, damping,
   clamp, material); the accuracy check is the long test.
2. 2 ranks vs 1 by particle id, every field, dx = 5 mm, first 0.02 s (550 steps, damping
   and the PIC blend active, the bar across the rank boundary): tolerance 1e-12 relative
   to each field's scale, i.e. roundoff (only the order of P2G additions differs).

Long (`long [shape] [dx ...]`, default cubic 0.005 0.0025): the issue's acceptance at the
finest dx: tip uy within 2 % of -66.10 mm, ux within 5 % of -7.188 mm; and the observed
order of the uy error between successive resolutions at least 0.7 (first order is expected
from the clamp's node-based edge). Measured (usl, cubic), with the clamp holding the nodes
within half a cell of the cylinder (solid_module.c, clamps_node):
  dx = 5 mm: uy -67.63 (+2.32 %), ux -7.513 (+4.52 %)
  dx = 2.5 mm: uy -66.81 (+1.07 %), ux -7.331 (+1.99 %); orders 1.12 (uy), 1.19 (ux)
Before that rule the clamp held only the nodes strictly inside the cylinder, the effective
root lay about a cell inside it, and the errors were first order with a large constant:
cubic +8.0 % / +3.2 % (uy), +14.9 % / +5.8 % (ux) at 5 / 2.5 mm, met only at 1.25 mm.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_csm1")
A = np.array([0.6, 0.2])
REF = np.array([-7.188, -66.10])  # mm
TOL = np.array([0.05, 0.02])      # the tolerances for ux, uy


def tip_history(out):
    """Times and tip A displacement (mm, by the Taylor step; and the bare pair mean)."""
    snaps = mt.snapshots(out)
    X = mt.particles(snaps[0][1])["x"]
    end = np.isclose(X[:, 0], X[:, 0].max())
    off = np.abs(X[:, 1] - A[1])
    pair = end & np.isclose(off, off[end].min())
    assert pair.sum() == 2, "expected two particles nearest the tip's mid-line"
    t, u, bare = [], [], []
    for time, path in snaps:
        p = mt.particles(path)
        F = p["F"][pair].reshape(-1, 2, 2)
        xa = p["x"][pair] + np.einsum("pij,pj->pi", F, A - X[pair])
        t.append(time)
        u.append(1e3 * (xa.mean(axis=0) - A))
        bare.append(1e3 * (p["x"][pair] - X[pair]).mean(axis=0))
    return np.array(t), np.array(u), np.array(bare)


def static_tip(dx, shape="quadratic", extra=()):
    """Run to the static state; check convergence; return tip (ux, uy) in mm."""
    out = mt.outdir(f"csm1_{shape}_dx{dx}")
    mt.run(["run", mt.case("csm1.ini"), f"output.dir={out}", f"grid.dx={dx}",
            f"grid.shape={shape}", "run.progress=false"] + list(extra))
    t, u, bare = tip_history(out)
    k = np.searchsorted(t, t[-1] - 0.3 - 1e-9)
    drift = abs(u[-1, 1] - u[k, 1]) / abs(u[-1, 1])
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    ke = d["kinetic"][-1] / d["internal"][-1]
    check(drift < 2e-4 and ke < 1e-8,
          f"{shape} dx = {dx}: static by t = {t[-1]:g} s: tip uy moved {drift:.1e} of itself "
          f"over the last {t[-1] - t[k]:.1f} s (< 2e-4), kinetic / strain energy {ke:.1e} "
          "(< 1e-8)")
    err = u[-1] / REF - 1.0  # > 0: deflects too far
    print(f"info {shape} dx = {dx}: tip A ux {u[-1, 0]:.4f} mm ({100 * err[0]:+.2f} %), "
          f"uy {u[-1, 1]:.4f} mm ({100 * err[1]:+.2f} %); bare mean of the two nearest "
          f"particles ux {bare[-1, 0]:.4f}, uy {bare[-1, 1]:.4f} mm")
    return u[-1]


def ranks_agree():
    mt.check_ranks_agree(check, mt.case("csm1.ini"), ["time.t_end=0.02", "output.interval=0.02"],
                         "csm1")


if len(sys.argv) > 1 and sys.argv[1] == "long":
    shape = sys.argv[2] if len(sys.argv) > 2 else "cubic"
    dxs = sys.argv[3:] or ["0.005", "0.0025"]
    tips = [static_tip(dx, shape) for dx in dxs]
    errs = [np.abs(u - REF) / np.abs(REF) for u in tips]
    for k in range(len(dxs) - 1):
        r = float(dxs[k]) / float(dxs[k + 1])
        order = np.log(errs[k] / errs[k + 1]) / np.log(r)
        print(f"info observed order dx {dxs[k]} -> {dxs[k + 1]}: ux {order[0]:.2f}, "
              f"uy {order[1]:.2f}")
        check(order[1] >= 0.7, f"{shape}: uy error falls from {100 * errs[k][1]:.2f} % to "
              f"{100 * errs[k + 1][1]:.2f} %, observed order {order[1]:.2f} (>= 0.7)")
    u, e = tips[-1], errs[-1]
    check(e[1] <= TOL[1], f"{shape} dx = {dxs[-1]}: tip uy {u[1]:.3f} mm vs -66.10 "
          f"({100 * e[1]:.2f} %, tolerance 2 %)")
    check(e[0] <= TOL[0], f"{shape} dx = {dxs[-1]}: tip ux {u[0]:.4f} mm vs -7.188 "
          f"({100 * e[0]:.2f} %, tolerance 5 %)")
else:
    u = static_tip("0.01", extra=["time.t_end=6", "output.interval=0.3"])
    e = u[1] / REF[1] - 1.0
    check(abs(e) < 0.15, f"dx = 10 mm: tip uy {u[1]:.2f} mm vs -66.10 ({100 * e:+.1f} %, "
          "tolerance 15 % on this coarse grid)")
    ranks_agree()
sys.exit(check.finish())
