"""Multirate's coupling step and the predictor (coupler/timescheme_multirate.c,
coupler/mpm_interface.h, fluid/fluid_stress.h fluid_signal_speed; issue 50, item 4).

1. fluid.viscous_step = damped raises the gas's stable step where the artificial viscosity is on:
   the shock panel (cases/shock_panel.ini at dx = 2.5 mm, multirate, usl, to 0.1 ms, the shock
   crossing the gas and meeting the panel) takes at most 0.92 times the coupling steps of
   `additive` (predicted: at a weakly compressing particle the additive speed is c + |v| + c (vnr's
   linear term, c_lin = 0.5, adds 2 nu / dx = c), the damped one c + |v| + 0.62 c: about 0.85 of
   it; measured 0.85 at dx = 1 mm, 745 against 635 coupling steps to 0.3 ms), and both runs end
   with the interface balanced to 1e-9. On the old code the key does not exist (exit 2).
2. coupling.predictor = linear (the gas meets the solid's interface velocity extrapolated from
   its last two coupling steps) on the stiff piston (cases/fsi_piston.ini, E = 5200, traction,
   the slab about ten substeps a coupling step, to t = 1.5; test_timeschemes's study): the slab's
   displacement error against monolithic at time.cfl = 0.05 falls at every halving of time.cfl
   = 0.4, 0.2, 0.1 with an overall order of at least 1.2 (measured 2.0: 1.25e-4, 4.6e-5,
   7.7e-6; 2.4 before check 3's fix: 1.9e-4, 6.2e-5, 6.9e-6; the held solid's 1.2e-4,
   5.1e-5, 3.0e-5, order 0.98, is printed beside it: its error is first order in the coupling
   step, the lag of the held face), and every predictor run
   balances the interface momentum to 1e-9 of the interface force (the predictor changes what
   the gas sees, never the bookkeeping of what it gives up). Tolerance: the order from the
   lag's first-order part removed; 1.2 sits between held's 0.98 and the measured 2.0.
3. The predictor where the solid leaves a node: the shock panel (cases/shock_panel.ini at
   dx = 1 mm, multirate, time.cfl = 0.4, coupling.predictor = linear, 1 rank, to
   0.235 ms) crosses a coupling step at about 0.228 ms where the panel's particles leave a node
   (test_timeschemes's light nodes): no coupling step changes the interface work W_net by more
   than 2 % of the panel's largest energy. Measured 0.20 % (the held solid 0.36 % on 2 ranks).
   Before the predictor divided the gas's load by the larger of the node's two holds' masses
   it divided by the mass at this hold, roundoff there: +150 J in one coupling step (4,957 %),
   +352 J booked by 0.235 ms and the panel's energy 2.9 J against 0.85 J (the tip's
   displacement 0.13 % off). Tolerance: test_timeschemes's for the held solid (2 %).
The predictor's restart (its last hold is checkpointed) is test_timeschemes_quick's.
"""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_multirate_step")


def run(case, name, args):
    out = mt.outdir(name)
    mt.run(["run", mt.case(case), f"output.dir={out}", "run.progress=false"] + list(args))
    with open(os.path.join(out, "summary.json")) as f:
        return out, json.load(f)


# 1. The damped stable step on the shock panel.
PANEL = ["grid.dx=0.0025", "time.t_end=1e-4", "output.interval=1e9", "time.method=usl",
         "coupling.time=multirate", "coupling.scheme=velocity"]
steps = {}
for form in ("additive", "damped"):
    out, s = run("shock_panel.ini", f"mrs_panel_{form}", PANEL + [f"fluid.viscous_step={form}"])
    steps[form] = s["steps"]
    check(s["coupling_imbalance"] < 1e-9,
          f"shock panel, fluid.viscous_step = {form}: interface imbalance "
          f"{s['coupling_imbalance']:.1e} (tolerance 1e-9); {mt.cost(out)}, {s['rhs_evals']} RHS")
ratio = steps["damped"] / steps["additive"]
check(ratio <= 0.92, f"shock panel to 0.1 ms: damped takes {steps['damped']} coupling steps, "
      f"additive {steps['additive']}: ratio {ratio:.3f} (at most 0.92; predicted about 0.85)")

# 2. The predictor on the stiff piston.
STIFF = ["solid.slab.E=5200", "time.t_end=1.5"]
CFLS = (0.4, 0.2, 0.1)


def displacement(out):
    p = np.loadtxt(os.path.join(out, "probes.csv"), delimiter=",", skiprows=1)
    return p[:, 0], p[:, 1]


ref, _ = run("fsi_piston.ini", "mrs_reference", STIFF + ["time.cfl=0.05"])
t_ref, u_ref = displacement(ref)
errors = {}
for label, extra in (("held", []), ("linear", ["coupling.predictor=linear"])):
    errors[label] = []
    for cfl in CFLS:
        out, s = run("fsi_piston.ini", f"mrs_{label}_{cfl}",
                     STIFF + ["coupling.time=multirate", f"time.cfl={cfl}"] + extra)
        t, u = displacement(out)
        errors[label].append(float(np.max(np.abs(np.interp(t_ref, t, u) - u_ref))))
        if label == "linear":
            check(s["coupling_imbalance"] < 1e-9,
                  f"piston, predictor, cfl {cfl}: interface imbalance {s['coupling_imbalance']:.1e} "
                  f"(tolerance 1e-9)")
for label, e in errors.items():
    orders = [math.log(e[k] / e[k + 1]) / math.log(2) for k in range(len(e) - 1)]
    overall = math.log(e[0] / e[-1]) / math.log(CFLS[0] / CFLS[-1])
    line = (f"piston, multirate ({'coupling.predictor = linear' if label == 'linear' else 'held'}"
            f"): error {', '.join(f'{x:.2e}' for x in e)} at cfl 0.4, 0.2, 0.1: orders "
            f"{', '.join(f'{o:.2f}' for o in orders)}, overall {overall:.2f}")
    if label == "linear":
        check(all(o > 0 for o in orders) and overall >= 1.2, line + " (at least 1.2)")
    else:
        print("info " + line)

# 3. The predictor where the panel leaves a node.
out, s = run("shock_panel.ini", "mrs_panel_light", [
    "grid.dx=0.001", "time.t_end=2.35e-4", "time.cfl=0.4", "output.interval=1e9",
    "coupling.time=multirate", "coupling.predictor=linear"])
jump, t_jump, e_max, w_end = mt.coupling_energy_jump(out)
check(jump <= 0.02 * e_max,
      f"shock panel, predictor, cfl 0.4 to 0.235 ms: the largest change of W_net in one coupling "
      f"step {jump:.3g} J (at t = {t_jump:.6g} s) is {100 * jump / e_max:.2f} % of "
      f"the panel's largest energy {e_max:.3g} J (tolerance 2 %; 4957 % before the fix); W_net "
      f"{w_end:.3g} J at the end; {mt.cost(out)}")
sys.exit(check.finish())
