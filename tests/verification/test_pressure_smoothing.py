"""fluid.pressure_smoothing (fluid/fluid_pressure_grid.c): a grid-smoothed share w of the gas
pressure in the particles' stress, with an energy booking that keeps total energy exact.

The closed box of test_gas_conservation (cases/gas_box.ini: a gaussian pressure pulse that
steepens into a weak shock ring, to t = 0.5) with w = 1, the whole pressure smoothed:

1. usl and musl, periodic faces and slip walls: total energy drift <= 1e-12 relative
   (test_gas_conservation's bound for the classic update: roundoff over ~80 steps). It holds
   only because each particle's energy takes its own pressure's work plus its share, through
   the same average, of what the smoothed pressure did beyond it; that share sums exactly to
   the difference. Measured with the share left out (own work only): drift 3.1e-3 usl,
   5.0e-3 musl, 4.8e-3 bs32 (fails).
2. bs32 (adaptive, time.rtol 1e-6): drift <= 1e-6, the pair's own time error
   (test_gas_conservation's bound; the semi-discrete system conserves energy exactly).
3. Mass to 1e-14 and momentum to 1e-13 sqrt(2 M K_max) in each run (test_gas_conservation's
   bounds: the force is still sum V sigma grad S, whose nodal sum is zero).
4. usl with slip walls on 2 ranks (split along x) against 1, by particle id: every field within
   1e-12 relative (sums in another order): the nodal sums are reduced over the ranks' halos.
5. A uniform gas at rest stays at rest (slip walls, w = 1): the average of a uniform pressure is
   that pressure; no particle moves (velocities exactly 0 over 0.05).
6. w = 0 (the default) gives bit for bit what a run without the key gives.

On the old code the key is unknown and every run exits 2, so every check fails. What the option
does to accuracy (worse on Sod and on the ERK grid-scale mode) is in docs/gas.md: this test only
holds its conservation and parallel properties, which any use of it relies on.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_pressure_smoothing")
CASE = mt.case("gas_box.ini")
WALLS = [f"boundary.{a}=slip" for a in ("x_lo", "x_hi", "y_lo", "y_hi")]
ON = ["fluid.pressure_smoothing=1"]


def run(label, extra, ranks=1, snaps=False):
    out = mt.outdir("psmooth_" + label.replace(" ", "_").replace("=", ""))
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"]
           + ([] if snaps else ["output.snapshots=false"]) + extra, ranks=ranks)
    return out


def totals(label, extra, e_tol):
    out = run(label, ON + extra)
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    M, K = d["mass"][0], float(d["kinetic"].max())
    dM = float(np.abs(d["mass"] - M).max() / M)
    dP = float(max(np.abs(d[c]).max() for c in ("px", "py")) / np.sqrt(2 * M * K))
    dE = float(np.abs(d["total"] - d["total"][0]).max() / d["total"][0])
    check(K > 1e-4 * d["total"][0], f"{label}: the pulse moves the gas (K_max {K:.2e})")
    check(dM <= 1e-14, f"{label}: mass drift {dM:.1e} (<= 1e-14)")
    check(dP <= 1e-13, f"{label}: momentum {dP:.1e} of sqrt(2 M K_max) (<= 1e-13)")
    check(dE <= e_tol, f"{label}: total energy drift {dE:.1e} over {len(d) - 1} steps "
          f"(<= {e_tol:g})")


for method in ("usl", "musl"):
    totals(method, [f"time.method={method}"], 1e-12)
    totals(f"{method} slip walls", [f"time.method={method}"] + WALLS, 1e-12)
totals("bs32", ["time.method=bs32"], 1e-6)

res = []
for r in (1, 2):
    out = run(f"ranks{r}", ON + WALLS + ["time.method=usl", "time.t_end=0.2", "output.interval=0.2"]
              + (["grid.ranks=2 1"] if r == 2 else []), ranks=r, snaps=True)
    res.append(mt.particles(mt.snapshots(out)[-1][1], "fluid"))
same = np.array_equal(res[0]["id"], res[1]["id"])
diff = mt.worst_difference(res[0], res[1])[0] if same else np.inf
check(same and diff <= 1e-12, f"usl, slip walls, 2 ranks vs 1 by id: largest relative difference "
      f"{diff:.1e} over every field (<= 1e-12)")

out = run("rest", ON + WALLS + ["time.method=usl", "time.t_end=0.05", "output.interval=0.05",
                                "gas.air.pressure_field=1"], snaps=True)
snaps = mt.snapshots(out)
dv = float(np.abs(mt.particles(snaps[-1][1], "fluid")["v"]).max())
check(dv == 0.0 and len(snaps) > 1, f"uniform gas at rest, w = 1: largest velocity {dv:.1e} "
      "(must be 0)")

base = ["time.method=usl", "time.t_end=0.1", "output.interval=0.1"]
a, b = (mt.particles(mt.snapshots(run(f"w0_{k}", base + x, snaps=True))[-1][1], "fluid")
        for k, x in (("default", []), ("zero", ["fluid.pressure_smoothing=0"])))
same = all(np.array_equal(a[f], b[f]) for f in ("id", "x", "v", "e", "J"))
check(same, "w = 0 and no key: the same particles bit for bit (ids, x, v, e, J)")

sys.exit(check.finish())
