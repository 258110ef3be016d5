"""The temporal coupling schemes' consistency, convergence, balance and restart
(coupler/mpm_timescheme.h; the energy check is test_piperno_farhat.py).

Case: cases/fsi_piston.ini (a slab oscillating on two gas springs, traction, usl) with a stiff
slab, E = 5200 (c_s = 11.8, ten times the gas's sound speed, so the slab's stable step is about a
tenth of the gas's), to t = 1.5 (a fifth of the period). The slab's displacement comes from the
probe at its middle (probes.csv, every step).

1. multirate with coupling.substeps = 1 is the monolithic step: diagnostics.csv to 1e-12
   relative (the same arithmetic in another order: the gas's exchange at the start of the step
   is captured and given to the solid, which the monolithic step applies in place). The gas
   runs pure FLIP here (fluid.pic_fraction = 0): with the PIC share a gas beside a solid takes
   by default under usl (0.02, fluid/fluid_module.c) the pair differed by 1.3e-12 (2026-12-06),
   the share's own rounding amplified by the stiff slab as in check 5.
2. multirate's coupling error falls with the coupling step: the largest difference of the
   slab's displacement from a monolithic reference at time.cfl = 0.05, for time.cfl = 0.4, 0.2,
   0.1 (the gas's step; the slab substeps about ten times in each), decreases at every
   refinement with an observed order of at least 0.7 overall (predicted 1: the gas meets the
   slab held at the start of each coupling step, so its load lags the slab's motion by up to
   one coupling step; measured 1.55 then 0.76, 1.16 overall, with a held load; printed with
   interpolated loads and beside monolithic's own error and cost). The same with
   coupling.slow_substeps = 0 (the gas, too, at the slab's rate, against the slab held over the
   coupling step: the coupling lag alone, predicted first order at least) falls with an overall
   order of at least 0.7 as well (measured 2.20 then 1.58, 1.89 overall: the lag's first-order
   part is small here); its share of the held run's error is printed (measured 0.21, 0.10,
   0.06: the rest is the gas's own step, several times monolithic's).
3. Every partitioned run balances the interface momentum to 1e-9 of the interface force
   (summary.json; the owed momentum included).
4. Restart is bitwise for every temporal scheme: staggered (solid_first, gas_first, parallel,
   and solid_first strongly coupled: sub-iterations with Aitken relaxation, whose predictor is
   checkpointed interface state), multirate (held, interpolated, and with the predictor,
   coupling.predictor = linear, whose last hold is checkpointed; and coupling.exchange = shared,
   with coupling.scheme = velocity) and monolithic, run to 0.6 with a checkpoint at 0.3 and
   restarted from it on 1 rank: the last snapshots equal to the bit, and the restarted run's
   momentum balance still closes (the owed momentum is in the checkpoint).
`quick` (the argument; for the sanitizer pass): check 4, to t = 0.06 with the checkpoint at
0.03, and on 2 ranks the restarts of staggered solid_first, strong staggered and multirate
(classic, classic with the predictor, MRIStep, and the shared exchange); and check 5 for the
shared exchange (multirate, coupling.exchange = shared, velocity scheme: 2 ranks against 1 to
t = 0.5; measured 1.7e-12 of the largest value, a 1e-15 change of the slab's velocity 1.4e-12).

`mri` (the argument): multirate with an ERK pair, ARKODE MRIStep (bs32 fixed steps,
MRI-GARK-ERK33a; coupler/timescheme_multirate.c), on the same stiff piston:
6. its coupling error against a fine monolithic bs32 reference (time.cfl = 0.05, the same
   method of lines) falls at every halving of time.cfl = 0.4, 0.2, 0.1 (the slow step; the slab
   substeps about five times in each) with an overall observed order of at least 1.5. Predicted:
   the table's 3, reduced towards 2 by the MPM right-hand side, which is only once continuously
   differentiable in the positions (the quadratic B-spline's gradient has kinks where a particle
   crosses a cell face): monolithic bs32 itself shows 1.96 and 2.98 here. Measured 2.45 and
   2.67 (overall 2.56; 2026-12-06, both with the hybrid pressure, which the gas beside a solid
   takes under the ERK pairs by default, and with the coupling's relaxation of the phases' own
   velocities, coupling.mol_rate; without it 1.70 and 2.60, overall 2.15; with the particles'
   pressure 1.45 and 2.50, overall 1.98). From d8fcec1 to 2026-11-28 the gas's wall rule for the method of lines
   scaled the velocity into the slip ends after each accepted step, a change whose strength
   depended on the step: this check failed at orders 0.21 and 0.33 (monolithic bs32 about 1);
   the rule is now a rate in the right-hand side (fluid/fluid_transfer.c). Its ratio to
   monolithic bs32's error at the same time.cfl is printed (measured 2.9-3.5x), not checked:
   there monolithic's gas steps at
   the slab's limit, five times smaller than MRIStep's, so the ratio measures the gas's own time
   error at its own step, not the coupling (without the artificial viscosity it is 56x at
   time.cfl = 0.4). An earlier check held it under 5x (2.3-3.6x with the lagged rate).
7. its momentum balance closes to 1e-9 of the interface force, and on 2 ranks it gives 1 rank's
   result within 10x what a 1e-15 change of the slab's velocity does on 1 rank.

8. Light nodes (mpm_interface.h): the shock panel (cases/shock_panel.ini at dx = 1 mm, multirate,
   held load, time.cfl = 0.4, to 0.235 ms) crosses the coupling step at 0.2305 ms where the
   panel's particles leave a node they touched at the start of the step with 1e-7 to 1e-13 of
   the heaviest node's mass: no coupling step changes the interface work W_net by more than 2 %
   of the panel's largest energy in the window (measured 0.40 %, 2 ranks; without the rule
   141 %, a jump of +1.38 J in that step: the load divided by the vanishing mass gave the node
   5e6 m/s). The tolerance is five times the largest step of the sound run and seventy times
   under the failure.

5. multirate on 2 ranks gives 1 rank's result: positions and velocities by id, differing by no
   more than 10 times what a 1e-15 relative change of the slab's initial velocity does on 1 rank
   (fixed steps: roundoff in the reductions only, which the stiff slab amplifies as it amplifies
   any perturbation; measured 4.5e-12 of the largest value).
"""
import csv
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

