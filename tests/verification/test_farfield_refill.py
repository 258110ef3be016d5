"""A far field where the gas inside slows down: the inflow follows the gas, not the free stream.

Case: cases/acoustic_pulse.ini made uniform (rho = 1, p = 1/1.4, c = 1), moving at U = 0.1
towards a slip wall at x = 2, entering through a farfield face at x = 0 (quasi-1-D: y periodic,
160 x 3 cells). At t = 0 the gas meets the wall; a reflected shock leaves it with the gas at
rest behind it and reaches x = 0 at about t = 2.2. From then on the whole column is at rest at
the reflected pressure p_r, and exactly as much gas should enter as the characteristic boundary
state lets in: u_b . n = (u + u_inf) . n / 2 + (p - p_inf) / 2Z, which is zero to first order
in U when p - p_inf = Z U (the acoustic reflected state), and slightly negative (a trickle out)
for the true weak shock.

Before the refill rule (fluid/fluid_boundary.c: a farfield face's lattice lines refill the gap
their particles leave, in the characteristic boundary state), the face went on injecting the
free-stream lattice at rho_inf U whatever the gas inside did: on this case the column kept
compressing after t = 2.2 and the run blew up at t = 3.84 (its energy grew 1000-fold); the
shock panel's upstream face piled up twice its particles and turned the gas there to noise.

Checks (t = 3 to 5, after the reflected shock has left):
- the mass entering per unit time, relative to the free stream's rho_inf U H: |ratio| <= 0.1.
  Tolerance: the refill adds whole lattice layers (one layer over the window is 3 % of the
  free stream's inflow over it), and the linear characteristic state is first order in the
  shock strength (a few %); the old rule would give 1.0.
- the mean pressure of the column at t = 5 against the exact reflected-shock pressure p_r
  (Rankine-Hugoniot for a gas at U reflected by a wall): within 2 %. The old rule's pile-up
  raises it by about 20 % by then.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_farfield_refill")
GAMMA, RHO, P, U, H = 1.4, 1.0, 1.0 / 1.4, 0.1, 0.0375


def reflected_pressure():
    """p_r of the shock that brings gas moving at U to rest against a wall (bisection on the
    shock's velocity jump, in the gas's frame)."""
    c = np.sqrt(GAMMA * P / RHO)

    def jump(pr):
        r = pr / P
        beta = (GAMMA - 1) / (GAMMA + 1)
        return c / GAMMA * (r - 1) * np.sqrt(2 * GAMMA / (GAMMA + 1) / (r + beta))

    lo, hi = P, 2 * P
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if jump(mid) < U else (lo, mid)
    return 0.5 * (lo + hi)


out = mt.outdir("farfield_refill")
mt.run(["run", mt.case("acoustic_pulse.ini"), f"output.dir={out}", "boundary.x_hi=slip",
        f"freestream.velocity={U} 0", f"gas.air.velocity={U} 0", f"gas.air.density_field={RHO}",
        f"gas.air.pressure_field={P!r}", "time.t_end=5", "output.interval=1", "run.progress=false"])
d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
t, mass = d["t"], d["mass"]
rate = (np.interp(5.0, t, mass) - np.interp(3.0, t, mass)) / 2.0
ratio = rate / (RHO * U * H)
check(abs(ratio) <= 0.1, f"mass entering from t = 3 to 5: {ratio:+.3f} of the free stream's "
      "rho U H (|.| <= 0.1; the free-stream lattice's rule: 1.0)")
pr = reflected_pressure()
last = mt.particles(mt.snapshots(out)[-1][1], "fluid")
p_mean = float(np.sum(last["p"][:, 0] * last["m"][:, 0]) / np.sum(last["m"][:, 0]))
check(abs(p_mean / pr - 1) <= 0.02 and abs(last["time"] - 5) < 1e-9,
      f"mean pressure at t = {last['time']:.3g}: {p_mean:.5f} against the reflected shock's "
      f"{pr:.5f} ({100 * (p_mean / pr - 1):+.2f} %, within 2 %)")
sys.exit(check.finish())
