"""Which explicit time methods are safe for undamped waves (DESIGN.md section 5), measured on
the axial bar (cases/axial_bar.ini, N = 50 cells, v0 = 1e-4: linear regime) with fixed steps
(time.adaptive = false: no error control hides an instability) over two periods.

For the first mode, theta = omega_1 h, one step multiplies the mode's energy by |R(i theta)|^2:
  ERK order 2 (ralston21): 1 + theta^4 / 4       (grows: unstable for any step)
  ERK order 3 (bs32):      1 - theta^4 / 12      (decays: stable for theta < sqrt 3)
  ERK order 4, 5:          1 - O(theta^6)        (neutral at this step)
1. At CFL 0.4 (theta = 0.0126), the measured total-energy change after the run matches
   these predictions for ralston21 (+6.3e-6) and bs32 (-2.1e-6) within 10 % (the energy
   measure and omega_1 are exact to about 0.1 %; 10 % leaves room for the O(theta^6) terms
   and the higher modes' share), and is below 1e-7 for zonneveld43 and dp54.
2. At CFL 0.9, forward Euler and ralston21 blow up: the energy grows more than 1000-fold or
   the run stops on an unphysical state (roundoff excites the high grid modes, which grow
   by |R|^2 per step). The third-order and higher pairs keep the energy within 0.1 %.
3. The classic updates (usl, musl: symplectic-Euler-like) are stable at CFL 0.8 (energy
   change within 0.5 %: their energy error is first order in h, measured -0.17 % at 0.8 and
   -0.01 % at 0.5). With quadratic B-splines their limit is below 1: at CFL 0.9 usl blows up
   on this bar (measured energy growth 2.4e4-fold) while musl still holds (-0.23 %); the test
   reports both without asserting them. The default CFL is 0.4.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_stability")
L, OMEGA, C = 25.0, 2 * np.pi / 10.0, 10.0


def run(method, cfl):
    out = mt.outdir(f"stability_{method}_cfl{cfl}")
    p = mt.run(["run", mt.case("axial_bar.ini"), f"output.dir={out}", "grid.dx=0.5",
                "domain.hi=26 1", "geometry.bar.hi=25 1", "solid.bar.velocity_field="
                "1e-4*sin(pi*x/50); 0", "time.t_end=20", f"time.method={method}",
                "time.adaptive=false", f"time.cfl={cfl}", "output.snapshots=false",
                "run.progress=false"], check=False)
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    return p.returncode, d


rc, d = run("ralston21", 0.4)
steps = len(d["t"]) - 1
theta = OMEGA * 0.4 * 0.5 / C  # h = cfl dx / (c + |v|), |v| <= 1e-4 << c
for method, per_step in (("ralston21", theta**4 / 4), ("bs32", -theta**4 / 12)):
    if method != "ralston21":
        rc, d = run(method, 0.4)
    change = d["total"][-1] / d["total"][0] - 1
    expect = (1 + per_step) ** steps - 1
    check(rc == 0 and abs(change - expect) <= 0.1 * abs(expect),
          f"{method} CFL 0.4: energy change {change:+.3e} over {steps} steps, predicted "
          f"{expect:+.3e} (|R(i theta)|^2 per step, theta = {theta:.4f}; tolerance 10 %)")
for method in ("zonneveld43", "dp54"):
    rc, d = run(method, 0.4)
    change = d["total"][-1] / d["total"][0] - 1
    check(rc == 0 and abs(change) < 1e-7,
          f"{method} CFL 0.4: energy change {change:+.3e} (neutral: < 1e-7)")

for method in ("euler", "ralston21"):
    rc, d = run(method, 0.9)
    growth = d["total"].max() / d["total"][0]
    check(rc != 0 or growth > 1e3, f"{method} CFL 0.9: unstable as predicted: "
          f"{'run stopped on an unphysical state' if rc else 'ran to the end'} at t = "
          f"{d['t'][-1]:.3g}, energy grew {growth:.3g}-fold")
for method, cfl, tol in (("bs32", 0.9, 1e-3), ("zonneveld43", 0.9, 1e-3), ("dp54", 0.9, 1e-3),
                         ("usl", 0.8, 5e-3), ("musl", 0.8, 5e-3)):
    rc, d = run(method, cfl)
    change = d["total"][-1] / d["total"][0] - 1
    check(rc == 0 and abs(change) < tol,
          f"{method} CFL {cfl}: stable, energy change {change:+.3e} over t = {d['t'][-1]:.3g} "
          f"(< {100 * tol:g} %)")
for method in ("usl", "musl"):
    rc, d = run(method, 0.9)
    print(f"info {method} CFL 0.9: {'stopped' if rc else 'ran'} to t = {d['t'][-1]:.3g}, energy "
          f"change {d['total'][-1] / d['total'][0] - 1:+.3e}")
sys.exit(check.finish())