QUICK = sys.argv[1:] == ["quick"]
MRI = sys.argv[1:] == ["mri"]
check = mt.Checks("test_timeschemes_quick" if QUICK else
                  "test_timeschemes_mri" if MRI else "test_timeschemes")
CASE = mt.case("fsi_piston.ini")
STIFF = ["solid.slab.E=5200", "time.t_end=1.5"]


def run(name, args, ranks=1):
    out = mt.outdir(name)
    mt.run(["run", CASE, f"output.dir={out}"] + list(args), ranks=ranks)
    return out


def rows(out, name="diagnostics.csv"):
    with open(os.path.join(out, name)) as f:
        return list(csv.DictReader(f))


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def displacement(out):
    p = np.loadtxt(os.path.join(out, "probes.csv"), delimiter=",", skiprows=1)
    return p[:, 0], p[:, 1]


def final_particles(out):
    return {ph: mt.particles(mt.snapshots(out)[-1][1], ph) for ph in ("solid", "fluid")}


def largest_difference(a, b, fields=None):
    worst = 0.0
    for ph in a:
        if not np.array_equal(a[ph]["id"], b[ph]["id"]):
            return math.inf
        for f in fields or [k for k in a[ph] if k not in ("id", "time")]:
            scale = max(float(np.max(np.abs(a[ph][f]))), 1e-300) if fields else 1.0
            worst = max(worst, float(np.max(np.abs(a[ph][f] - b[ph][f]))) / scale)
    return worst


balances = []
CFLS = (0.4, 0.2, 0.1)


def coupling_errors(base, variants):
    """The slab displacement's largest difference from a monolithic run at time.cfl = 0.05 with
    the same base keys, for each (label, keys) at each of CFLS; the first label is the
    monolithic one, the others' momentum balances go to `balances`."""
    ref = run(f"ts_reference{'_erk' if 'time.method=bs32' in base else ''}",
              base + ["time.cfl=0.05"])
    t_ref, u_ref = displacement(ref)
    amplitude = float(np.max(np.abs(u_ref)))
    errors = {}
    for label, args in variants:
        errors[label] = []
        for cfl in CFLS:
            out = run(f"ts_{label.replace(' ', '_')}_{cfl}", base + args + [f"time.cfl={cfl}"])
            t, u = displacement(out)
            err = float(np.max(np.abs(np.interp(t_ref, t, u) - u_ref)))
            errors[label].append(err)
            if label != variants[0][0]:
                balances.append(summary(out)["coupling_imbalance"])
            print(f"{label}, cfl {cfl}: displacement error {err:.3e} ({err / amplitude:.2e} of the "
                  f"amplitude {amplitude:.3e}); {mt.cost(out)}, {summary(out)['rhs_evals']} RHS")
    return errors


