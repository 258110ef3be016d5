"""The inviscid reference behind the RAE 2822 figures (tools/euler_aerofoil.py), checked on its
coarsest grid against the grid of the committed reference (bench/results/rae2822_euler_cp.csv,
written by bench/bench_euler_reference.py), and on a symmetric aerofoil. The low-Mach check
against the panel method is the bench's (it takes 10 minutes).

a) RAE 2822, M 0.729, alpha 2.31 deg, 192 x 64 cells: the density residual falls 1e5-fold
   (a steady state is reached), and against the reference grid (384 x 128): Cl within 2 %, the
   upper-surface shock within 0.01 c, the Cp RMS difference (stations every 0.01 c) at most
   0.07 on the upper surface and 0.01 on the lower. Measured: -1.28 %, 0.003 c, 0.045, 0.005
   (bench/results/rae2822_euler.md); the tolerances are about 1.5 times the coarse grid's own
   distance from the reference (0.01 at least), so that its discretisation error passes and a
   broken flux, boundary or dissipation switch, which moves these by far more, fails.
b) The symmetric NACA 0012 at alpha 0 (M 0.5, 192 x 64, 300 iterations): Cl = 0 to 1e-12,
   since the grid and the scheme are mirror-symmetric (an orientation or sign slip would lift).
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, os.path.join(HERE, "..", "tools"))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import euler_aerofoil as E  # noqa: E402
import mpmtest as mt  # noqa: E402
import rae2822  # noqa: E402

check = mt.Checks("test_euler_reference")

with open(rae2822.REFERENCE) as f:
    refrun = json.loads(f.readline()[1:])
ref = rae2822.reference()

s, mesh, cl, cd, pw, hist, wall = E.solve(E.read_outline(mt.case("rae2822_coordinates.csv")),
                                          0.729, 2.31, 192, 64, 0.002, 40.0, 20000, 1e-5, 2.5,
                                          log=False)
cp = {"upper": [], "lower": []}
for x, side, p in zip(mesh.wall_mid[:, 0], E.sides(mesh), pw):
    cp[side].append((x, (p - s.p0) / s.q))
cp = {k: sorted(v) for k, v in cp.items()}
print(f"192 x 64: {hist[-1][0]} iterations, {wall:.0f} s, Cl {cl:.4f} (reference "
      f"{refrun['cl']:.4f}), Cd {cd:.5f} (reference {refrun['cd']:.5f})")
check(hist[-1][1] < 1e-5, f"converged: the residual fell to {hist[-1][1]:.2e} (1e-5)")
check(abs(cl / refrun["cl"] - 1) <= 0.02,
      f"Cl {cl:.4f} against the reference grid's {refrun['cl']:.4f}: "
      f"{100 * (cl / refrun['cl'] - 1):+.2f} % (tolerance 2 %)")
shock, shock_ref = rae2822.shock_position(cp["upper"]), rae2822.shock_position(ref["upper"])
check(shock is not None and abs(shock - shock_ref) <= 0.01,
      f"shock at x/c {shock or float('nan'):.4f} against the reference grid's {shock_ref:.4f} "
      "(tolerance 0.01)")
for side, tol in (("upper", 0.07), ("lower", 0.01)):
    d = rae2822.rms_against(cp, ref, side, 0.01)
    check(d <= tol, f"Cp RMS to the reference grid, {side} surface: {d:.4f} (tolerance {tol})")

outline = E.naca4(0.12, 101)
s, mesh, cl, cd, pw, hist, wall = E.solve(outline, 0.5, 0.0, 192, 64, 0.002, 40.0, 300, 0.0, 2.5,
                                          log=False)
check(abs(cl) < 1e-12, f"NACA 0012 at alpha 0: Cl {cl:.2e} (tolerance 1e-12)")
sys.exit(check.finish())
