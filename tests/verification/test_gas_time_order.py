"""The ERK pairs' time error on the gas: the artificial viscosity's strain rate (cases/sod.ini).

The method-of-lines RHS of the ERK pairs is an ODE only if it is a function of the state. With
fluid.strain_rate = lagged the artificial viscosity reads the strain rate of the previous step,
so the RHS depends on the step history and every pair is first order in time wherever that
viscosity acts (shocks, and the particle noise of any flow). With fluid.strain_rate = current
(the default) it takes the rate of the state itself (a second deposit and a gather per RHS).

Sod at 200 cells to t = 0.1, bs32 with fixed steps (time.adaptive = false) at time.cfl = 0.4,
0.2, 0.1 against the same setting at time.cfl = 0.025; error: the mean over the particles (by
id) of the velocity difference, relative to the largest velocity. Checks:
  1. current: the error falls at every halving, with an overall order of at least 1.5
     (halfway between the lag's first order and the 2 the MPM right-hand side allows: bs32 is
     third order, but the kinks of the B-spline gradient where a particle crosses a cell face
     and the viscosity's compression switch cap it, as they cap the coupled cases at about 2;
     docs/verification.md). Measured 2.01, 1.77, overall 1.89.
  2. current is at least 4x more accurate than lagged at each time.cfl: measured 10.6x,
     19.7x, 28.7x (the bound leaves a factor 2.6 below the smallest).
  3. lagged is first order: overall order below 1.5 (measured 1.12, 1.22, overall 1.17). This
     is the diagnosis of the lag, kept as a check so that a change that makes the lag harmless
     shows here.
The cost is printed: current's RHS costs about 1.6x lagged's (its reference 9.6 s against
5.7 s), and at time.cfl = 0.4 it is already more accurate than lagged at 0.1 (2.2e-5 in 0.5 s
against 4.6e-5 in 1.5 s).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import shocktube  # noqa: E402

check = mt.Checks("test_gas_time_order")
N, T = 200, 0.1
CFLS = (0.4, 0.2, 0.1)
REF_CFL = 0.025


def errors(rate):
    def run_at(cfl):
        return shocktube.run("sod.ini", N, "bs32", T, extra=[
            f"fluid.strain_rate={rate}", f"time.cfl={cfl}", "time.adaptive=false",
            f"output.interval={T}"])
    return mt.time_errors(rate, run_at, CFLS, REF_CFL, lambda d: float(np.mean(np.abs(d))))


cur, lag = errors("current"), errors("lagged")
steps, overall = mt.orders(cur)
check(all(a > b for a, b in zip(cur, cur[1:])) and overall >= 1.5,
      f"current: velocity error {', '.join(f'{x:.2e}' for x in cur)} at time.cfl "
      f"{', '.join(map(str, CFLS))}: orders {', '.join(f'{o:.2f}' for o in steps)}, overall "
      f"{overall:.2f} (falls at every halving; overall at least 1.5)")
ratios = [b / a for a, b in zip(cur, lag)]
check(min(ratios) >= 4, f"current against lagged: {', '.join(f'{r:.1f}x' for r in ratios)} "
      f"more accurate (at least 4x)")
steps, overall = mt.orders(lag)
check(overall < 1.5, f"lagged: velocity error {', '.join(f'{x:.2e}' for x in lag)}: orders "
      f"{', '.join(f'{o:.2f}' for o in steps)}, overall {overall:.2f} (first order: below 1.5)")
sys.exit(check.finish())