def check_order(label, e, least, why):
    """The errors at CFLS fall at every halving, with an overall observed order >= least."""
    orders = [math.log(e[k] / e[k + 1]) / math.log(2) for k in range(len(e) - 1)]
    overall = math.log(e[0] / e[-1]) / math.log(CFLS[0] / CFLS[-1])
    check(all(o > 0 for o in orders) and overall >= least,
          f"{label}: error {', '.join(f'{x:.3e}' for x in e)} at cfl "
          f"{', '.join(map(str, CFLS))}: orders {', '.join(f'{o:.2f}' for o in orders)}, overall "
          f"{overall:.2f} ({why})")


def consistency_and_convergence():

    # 1. substeps = 1 is the monolithic step.
    flip = STIFF + ["fluid.pic_fraction=0"]  # pure FLIP (the header)
    mono = run("ts_mono", flip)
    one = run("ts_multirate_1", flip + ["coupling.time=multirate", "coupling.substeps=1"])
    worst = 0.0
    for key in ("dt", "px", "kinetic", "internal", "total"):
        x = np.array([float(r[key]) for r in rows(mono)])
        y = np.array([float(r[key]) for r in rows(one)])
        worst = max(worst, float(np.max(np.abs(x - y)) / np.max(np.abs(x))))
    check(len(rows(mono)) == len(rows(one)) and worst < 1e-12,
          f"multirate, substeps = 1, against monolithic over {len(rows(one)) - 1} steps: largest "
          f"difference {worst:.1e} (tolerance 1e-12)")
    balances.append(summary(one)["coupling_imbalance"])

    # 2. The coupling error against a fine monolithic reference.
    errors = coupling_errors(STIFF, [("monolithic", []),
                                     ("multirate held", ["coupling.time=multirate"]),
                                     ("multirate interpolated", ["coupling.time=multirate",
                                                                 "coupling.load=interpolated"]),
                                     ("multirate lag", ["coupling.time=multirate",
                                                        "coupling.slow_substeps=0"])])
    check_order("multirate (held)", errors["multirate held"], 0.7, "predicted 1; at least 0.7")
    # 2b. The coupling lag alone: the gas at the slab's rate against the slab held over the
    # coupling step.
    check_order("multirate, coupling.slow_substeps = 0 (the coupling lag alone)",
                errors["multirate lag"], 0.7, "predicted at least 1: the held slab; at least 0.7")
    share = [lag / held for lag, held in zip(errors["multirate lag"], errors["multirate held"])]
    print("the coupling lag's share of multirate's (held) error at cfl "
          f"{', '.join(map(str, CFLS))}: {', '.join(f'{x:.2f}' for x in share)}")

    # 3. Momentum balance.
    check(max(balances) < 1e-9, f"partitioned runs: interface momentum imbalance at most "
          f"{max(balances):.1e} of the interface force (tolerance 1e-9)")



# 4. Restart, every temporal scheme.
SHARED = ["coupling.scheme=velocity", "coupling.exchange=shared"]
SCHEMES = [("monolithic", ["coupling.time=monolithic"]),
           ("staggered solid_first", ["coupling.time=staggered"]),
           ("staggered gas_first", ["coupling.time=staggered", "coupling.order=gas_first"]),
           ("staggered parallel", ["coupling.time=staggered", "coupling.order=parallel"]),
           ("staggered strong", ["coupling.time=staggered", "coupling.iterations=40",
                                 "coupling.tolerance=1e-8"]),
           ("multirate held", ["coupling.time=multirate", "solid.slab.E=5200"]),
           ("multirate interpolated", ["coupling.time=multirate", "coupling.load=interpolated",
                                       "solid.slab.E=5200"]),
           ("multirate mristep", ["coupling.time=multirate", "solid.slab.E=5200",
                                  "time.method=bs32", "time.adaptive=false"]),
           ("multirate predictor", ["coupling.time=multirate", "coupling.predictor=linear",
                                    "fluid.viscous_step=damped", "solid.slab.E=5200"]),
           ("multirate shared", ["coupling.time=multirate", "solid.slab.E=5200"] + SHARED)]
