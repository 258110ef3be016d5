"""The Riemann-based artificial viscosity (fluid.av_form = riemann; fluid/fluid_stress.h,
fluid/fluid_limiter.c) against today's von Neumann-Richtmyer form (vnr) at 400 cells, usl
(fixed steps: every figure below is deterministic, and the same on every machine to roundoff).

Measured (usl, 400 cells; bench/bench_av.py):
  Toro 3 (cases/strong_shock.ini, t = 0.012): L1 vnr 2.526e-2, riemann 2.176e-2 (0.861x);
      post-shock plateau scatter (std / mean of the particle densities between the contact and
      the shock, 3 cells clear of each) 4.35e-2 and 2.56e-2 (0.59x); shock +0.27 and +0.35
      cells from the exact 0.7829.
  Sod (cases/sod.ini, t = 0.2): L1 3.214e-3 and 3.063e-3 (0.953x).
Checks, for the form named by the argument (default riemann), each against vnr's own run:
  - Toro 3: L1 <= 0.93 of vnr's (the gain measured, 0.861, with half of it as margin for
    roundoff-level changes elsewhere in the gas: a real regression of the form loses more);
    plateau scatter <= 0.75 of vnr's (measured 0.59); shock within 1 cell of the exact position
    (the issue's bound).
  - Sod: L1 no worse than vnr's (measured 0.953x; the 1-D model's 13 % gain did not carry over
    in full: see docs/gas.md).
Run with the argument `vnr` it compares vnr with itself, and the two ratio checks fail: that is
how the test was checked to be able to fail.
Bad input: an unknown fluid.av_form is one line naming the key, exit 2.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

check = mt.Checks("test_av_form")
FORM = sys.argv[1] if len(sys.argv) > 1 else "riemann"
N = 400
TORO3 = ("strong_shock.ini", Riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), gamma=1.4, x0=0.5),
         0.012)
SOD = ("sod.ini", Riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), gamma=1.4, x0=0.5), 0.2)


def measure(case, form):
    ini, exact, t = case
    out = shocktube.run(ini, N, "usl", t, 1, [f"output.interval={t}", f"fluid.av_form={form}"])
    l1, xs, P = shocktube.measure(out, N, exact, t)
    x, rho = P["x"][:, 0], P["rho"][:, 0]
    a, b = exact.contact_position(t) + 3.0 / N, exact.shock_position(t) - 3.0 / N
    r = rho[(x > a) & (x < b)]
    print(f"info {ini} {form}: L1 {l1:.4e}, shock {xs:.5f} (exact {exact.shock_position(t):.5f}),"
          f" plateau scatter {np.std(r) / np.mean(r):.3e}; {mt.cost(out)}")
    return l1, xs, float(np.std(r) / np.mean(r)), exact.shock_position(t)


ref, new = measure(TORO3, "vnr"), measure(TORO3, FORM)
check(new[0] <= 0.93 * ref[0], f"Toro 3, {FORM}: L1 {new[0]:.4e} = {new[0] / ref[0]:.3f} of vnr's "
      f"{ref[0]:.4e} (<= 0.93; measured 0.861)")
check(new[2] <= 0.75 * ref[2], f"Toro 3, {FORM}: plateau scatter {new[2]:.3e} = "
      f"{new[2] / ref[2]:.2f} of vnr's (<= 0.75; measured 0.59)")
check(abs(new[1] - new[3]) * N <= 1.0, f"Toro 3, {FORM}: shock {(new[1] - new[3]) * N:+.2f} cells "
      "from the exact position (within 1)")
ref, new = measure(SOD, "vnr"), measure(SOD, FORM)
check(new[0] <= ref[0], f"Sod, {FORM}: L1 {new[0]:.4e} = {new[0] / ref[0]:.3f} of vnr's "
      f"{ref[0]:.4e} (<= 1; measured 0.953)")
check(abs(new[1] - new[3]) * N <= 1.0, f"Sod, {FORM}: shock {(new[1] - new[3]) * N:+.2f} cells "
      "from the exact position (within 1)")

p = mt.run(["check", mt.case("sod.ini"), "fluid.av_form=godunov"], check=False)
lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
check(p.returncode == 2 and len(lines) == 1 and "fluid.av_form" in lines[0],
      f"fluid.av_form=godunov: exit {p.returncode}, {len(lines)} line(s) naming the key "
      "(exit 2, one line)")

sys.exit(check.finish())
