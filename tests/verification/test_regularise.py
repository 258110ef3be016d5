"""Conservative particle regularisation of the gas (fluid/fluid_regularise.c).

Case: cases/gas_box.ini (periodic unit square, 32 x 32 cells, 4 particles per cell) with
p = 1, rho = 1 and v = (sin 2 pi x, sin 2 pi y) (Mach up to 0.85): the gas streams away from
the lines x = 0 and y = 0 and into x = 0.5 and y = 0.5, so cells deplete on one side and
crowd on the other. Thresholds regularise_min = 3, regularise_max = 6, so that both splits and
merges happen within t = 0.3 (the defaults 2 and 16 would merge only under fourfold
compression). Checks:

1. Every event (run.log_level=debug prints the global totals before and after it, to 17
   digits): mass, momentum and total energy unchanged to 1e-13 relative (momentum relative to
   sqrt(2 M E), which bounds sum m |v|). Each merge or split changes its particles' totals
   by a few roundings (~1e-16 of their share); the totals are sums over ~4000 particles in
   another order before and after, whose rounding can reach n eps = 4.5e-13 in the worst case
   and is ~sqrt(n) eps = 7e-15 typically: 1e-13 catches any lost term (a merged kinetic-energy
   defect alone is ~1e-6 of E here) and is above the summation noise. For usl, musl and usl
   with APIC (every step, regularise_every = 1) and bs32 (every 5 steps).
2. Over the usl, musl and APIC runs the total energy in diagnostics.csv drifts by <= 1e-12
   relative, as without regularisation (test_gas_conservation): the events add no drift.
3. After an event every non-empty cell holds 3 to 6 particles (regularise_every = 1: every
   snapshot follows an event); ids stay unique; splits and merges both happened.
4. 2 ranks vs 1 (usl, regularise_every = 5): the same particle ids (new ids do not depend on
   the ranks), every field within 1e-12 relative (sums in another order; as test_sod).
5. Restart (usl and bs32, and usl with light merges, regularise_every = 5, checkpoint at
   t = 0.15): the restarted run ends bitwise identical by id (the event schedule is the sim's
   step count, which the checkpoint carries).
6. Light merges (fluid.merge_light = 0.4, usl, an event every step): every event conserves as
   in 1, the energy drifts as in 2, and at every snapshot (each follows an event) no particle
   is lighter than 0.4 of the heaviest in its cell (the merges by count make such particles: the usl run of 1-3 is
   the control, where they must be found, so that the check can fail); every non-empty cell
   still holds 3 to 6 particles (a light merge splits the pair again: it keeps the count) and
   ids stay unique. 2 ranks give 1 rank's result as in 4.
"""
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_regularise")
CASE = mt.case("gas_box.ini")
T = 0.3
FLOW = ["gas.air.pressure_field=1", "gas.air.velocity_field=sin(2*pi*x); sin(2*pi*y)",
        f"time.t_end={T}", "fluid.regularise_min=3", "fluid.regularise_max=6"]
EVENT = re.compile(r"regularise step (\d+): (?:\d+) refills, (\d+) splits, (\d+) merges; mass (\S+) -> (\S+), "
                   r"momentum \((\S+), (\S+), (\S+)\) -> \((\S+), (\S+), (\S+)\), "
                   r"energy (\S+) -> (\S+)")


def run(label, extra, every):
    out = mt.outdir("regularise_" + label.replace(" ", "_"))
    p = mt.run(["run", CASE, f"output.dir={out}", "run.progress=false", "run.log_level=debug",
                "output.interval=0.1", f"fluid.regularise_every={every}"] + FLOW + extra)
    events = [[float(v) for v in m.groups()] for m in EVENT.finditer(p.stderr)]
    return out, np.array(events)


def per_event(label, ev):
    splits, merges = int(ev[:, 1].sum()), int(ev[:, 2].sum())
    check(splits > 0 and merges > 0, f"{label}: {len(ev)} events, {splits} splits and {merges} "
          "merges")
    M, E = ev[:, 3], ev[:, 11]
    dM = float(np.abs(ev[:, 4] - M).max() / M.max())
    dP = float(np.abs(ev[:, 8:11] - ev[:, 5:8]).max() / np.sqrt(2 * M.max() * E.max()))
    dE = float(np.abs(ev[:, 12] - E).max() / E.max())
    check(max(dM, dP, dE) <= 1e-13, f"{label}: per event, largest change of mass {dM:.1e}, "
          f"momentum {dP:.1e} of sqrt(2 M E), total energy {dE:.1e} (each <= 1e-13)")