ERK = ["time.method=bs32", "time.adaptive=false"]


def mri_convergence():
    errors = coupling_errors(STIFF + ERK, [("monolithic bs32", []),
                                           ("multirate mristep", ["coupling.time=multirate"])])
    e, m = errors["multirate mristep"], errors["monolithic bs32"]
    check_order("multirate (MRIStep, bs32, MRI-GARK-ERK33a)", e, 1.5,
                "at least 1.5; see the header")
    print(f"info multirate (MRIStep) error {', '.join(f'{a / b:.1f}x' for a, b in zip(e, m))} "
          f"monolithic bs32's at the same time.cfl (a gas step 5x larger; see the header)")
    check(max(balances) < 1e-9, f"MRIStep runs: interface momentum imbalance at most "
          f"{max(balances):.1e} of the interface force (tolerance 1e-9)")


def restarts(t_half, ranks, schemes):
    for label, args in schemes:
        name = label.replace(" ", "_")
        full = run(f"ts_restart_{name}_np{ranks}", args + [
            f"time.t_end={2 * t_half}", f"output.interval={t_half}",
            f"output.checkpoint_interval={t_half}"], ranks=ranks)
        again = mt.outdir(f"ts_restarted_{name}_np{ranks}")
        mt.run(["restart", os.path.join(full, "checkpoint_000001.h5"), f"output.dir={again}"],
               ranks=ranks)
        d = largest_difference(final_particles(full), final_particles(again))
        imb = summary(again)["coupling_imbalance"]
        check(d == 0 and imb < 1e-9, f"{label} on {ranks} rank(s): restarted from t = {t_half}, "
              f"the state at {2 * t_half} differs by {d:.1e} (tolerance 0: bitwise); momentum "
              f"imbalance after the restart {imb:.1e}")




def two_ranks(label, extra):
    """5 and 7: 2 ranks against 1, against what a 1e-15 change of the input does on 1 rank."""
    args = ["solid.slab.E=5200", "coupling.time=multirate", "time.t_end=0.5"] + extra
    name = label.replace(" ", "_")
    one = final_particles(run(f"ts_{name}_np1", args))
    two = final_particles(run(f"ts_{name}_np2", args + ["grid.ranks=2 1"], ranks=2))
    nudged = final_particles(run(f"ts_{name}_nudged",
                                 args + ["solid.slab.velocity=0.05000000000000005 0"]))
    d = largest_difference(one, two, fields=("x", "v"))
    scale = largest_difference(one, nudged, fields=("x", "v"))
    check(0 < scale and d <= 10 * scale,
          f"{label} on 2 ranks against 1 (by id, t = 0.5): largest difference {d:.1e} of the "
          f"largest value; a 1e-15 change of the slab's velocity gives {scale:.1e} (tolerance 10x "
          f"that: roundoff in the reductions, amplified like any perturbation of the input)")


def light_nodes():
    """8: the shock panel's coupling step where the panel leaves a node within the step."""
    out = mt.outdir("ts_light_nodes")
    mt.run(["run", mt.case("shock_panel.ini"), f"output.dir={out}", "grid.dx=0.001",
            "time.t_end=2.35e-4", "time.cfl=0.4", "coupling.load=held", "run.progress=false",
            "grid.ranks=2 1"], ranks=2)
    jump, t_jump, e_max, _ = mt.coupling_energy_jump(out)
    check(jump <= 0.02 * e_max,
          f"light nodes: shock panel, multirate at cfl 0.4 to 0.235 ms: the largest change of "
          f"W_net in one coupling step {jump:.3g} J (at t = {t_jump:.6g} s) is "
          f"{100 * jump / e_max:.2f} % of the panel's largest energy {e_max:.3g} J (tolerance "
          f"2 %; 141 % without the light-node rule)")


if QUICK:
    restarts(0.03, 1, SCHEMES)
    restarts(0.03, 2, [SCHEMES[1], SCHEMES[4], SCHEMES[6], SCHEMES[7], SCHEMES[8], SCHEMES[9]])
    two_ranks("multirate shared", SHARED)
    sys.exit(check.finish())
if MRI:
    mri_convergence()
    two_ranks("multirate mristep", ERK)
    sys.exit(check.finish())
consistency_and_convergence()
light_nodes()
restarts(0.3, 1, SCHEMES)
two_ranks("multirate", [])
sys.exit(check.finish())
