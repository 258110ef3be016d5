"""A pre-stressed slab between gas columns at the same pressure stays at rest
(cases/fsi_prestress.ini; solid.NAME.initial_pressure / initial_stress, solid/solid_prestress.h).

Scene: quasi-1-D strip, 3 cells high, periodic in y, slip walls at the x ends; gas rho = 1,
p = 1 (c_g = 1.1832) | neo_hookean slab rho_s = 0.1, E = 42, nu = 0.3 (Z_s = 2.3778) seeded
with initial_pressure = 1 | gas at p. The step is held at time.dt_max = 1.5e-4, so t_end = 0.15
is 1,000 steps (the runs take 1,002-1,003: the last steps end on the output times).

Measured per run:
- speed: an upper bound of every particle's speed at every step, sqrt(2 KE_max / m_min), with
  KE from diagnostics.csv (each step) and m_min the lightest particle; over c_g. Bound 1e-10:
  the forces cancel node by node up to the roundoff of sums of O(10) terms of size p V (1e-16
  relative), which moves the particles at ~1e-16 p / Z per step, a random walk over 1,000 steps
  near 1e-12 c_g (measured: the bound 5e-13 - 1.6e-12, the largest speed in the snapshots
  3e-14 - 9e-14); the same scene without the initial stress moves at O(p / (Z_s + Z_g)) =
  0.24 c_g (its rms speed sqrt(2 KE / M), a lower bound of the largest, must exceed a tenth of
  that; measured 0.056 c_g), about nine orders above the bound.
- stress: the slab's Cauchy stress from its F (neo_hookean: (mu (b - I) + lambda ln J I) / J)
  at every snapshot, max |sigma + p I| / p <= 1e-10 (the Newton solve of F0 ends at the roundoff
  of the model's stress, eps E / p ~ 1e-14; measured 2e-14 - 3.1e-13); and the gas pressure
  max |p_gas - p| / p <= 1e-10 (measured 2e-13).
Runs: coupling.scheme velocity, contact, traction under time.method usl and the default bs32
(contact refuses bs32: its on/off switch is non-smooth for an adaptive pair; it runs usl and
musl); sharp under usl, musl and bs32, under multirate (usl and bs32), with the gauge
(physics.gauge_pressure = p, bs32), on 2 ranks and in 3-D (its
multipliers carry the interface's p0 only if its points sit on the slab's current faces: with
the reference volume's half-width they sat 3e-5 off and the gas moved at 1e-4 c_g); traction with the least-squares wall (fluid.wall_treatment); coupling.time multirate
(usl, and bs32, which is MRIStep and takes the hybrid pressure by default) and staggered
gas_first; velocity usl on 2 ranks and in 3-D (the strip 3 cells deep, periodic in z); the other models (linear_elastic, stvk, hypoelastic, j2) under velocity usl
(speed only: their stress is not in the output); the gas with fluid.pressure = hybrid under
velocity usl, traction bs32 and velocity bs32 on 2 ranks (its pressure continued through the
whole slab, the span forces there handed to it: at rest they are the negative of the slab's own
force node by node; measured 1.4e-13 - 1.6e-13 c_g).
Also: the initial total energy holds the slab's stored energy W(F0) V0 (1e-10 relative: the
same sum in C and here, roundoff only; measured 2e-13) and the coupling creates none
(|W_net| of summary.json <= 1e-10 of the solid's energy: at rest it works on roundoff
velocities; measured 1.6e-14); a restart at T/2 of a prestressed slab pushed by a pressure
difference (neo_hookean and hypoelastic, whose stress is ODE state) ends bitwise identical to
the run through; and the control above.

Known, reported not checked (XFAIL): coupling.time = staggered with coupling.order solid_first
(the default) or parallel kicks the slab at the first step (largest speed in the snapshots
0.11 c_g, the bound 0.63 c_g): the solid's first advance takes the load of the gas's previous
advance, and before the first step there is none, so the slab's -p I pushes out unopposed for
one coupling step. Curing it needs the partitioned schemes to start with the gas's load at
t = 0 (coupler/mpm_partitioned.c, mpm_interface.h: a load the gas has not yet given up).
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_prestress")
CASE = mt.case("fsi_prestress.ini")
P, C_GAS, E, NU = 1.0, (1.4 * 1.0 / 1.0) ** 0.5, 42.0, 0.3
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
TOL = 1e-10


def run(name, *extra, ranks=1):
    out = mt.outdir(name)
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"] + list(extra), ranks)
    return out


# The same scene in 3-D: the strip 3 cells deep too, periodic in z.
THREE_D = ["domain.dim=3", "domain.lo=0 0 0", "domain.hi=0.8 0.03 0.03", "boundary.z_lo=periodic",
           "boundary.z_hi=periodic",
           "geometry.left.lo=0 0 0", "geometry.left.hi=0.3 0.03 0.03",
           "geometry.slab.lo=0.3 0 0", "geometry.slab.hi=0.5 0.03 0.03",
           "geometry.right.lo=0.5 0 0", "geometry.right.hi=0.8 0.03 0.03"]


def diagnostics(out):
    return np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)


def nh_stress(F):
    J, eye = np.linalg.det(F), np.eye(F.shape[1])
    b = F @ F.transpose(0, 2, 1)
    return (MU * (b - eye) + LAM * np.log(J)[:, None, None] * eye) / J[:, None, None]


def nh_energy(F):
    J = np.linalg.det(F)
    trb = np.einsum("nij,nij->n", F, F)
    return 0.5 * MU * (trb - F.shape[1]) - MU * np.log(J) + 0.5 * LAM * np.log(J) ** 2


def measure(out):
    """(speed bound / c_g, max |sigma + p I| / p of a neo_hookean slab, max |p_gas - p| / p,
    steps)."""
    snaps = mt.snapshots(out)
    first = mt.particles(snaps[0][1])
    gas0 = mt.particles(snaps[0][1], "fluid")
    m_min = min(first["m"].min(), gas0["m"].min())
    d = diagnostics(out)
    speed = float(np.sqrt(2 * d["kinetic"].max() / m_min)) / C_GAS
    stress = pgas = 0.0
    for _, path in snaps:
        s, g = mt.particles(path), mt.particles(path, "fluid")
        dim = s["x"].shape[1]
        sig = nh_stress(s["F"].reshape(-1, dim, dim))
        stress = max(stress, float(np.abs(sig + P * np.eye(dim)).max()))
        pgas = max(pgas, float(np.abs(g["p"] - P).max()))
    return speed, stress / P, pgas / P, int(d["step"][-1])


def at_rest(label, out, stress_too=True):
    speed, stress, pgas, steps = measure(out)
    check(steps >= 1000, f"{label}: {steps} steps")
    check(speed <= TOL, f"{label}: particle speed <= {speed:.2e} c_g at every step "
          f"(bound {TOL:g})")
    if stress_too:
        check(stress <= TOL, f"{label}: slab stress max |sigma + p I| / p = {stress:.2e} "
              f"(bound {TOL:g})")
    check(pgas <= TOL, f"{label}: gas max |p - p0| / p0 = {pgas:.2e} (bound {TOL:g})")
    return speed


# ---- every spatial scheme, usl and the default pair -------------------------------------------
for scheme, method in (("velocity", "usl"), ("velocity", "bs32"), ("contact", "usl"),
                       ("contact", "musl"), ("traction", "usl"), ("traction", "bs32"),
                       ("sharp", "usl"), ("sharp", "musl"), ("sharp", "bs32")):
    out = run(f"prestress_{scheme}_{method}", f"coupling.scheme={scheme}", f"time.method={method}")
    at_rest(f"{scheme} {method}", out)
    if scheme == "velocity" and method == "usl":
        base = out
at_rest("traction usl, least-squares wall",
        run("prestress_ls", "coupling.scheme=traction", "fluid.wall_treatment=least_squares"))
at_rest("velocity usl, multirate", run("prestress_multirate", "coupling.time=multirate"))
at_rest("velocity bs32, multirate (MRIStep), the hybrid pressure (auto)",
        run("prestress_multirate_bs32", "coupling.time=multirate", "time.method=bs32",
            "time.adaptive=false"))
at_rest("sharp usl, multirate",
        run("prestress_sharp_multirate", "coupling.scheme=sharp", "coupling.time=multirate"))
at_rest("sharp bs32, multirate (MRIStep)",
        run("prestress_sharp_multirate_bs32", "coupling.scheme=sharp", "coupling.time=multirate",
            "time.method=bs32", "time.adaptive=false"))
at_rest("sharp bs32, the gauge at p",
        run("prestress_sharp_gauge", "coupling.scheme=sharp", "time.method=bs32",
            f"physics.gauge_pressure={P!r}"))
at_rest("velocity usl, 2 ranks", run("prestress_np2", ranks=2))
at_rest("sharp usl, 2 ranks", run("prestress_sharp_np2", "coupling.scheme=sharp", ranks=2))
at_rest("sharp usl, 3-D", run("prestress_sharp_3d", "coupling.scheme=sharp", *THREE_D))
at_rest("velocity usl, 3-D", run("prestress_3d", *THREE_D))
at_rest("velocity usl, the hybrid pressure", run("prestress_hybrid", "fluid.pressure=hybrid"))
at_rest("traction bs32, the hybrid pressure",
        run("prestress_hybrid_traction", "fluid.pressure=hybrid", "coupling.scheme=traction",
            "time.method=bs32"))
at_rest("velocity bs32, the hybrid pressure, 2 ranks",
        run("prestress_hybrid_np2", "fluid.pressure=hybrid", "time.method=bs32", ranks=2))
at_rest("velocity usl, staggered gas_first",
        run("prestress_gas_first", "coupling.time=staggered", "coupling.order=gas_first"))
for mat, extra in (("linear_elastic", ()), ("stvk", ()), ("hypoelastic", ()),
                   ("j2", ("solid.slab.sigma_y=10",))):
    out = run(f"prestress_{mat}", f"solid.slab.material={mat}", *extra)
    at_rest(f"{mat} velocity usl", out, stress_too=False)

# ---- the control: without the initial stress the same scene moves at O(p / Z) ------------------
# The rms speed sqrt(2 KE / M) over the whole scene is a lower bound of the largest speed.
free = run("prestress_free", "solid.slab.initial_pressure=0")
d = diagnostics(free)
rms = float(np.sqrt(2 * d["kinetic"].max() / d["mass"][0])) / C_GAS
z_speed = P / (2.3778 + 1.1832) / C_GAS
check(rms > 0.1 * z_speed, f"without the initial stress: rms speed up to {rms:.3f} c_g "
      f"(p / (Z_s + Z_g) = {z_speed:.3f} c_g; above 0.1 of it), so the at-rest checks can fail")

# ---- energy bookkeeping ------------------------------------------------------------------------
d = diagnostics(base)
s0, g0 = mt.particles(mt.snapshots(base)[0][1]), mt.particles(mt.snapshots(base)[0][1], "fluid")
stored = float((nh_energy(s0["F"].reshape(-1, 2, 2)) * s0["V0"].ravel()).sum())
gas_e = float((g0["m"].ravel() * g0["e"].ravel()).sum())
err = abs(d["internal"][0] - gas_e - stored) / stored
check(err <= TOL, f"initial internal energy = gas + slab's stored W(F0) V0 = {stored:.6e} J "
      f"(difference {err:.1e} of it; bound {TOL:g})")
with open(os.path.join(base, "summary.json")) as f:
    summ = json.load(f)
w = abs(summ["coupling_work"]) / summ["solid_energy_peak"]
check(w <= TOL, f"energy created by the coupling {summ['coupling_work']:.2e} J = {w:.1e} of the "
      f"solid's (bound {TOL:g})")

# ---- restart: a prestressed slab pushed by a pressure difference, bitwise ----------------------
for mat in ("neo_hookean", "hypoelastic"):
    push = ["gas.left.pressure=1.1", f"solid.slab.material={mat}"]
    full = run(f"prestress_full_{mat}", "output.checkpoint_interval=0.075", *push)
    rest = mt.outdir(f"prestress_restarted_{mat}")
    mt.run(["restart", os.path.join(full, "checkpoint_000001.h5"), f"output.dir={rest}"])
    a, b = (mt.particles(mt.snapshots(o)[-1][1]) for o in (full, rest))
    moved = float(np.abs(a["v"]).max())
    same = np.array_equal(a["id"], b["id"]) and all(
        np.array_equal(a[k], b[k]) for k in ("x", "v", "F", "V0"))
    check(same and moved > 1e-3, f"{mat}: restart at T/2 ends bitwise identical to the run "
          f"through (x, v, F, V0; the slab moves at up to {moved:.3f} m/s)")

# ---- known: staggered solid_first and parallel kick the slab at the first step -----------------
for order in ("solid_first", "parallel"):
    speed, _, _, _ = measure(run(f"prestress_{order}", "coupling.time=staggered",
                                 f"coupling.order={order}"))
    check.expect_fail(speed <= TOL, f"staggered {order}: speed bound {speed:.2e} c_g "
                      f"(tolerance {TOL:g})", "the first advance of the solid has no gas load; "
                      "see the docstring")

sys.exit(check.finish())