def cells_of(P):
    cells = np.floor(P["x"][:, :2] * 32).astype(int).clip(0, 31)
    return cells[:, 0] + 32 * cells[:, 1]


def light_particles(out, mu):
    """Most particles lighter than mu times their cell's heaviest in one snapshot after t = 0."""
    most = 0
    for t, path in mt.snapshots(out):
        if t == 0:
            continue
        P = mt.particles(path, "fluid")
        cell, m = cells_of(P), P["m"].ravel()
        heaviest = np.zeros(32 * 32)
        np.maximum.at(heaviest, cell, m)
        most = max(most, int((m < mu * heaviest[cell]).sum()))
    return most


def cell_counts(out):
    """Worst per-cell counts over the snapshots after t = 0 (non-empty cells), unique ids."""
    lo, hi, unique = 1 << 30, 0, True
    for t, path in mt.snapshots(out):
        P = mt.particles(path, "fluid")
        unique &= len(np.unique(P["id"])) == len(P["id"])
        n = np.bincount(cells_of(P), minlength=32 * 32)
        lo, hi = min(lo, int(n[n > 0].min())), max(hi, int(n.max()))
    return lo, hi, unique


outs = {}
for label, extra in (("usl", ["time.method=usl"]), ("musl", ["time.method=musl"]),
                     ("usl apic", ["time.method=usl", "transfer.velocity=apic"])):
    out, ev = run(label, extra, 1)
    outs[label] = out
    per_event(label, ev)
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    drift = float(np.abs(d["total"] - d["total"][0]).max() / d["total"][0])
    check(drift <= 1e-12, f"{label}: total energy drift over {len(d) - 1} steps with an event "
          f"each: {drift:.1e} (<= 1e-12)")
    lo, hi, unique = cell_counts(out)
    check(lo >= 3 and hi <= 6 and unique, f"{label}: after events every non-empty cell holds "
          f"{lo} to {hi} particles (3 to 6), ids unique: {unique}")
    print(f"info {label}: {int(d['particles'][0])} -> {int(d['particles'][-1])} particles")

_, ev = run("bs32", ["time.method=bs32"], 5)
per_event("bs32", ev)

LIGHT = ["fluid.merge_light=0.4"]
out, ev = run("usl light", ["time.method=usl"] + LIGHT, 1)
per_event("usl light", ev)
d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
drift = float(np.abs(d["total"] - d["total"][0]).max() / d["total"][0])
check(drift <= 1e-12, f"usl light: total energy drift over {len(d) - 1} steps {drift:.1e} (<= 1e-12)")
light, control = light_particles(out, 0.4), light_particles(outs["usl"], 0.4)
check(light == 0 and control > 0, f"usl light: after events {light} particles lighter than 0.4 of "
      f"their cell's heaviest (0), against {control} without fluid.merge_light (> 0: the control)")
lo, hi, unique = cell_counts(out)
check(lo >= 3 and hi <= 6 and unique, f"usl light: after events every non-empty cell holds {lo} "
      f"to {hi} particles (3 to 6), ids unique: {unique}")
print(f"info usl light: {int(d['particles'][0])} -> {int(d['particles'][-1])} particles")

EVERY5 = ["fluid.regularise_every=5", "output.interval=0.1"] + FLOW
mt.check_ranks_agree(check, CASE, EVERY5 + ["time.method=usl"], "regularise_ranks",
                     phase="fluid")
mt.check_ranks_agree(check, CASE, EVERY5 + ["time.method=usl"] + LIGHT, "regularise_ranks_light",
                     phase="fluid")
for label, extra in (("usl", ["time.method=usl"]), ("bs32", ["time.method=bs32"]),
                     ("usl light", ["time.method=usl"] + LIGHT)):
    # restart_difference sets time.t_end itself (a key may be given once on the command line)
    args = [a for a in EVERY5 if not a.startswith("time.t_end=")] + extra
    same_ids, worst, _ = mt.restart_difference(CASE, args, T,
                                               f"regularise_restart_{label.replace(' ', '_')}",
                                               phase="fluid")
    check(same_ids and worst == 0.0, f"{label}: restart at t = {T / 2:g} ends bitwise identical "
          f"by id (ids equal: {same_ids}, largest difference {worst:.1e})")

sys.exit(check.finish())
