"""The 3-D sphere at Mach 0.8 on the hierarchy (cases/sphere_m08.ini, issue 52's case C) at a
smoke test's size: the case file itself at 20^3 level-0 cells (grid.dx = 0.5, levels 1 and 2 in
its static boxes, about 115,000 particles) for 3 steps from the impulsive start (~5 s). Checks
that the case is accepted and seeds every level, that it runs, that the mass is constant (no
layer has entered or left through the far-field faces yet, and split and merge conserve it),
that the flow keeps the scene's symmetry about the stream's axis (no momentum across it), and
that the force on the sphere is booked and stays near d'Alembert's zero drag of the potential
flow the case starts from (obstacles.csv).
The scene's cost and stability are bench/bench_sphere.py's (docs/refinement.md, "The 3-D
sphere"); no test runs it at full size.
Able to fail: with the sphere off the axis (obstacle.sphere.center = 4 5.1 5, a second
argument "off") the momentum across the axis check fails.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

OFF = len(sys.argv) > 1 and sys.argv[1] == "off"
check = mt.Checks("test_refine_sphere_smoke")
CASE = os.path.join(mt.SOURCE, "cases", "sphere_m08.ini")
STEPS = 3
DT = 0.01  # below the finest level's stable step at dx = 0.5 (0.4 x 0.125 / 1.8 = 0.028)

out = os.path.join(mt.outdir("refine_sphere_smoke"), "run")
extra = ["obstacle.sphere.center=4 5.1 5"] if OFF else []
mt.run(["run", CASE, f"output.dir={out}", "output.overwrite=true", "run.progress=false",
        "grid.dx=0.5", f"time.dt_max={DT}", f"time.t_end={DT * (STEPS - 0.5)}"] + extra)
d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
levels = [int(d[f"particles_l{level}"][0]) for level in range(3)]
check(int(d["step"][-1]) == STEPS and min(levels) > 0,
      f"{int(d['step'][-1])} steps (expected {STEPS}), particles on every level at the start: "
      f"{' / '.join(map(str, levels))}")
dm = np.abs(d["mass"] / d["mass"][0] - 1).max()
# A sum of ~1.2e5 fixed particle masses (splits and merges keep each group's sum): roundoff.
check(dm <= 1e-12, f"mass constant to {dm:.1e} (bound 1e-12, roundoff) over {STEPS} steps")
across = max(np.abs(d["py"]).max(), np.abs(d["pz"]).max()) / np.abs(d["px"]).max()
# The domain, the lattices, the boxes and the sphere are symmetric about y = 5 and z = 5: the
# momentum across the axis is the roundoff of sums of ~1e5 terms (measured below 1e-15).
check(across <= 1e-12, f"momentum across the stream's axis {across:.1e} of px (bound 1e-12)")
ob = np.genfromtxt(os.path.join(out, "obstacles.csv"), delimiter=",", names=True, dtype=None,
                   encoding=None)
cd = np.atleast_1d(ob["Cd"])
# The potential flow has no drag; the seeded lattice's and the grid's departures from it give a
# little (measured 0.012 after 3 steps); the impulsive start gave 0.8-0.9 over the same steps.
check(len(cd) == STEPS and np.all(np.abs(cd) <= 0.1), f"drag coefficient of the sphere at each "
      f"step {', '.join(f'{c:.3f}' for c in cd)} (|Cd| <= 0.1: the potential start's zero drag)")
sys.exit(check.finish())
