"""Sod shock tube (validation/sod_exact_star_state.csv; cases/sod.ini).

gamma = 1.4, (rho, u, p) = (1, 0, 1) | (0.125, 0, 0.1), diaphragm at x0 = 0.5, t = 0.2, on a
strip of N x 3 cells periodic in y with slip walls at x = 0 and 1 (the waves do not reach
them). Reference: the exact Riemann solver of tests/tools/riemann.py, itself checked here
against the star state and wave positions of the validation CSV (to 2e-6 relative: the CSV
gives six significant digits).

Density measure and shock position: see tests/tools/shocktube.py (particle densities joined
by linear interpolation, averaged per cell, against the exact cell averages).

Acceptance, checked for the case's own method and step (cases/sod.ini: usl at time.cfl 0.9,
with the hybrid pressure that fluid.pressure = auto picks for it):
  - issue 4: L1 <= 8e-3 at 400 cells, observed order >= 0.8 from 100 to 800 cells (log2 of the
    L1 ratio over the doublings, divided by their count), shock within 2 cells of x = 0.8504;
  - issue 50: the order stays >= 0.8 up to 1600 cells, over 800 -> 1600 alone too (measured
    1.05 / 1.01 / 1.04 per doubling from 200 cells, L1 2.08e-3 at 400 and 5.03e-4 at 1600; bs32
    with the particles' pressure, the default before, gave order 0.35 over 800 -> 1600 and
    fails it: its L1 1.79e-3 -> 1.40e-3).
The default run (fast) checks the case's method at 100 and 200 cells: the shock within 2 cells;
L1 at 200 cells <= 1.6e-2 (the 400-cell bound under the first-order convergence shocks allow,
since shocks and contacts limit any method to first order in L1); order 100 -> 200 >= 0.8. It
checks usl and musl at their documented 0.4 and bs32 at the case's step, at 200 cells, the same
way, that mass is constant (to the 1e-14 of summing in another order after particle sorts) and,
with the walls at rest, that usl and musl conserve total energy to 1e-12 (relative; their
transfer, with the hybrid's pressure too, is exactly energy-conserving: roundoff over ~400
steps stays near 1e-14). It prints the particles' pressure at 200 cells beside it (info).
2 ranks (split along x, so the shock and the contact cross the rank boundary) vs 1: usl and
musl take the same fixed steps, so every particle field must agree to 1e-12 relative (sums in
another order). So does bs32 at its fixed step. Adaptive steps followed the global error
norm, whose sum in another order moves a step by roundoff (measured 9.3e-13 then, under a
tolerance of 1e-10); its RHS is a function of the state alone (the artificial viscosity takes
the current strain rate, fluid.strain_rate = current), so that moves the solution by roundoff
too. (With the strain rate of the previous step, the default before, the particles differed
by 6e-4: the step sequence changed the solution at first order.)
`long` adds 400, 800 and 1600 cells for the case's method and checks both acceptances; it runs
usl and musl at 0.4 and bs32 at 400 and 800 cells, checks L1 at 400 and the shock position,
and prints their orders (docs/verification.md).
"""
import configparser
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

check = mt.Checks("test_sod")
LONG = len(sys.argv) > 1 and sys.argv[1] == "long"
LEFT, RIGHT, T = (1.0, 0.0, 1.0), (0.125, 0.0, 0.1), 0.2
EXACT = Riemann(LEFT, RIGHT, gamma=1.4, x0=0.5)
FV_L1_400 = 1.3e-3  # second-order finite-volume Godunov scheme at 400 cells (issue 4)

# validation/sod_exact_star_state.csv
CSV = {"p_star": 0.303130, "u_star": 0.927453, "rho_star_L": 0.426319, "rho_star_R": 0.265574,
       "shock_speed": 1.752156, "x_shock_t0.2": 0.850431, "x_contact_t0.2": 0.685491}
mine = {"p_star": EXACT.p_star, "u_star": EXACT.u_star, "rho_star_L": EXACT.r_star_l,
        "rho_star_R": EXACT.r_star_r, "shock_speed": EXACT.s_r,
        "x_shock_t0.2": EXACT.shock_position(T), "x_contact_t0.2": EXACT.contact_position(T)}
