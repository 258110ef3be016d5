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
Default: 200 cells for bs32, usl and musl, and bs32 at 400 cells as the case sets it (issue 50:
L1 <= 2.23e-2 with the shock within 1 cell; measured 1.975e-2 and +0.18 cells with fixed-step
bs32 at time.cfl = 0.99 and fluid.mol_damping = 0.3; the case's settings before, fixed bs32 at
0.8 without the damping, gave 2.255e-2 and fail it. The bound is the issue's own, no margin
added: the runs are deterministic to roundoff). `long`: 100, 200, 400 and 800 cells, where the L1
error of bs32 and musl must also fall from 200 to 800 cells (by at least 25 %, well short of
the 50 % of first order, since the shock in L1 converges at first order at best). usl's L1
stalls there (measured 3.03e-2 at 200 cells, 2.53e-2 at 400, 2.79e-2 at 800), as it does on
Sod past 400 cells: particle velocity noise that its exact energy balance turns into heat,
at a rate that grows as the cells shrink (docs/gas.md); it is printed, not checked.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

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


Ns = (100, 200, 400, 800) if LONG else (200,)
for method in ("bs32", "usl", "musl"):
    l1s = {}
    for N in Ns if LONG or method != "bs32" else (200, 400):
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
        if method == "bs32" and N == 400:
            check(l1 <= 2.23e-2 and abs(off) <= 1.0, f"bs32 N=400 (the case's settings): L1 "
                  f"{l1:.4e} <= 2.23e-2, shock {off:+.2f} cells (within 1)")
        if method != "bs32" and N == 200:
            dE = energy_drift(out)
            check(dE <= 1e-12, f"{method} N={N}: total energy drift {dE:.1e} (<= 1e-12)")
    if LONG:
        msg = f"{method}: L1 from {l1s[200]:.3e} (200 cells) to {l1s[800]:.3e} (800 cells)"
        if method == "usl":
            print("info " + msg)
        else:
            check(l1s[800] <= 0.75 * l1s[200], msg + " (falls by >= 25 %)")

sys.exit(check.finish())
