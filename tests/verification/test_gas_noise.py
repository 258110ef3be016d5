"""Particle noise of the gas in a uniform post-shock region (issue 50, item 3): the Mach 2.5 wedge
(cases/wedge.ini, at its own settings, dx = 0.01, t = 1.2), measured by tools/gas_noise.py in
the region where theta-beta-M gives a uniform state (0.4 <= x <= 1 - 4 dx, at least 4 cells
from the ramp and from the exact shock line; rho2 = 1.8663 x 1.4 = 2.6128).

- Scatter: the relative standard deviation of the particles' own density m / (V0 J) there is
  at most 1.68 %: the issue's acceptance, 3 times below the 5.05 % of the case's settings before
  2026-12-02 (fluid.wall_treatment = ghost, the code's default: the gas it traps inside the
  ramp's foot bends the shock and sends ripples downstream). Measured with least_squares, the
  case's treatment now: 1.20 %.
- Mean: within 1 % of rho2 (measured -0.33 %; ghost's -4.7 %, the ripples' kinetic energy
  turned into heat by the exact energy balance). The pressure ratio and the angle are
  test_wedge's.
- The cell field the density strips draw (rho mass-weighted per cell) obeys the same bound
  (measured 1.03 %; ghost 4.16 %).
Check that it fails on the old settings: `test_gas_noise.py ghost` runs the same with
fluid.wall_treatment = ghost (5.05 %: fails).
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "tools"))
import gas_noise  # noqa: E402

OLD = "ghost" in sys.argv[1:]
check = mt.Checks("test_gas_noise" + ("_ghost" if OLD else ""))
BOUND = 0.0505 / 3  # the issue's 3x below the old settings' 5.05 %
out = mt.outdir("gas_noise_wedge" + ("_ghost" if OLD else ""))
extra = ["fluid.wall_treatment=ghost"] if OLD else []
mt.run(["run", mt.case("wedge.ini"), f"output.dir={out}", "run.progress=false"] + extra)
r = gas_noise.measure(gas_noise.load(out), "wedge", 4.0)
check(r["particle"] <= BOUND,
      f"particle density scatters by {100 * r['particle']:.2f} % over {r['particles']} particles "
      f"(bound {100 * BOUND:.2f} %: 3x below the old 5.05 %)")
check(r["cells"] <= BOUND,
      f"the cell field scatters by {100 * r['cells']:.2f} % over {r['ncells']} cells (bound "
      f"{100 * BOUND:.2f} %)")
err = r["particle_mean"] / r["exact"] - 1
check(abs(err) <= 0.01, f"mean density {r['particle_mean']:.4f} against theta-beta-M's "
      f"{r['exact']:.4f} ({100 * err:+.2f} %, tolerance 1 %)")
sys.exit(check.finish())