worst = max(abs(mine[k] - v) / abs(v) for k, v in CSV.items())
check(worst <= 2e-6, f"exact solver vs the validation CSV: largest relative difference {worst:.1e} "
      "(<= 2e-6)")


def run(N, method, ranks=1, extra=()):
    return shocktube.run("sod.ini", N, method, T, ranks, ["output.interval=0.2"] + list(extra))


def measure(out, N):
    return shocktube.measure(out, N, EXACT, T)


def conservation(out, method):
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    dm = abs(d["mass"][-1] - d["mass"][0]) / d["mass"][0]
    dE = float(np.abs(d["total"] - d["total"][0]).max() / d["total"][0])
    # Particle masses never change; only the order of the sum does (particles are sorted).
    check(dm <= 1e-14, f"{method}: mass change {dm:.1e} (<= 1e-14, summation order)")
    if method in ("usl", "musl"):
        check(dE <= 1e-12, f"{method}: total energy drift {dE:.1e} with walls at rest (<= 1e-12)")
    else:
        print(f"info {method}: total energy drift {dE:.1e} (time-integration error)")


def study(method, Ns, acceptance, extra=()):
    res = {}
    for N in Ns:
        out = run(N, method, extra=extra)
        l1, xs, _ = measure(out, N)
        res[N] = (l1, xs)
        off = (xs - EXACT.shock_position(T)) * N
        check(abs(off) <= 2.0, f"{method} N={N}: L1 {l1:.3e}, shock at {xs:.5f} ({off:+.2f} cells; "
              "within 2)")
        if N == 200:
            conservation(out, method)
            check(l1 <= 1.6e-2, f"{method} N=200: L1 {l1:.3e} <= 1.6e-2")
        if N == 400:
            check(l1 <= 8e-3, f"{method} N=400: L1 {l1:.3e} <= 8e-3; ratio to the finite-volume "
                  f"1.3e-3: {l1 / FV_L1_400:.2f}")
    if len(Ns) < 2:
        return res
    order = np.log2(res[Ns[0]][0] / res[Ns[-1]][0]) / np.log2(Ns[-1] / Ns[0])
    msg = f"{method}: observed order {order:.2f} from N={Ns[0]} to {Ns[-1]} (L1 " + ", ".join(
        f"{res[N][0]:.3e}" for N in Ns) + ")"
    if acceptance:
        check(order >= 0.8, msg + " (>= 0.8)")
    else:
        print("info " + msg)
    return res


# The case's own method at its own step (shocktube.run gives usl and musl their documented
# 0.4 unless told otherwise).
CASE = configparser.ConfigParser()
CASE.read(mt.case("sod.ini"))
DEFAULT, DEFAULT_CFL = CASE["time"]["method"], CASE["time"]["cfl"]
res = study(DEFAULT, (100, 200, 400, 800, 1600) if LONG else (100, 200), True,
            [f"time.cfl={DEFAULT_CFL}"])
if LONG:
    o = np.log2(res[800][0] / res[1600][0])
    check(o >= 0.8, f"{DEFAULT} (the case's): order {o:.2f} from 800 to 1600 cells (>= 0.8)")
for method in ("usl", "musl", "bs32"):
    study(method, (200, 400, 800) if LONG else (200,), False)
l1p, _, _ = measure(run(200, DEFAULT, extra=[f"time.cfl={DEFAULT_CFL}",
                                              "fluid.pressure=particle"]), 200)
print(f"info {DEFAULT} at time.cfl {DEFAULT_CFL} with the particles' pressure: L1 {l1p:.3e} at "
      "200 cells")

# 2 ranks (split along x at 0.5: the contact and the shock cross the boundary) vs 1.
for method in ("usl", "musl", "bs32"):
    a = measure(run(200, method), 200)
    b = measure(run(200, method, 2, ["grid.ranks=2 1"]), 200)
    pa, pb = a[2], b[2]
    if not np.array_equal(pa["id"], pb["id"]):
        check(False, f"{method} 2 ranks: particle ids differ from 1 rank")
        continue
    diff, _ = mt.worst_difference(pa, pb)
    check(diff <= 1e-12, f"{method} 2 ranks vs 1, by id, every field: largest relative "
          f"difference {diff:.1e} (<= 1e-12)")

sys.exit(check.finish())
