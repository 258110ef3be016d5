"""Strong shock tube (Toro's test 3; cases/strong_shock.ini).

gamma = 1.4, (rho, u, p) = (1, 0, 1000) | (1, 0, 0.01), diaphragm at x0 = 0.5, t = 0.012: a
pressure ratio of 1e5; the shock runs at 23.5 into gas whose sound speed is 0.12 (Mach about
200) and compresses it sixfold. Exact solution from tests/tools/riemann.py; density measure
and shock position as in test_sod (tests/tools/shocktube.py).

Checks (issue 4): the run is stable (it reaches t = 0.012; an unphysical state would stop it
with an error), density and pressure are positive at every particle in every snapshot, and
the shock lies within 3 cells of the exact position x = 0.7822. The L1 density error is
reported. With the walls at rest the classic updates usl and musl must also conserve total
energy to 1e-12 (relative): this case stresses the exact energy balance with kinetic and
internal energies that differ by orders of magnitude between the two states.
Default: 200 cells for bs32 (at the case's fixed step), usl and musl (at time.cfl = 0.4), and
the case as it stands at 400 cells (usl at time.cfl = 0.9 with the hybrid pressure that
fluid.pressure = auto picks; issue 50: L1 <= 2.23e-2 with the shock within 1 cell; measured
2.004e-2 and +0.32 cells; fixed bs32 at 0.99 with fluid.mol_damping = 0.3, the case before
2026-12-04, 1.879e-2 and +0.16 cells in 4.7x the wall time; fixed bs32 at 0.8 without the
damping and with the particles' pressure, the case before 2026-12-02, gave 2.255e-2 and fails
it. The bound is the issue's own, no margin added: the runs are deterministic to roundoff).
`long`: 100, 200, 400 and 800 cells, where the L1 error of every method must also fall from 200
to 800 cells (by at least 25 %, well short of the 50 % of first order, since the shock in L1
converges at first order at best). With the particles' pressure usl's L1 stalled there (3.03e-2
at 200 cells, 2.53e-2 at 400, 2.79e-2 at 800): particle velocity noise that its exact energy
balance turns into heat, from the particles' quadrature of the pressure once they leave their
lattice (docs/gas.md); with the hybrid it falls (2.97e-2, 2.13e-2, 1.33e-2).

Galilean invariance (issue 50): Toro's test 5, test 3 in a frame moving at -19.6 so that the
gas crosses the grid at 19.6 (bench/fv_strip.py, toro3_moving: outflow and inflow faces), under
the case's method and settings, against the same problem at rest: L1(moving) / L1(at rest) <=
1.25 at 400 cells (default) and at 800 (long), and the ratio must not grow from 400 to 800 by
more than 0.1 (the issue: "the gap does not grow with refinement"; the particles' pressure, the
default before, gave 1.31 / 1.51 / 2.27 at 200 / 400 / 800: the hot expanded gas at rest on the
grid behind the rarefaction drifted off its lattice and the particles' quadrature of its
uniform pressure pushed it about). Measured with the hybrid pressure: under the case's usl at
0.9, 1.063 at 400 and 0.982 at 800 (bench/bench_galilean.py); under fixed bs32 at 0.99 with the
damping, the case before, 0.997 and 0.974.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

sys.path.insert(0, os.path.join(os.path.abspath(mt.SOURCE), "bench"))
import fv_strip  # noqa: E402

check = mt.Checks("test_strong_shock")
LONG = len(sys.argv) > 1 and sys.argv[1] == "long"
T = 0.012
EXACT = Riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), gamma=1.4, x0=0.5)
XS = EXACT.shock_position(T)
print(f"info exact: p* = {EXACT.p_star:.4f}, u* = {EXACT.u_star:.5f}, rho*_R = "
      f"{EXACT.r_star_r:.4f}, shock at {XS:.5f}")


def positive(out):
    rho_min = p_min = np.inf
    for _, path in mt.snapshots(out):
        P = mt.particles(path, "fluid")
        rho_min, p_min = min(rho_min, P["rho"].min()), min(p_min, P["p"].min())
    return rho_min, p_min


def energy_drift(out):
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    return float(np.abs(d["total"] - d["total"][0]).max() / d["total"][0])


# The case's own method and step (cases/strong_shock.ini); shocktube.run gives usl time.cfl 0.4
# unless told.
CASE = ("usl", ["time.cfl=0.9"])
Ns = (100, 200, 400, 800) if LONG else (200,)
for method in ("bs32", "usl", "musl"):
    l1s = {}
    for N in Ns:
        out = shocktube.run("strong_shock.ini", N, method, T)
        l1, xs, _ = shocktube.measure(out, N, EXACT, T)
        l1s[N] = l1
        rho_min, p_min = positive(out)
        check(rho_min > 0 and p_min > 0,
              f"{method} N={N}: stable to t = {T}; min density {rho_min:.3g}, min pressure "
              f"{p_min:.3g} (> 0)")
        off = (xs - XS) * N
        check(abs(off) <= 3.0, f"{method} N={N}: L1 {l1:.3e}, shock at {xs:.5f} ({off:+.2f} cells; "
              "within 3)")
        if method != "bs32" and N == 200:
            dE = energy_drift(out)
            check(dE <= 1e-12, f"{method} N={N}: total energy drift {dE:.1e} (<= 1e-12)")
    if LONG:
        msg = f"{method}: L1 from {l1s[200]:.3e} (200 cells) to {l1s[800]:.3e} (800 cells)"
        check(l1s[800] <= 0.75 * l1s[200], msg + " (falls by >= 25 %)")


out = shocktube.run("strong_shock.ini", 400, CASE[0], T, 1, CASE[1])
l1, xs, _ = shocktube.measure(out, 400, EXACT, T)
off = (xs - XS) * 400
check(l1 <= 2.23e-2 and abs(off) <= 1.0, f"the case's settings ({CASE[0]} {' '.join(CASE[1])}), "
      f"N=400: L1 {l1:.4e} <= 2.23e-2, shock {off:+.2f} cells (within 1)")


def galilean(N):
    """L1(moving) / L1(at rest) at N cells under the case's method and settings."""
    l1 = {}
    for name in ("toro3", "toro3_moving"):
        PR = fv_strip.PROBLEMS[name]
        out = shocktube.run(PR.case, N, CASE[0], PR.t, 1, [f"output.interval={PR.t}"] +
                            CASE[1] + PR.mpm_overrides(), x0=PR.x0)
        l1[name] = fv_strip.mpm_measure(PR, mt.particles(mt.snapshots(out)[-1][1], "fluid"), N)[0]
    r = l1["toro3_moving"] / l1["toro3"]
    check(r <= 1.25, f"Galilean, the case's settings, N={N}: L1 moving {l1['toro3_moving']:.4e} / at rest "
          f"{l1['toro3']:.4e} = {r:.3f} (<= 1.25)")
    return r


ratios = [galilean(N) for N in ((400, 800) if LONG else (400,))]
if LONG:
    check(ratios[1] <= ratios[0] + 0.1, f"Galilean: the ratio from 400 to 800 cells "
          f"{ratios[0]:.3f} -> {ratios[1]:.3f} (grows by at most 0.1)")

sys.exit(check.finish())
