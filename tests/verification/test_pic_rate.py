"""The gas's PIC share is a rate (fluid_transfer.c, "The PIC share as a rate"):
fluid.pic_fraction a is the share of a step at the gas's own stable step at time.cfl = 0.4,
h_pic, and any step h takes 1 - (1 - a)^(h / h_pic), so the damping per unit time depends
neither on the step nor on time.cfl. Before 2026-11-29 every step took a, and a gas stepped at a
tenth of its own step (beside a stiff solid under monolithic coupling) was damped ten times as
fast as under multirate; until later that day h_pic was the gas's own step at the run's
time.cfl, so halving time.cfl doubled the damping and the solution did not converge as the step
fell.

The scene isolates the PIC share: gas at rest in a periodic box (cases/gas_box.ini without its
pulse, dx = 1/32, 2 x 2 particles a cell) whose particles carry v_x = U sin(2 pi x / dx). The
particles sit at x = (k + 1/2) dx / 2, so neighbours move at +U and -U, and every node's
momentum, sum S m v, cancels exactly (the quadratic B-spline gives the two particles at dx / 4
and the two at 3 dx / 4 from a node equal weights, with opposite velocities): the grid stays at
rest, FLIP keeps the particles' velocities, and only the PIC share changes them, by the factor
(1 - a_h) a step. U = 1e-6 c, so neither the heat the share makes (U^2 / 2 per unit mass) nor
|v| in the signal c + |v| moves the step by more than 1e-6 (at U = 1e-3 c the step grew by
4e-4 as |v| decayed, and the decay differed from the formula by 4e-5). The artificial
viscosity is off: its linear term acts at any compression, a roundoff-sized one included, and
adds c to the signal, so the gas's own step would halve from one step to the next at random.

1. At the gas's own step (usl, time.cfl = 0.4, a = 0.1) the particles' RMS velocity after
   t = 0.05 is U 0.9^(t / h_pic), h_pic the run's step (diagnostics.csv), within 1e-6
   relative (roundoff and the sound speed's change, about 1e-7).
2. With time.dt_max = h_pic / 4 (four times the steps, the gas not setting its step) the same
   decay, within 1e-6 relative. Blended at a per step it would be 0.9^(4 t / h_pic), about a
   fifth of it here: the check tells the two forms apart.
3. At time.cfl = 0.1 (the gas setting its step, four times the steps) the same decay, within
   1e-6 relative. Stated at the run's own step it would again be 0.9^(4 t / h_pic).
4. At time.cfl = 0.6 (fewer, longer steps: a share above a) the same decay, within 1e-6.
5. Mass and total energy are conserved to roundoff in every run (diagnostics.csv: the PIC
   share's kinetic energy goes to heat): within 1e-12 relative, ten times the random walk of
   19 steps of sums over 4 096 particles (19 sqrt(4096) 1.1e-16 = 1.3e-13; measured 1.0e-13).
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_pic_rate")
CASE = mt.case("gas_box.ini")
DX, T, A = 1.0 / 32, 0.05, 0.1
C = math.sqrt(1.4)  # rho = 1, p = 1
U = 1e-6 * C
COMMON = ["time.method=usl", f"time.t_end={T}", f"output.interval={T}",
          "gas.air.pressure_field=1", f"gas.air.velocity_field={U!r}*sin(2*pi*x/{DX!r}); 0",
          f"grid.dx={DX!r}", f"fluid.pic_fraction={A}", "fluid.av_linear=0", "fluid.av_quadratic=0",
          "run.progress=false"]


def run(label, extra):
    out = mt.outdir("pic_rate_" + label)
    mt.run(["run", CASE, f"output.dir={out}"] + COMMON + extra)
    snaps = mt.snapshots(out)
    v0 = mt.particles(snaps[0][1], "fluid")["v"]
    v1 = mt.particles(snaps[-1][1], "fluid")["v"]
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    rms = lambda v: float(np.sqrt((v ** 2).sum(axis=1).mean()))  # noqa: E731
    drift = max(abs(d["mass"][-1] / d["mass"][0] - 1), abs(d["total"][-1] / d["total"][0] - 1))
    return rms(v1) / rms(v0), d, drift


own, d_own, drift_own = run("own", ["time.cfl=0.4"])
h_pic = float(np.median(d_own["dt"][1:]))
expected = (1 - A) ** (T / h_pic)
check(abs(own / expected - 1) <= 1e-6,
      f"at the gas's own step ({len(d_own['dt']) - 1} steps of {h_pic:.4g} s): RMS velocity "
      f"decayed to {own:.9f} of U, expected 0.9^(t / h_pic) = {expected:.9f} "
      f"({own / expected - 1:+.1e}, tolerance 1e-6)")
per_step = (1 - A) ** (4 * T / h_pic)
drifts = [drift_own]
for label, extra, what in (
        ("quarter", ["time.cfl=0.4", f"time.dt_max={h_pic / 4!r}"], "at a quarter of it"),
        ("cfl01", ["time.cfl=0.1"], "at time.cfl = 0.1"),
        ("cfl06", ["time.cfl=0.6"], "at time.cfl = 0.6")):
    got, d, drift = run(label, extra)
    drifts.append(drift)
    check(abs(got / expected - 1) <= 1e-6,
          f"{what} ({len(d['dt']) - 1} steps): decayed to {got:.9f}, the same per unit time "
          f"({got / expected - 1:+.1e}, tolerance 1e-6; a share of 0.1 a step at a quarter of "
          f"the step would give {per_step:.9f})")
check(max(drifts) <= 1e-12,
      f"mass and total energy conserved: largest relative drift {max(drifts):.1e} "
      "(tolerance 1e-12)")
sys.exit(check.finish())
