"""Mass-proportional damping (physics.damping = alpha): every mode's amplitude decays as
exp(-alpha t / 2). The axial bar (cases/axial_bar.ini, N = 50, linear regime v0 = 1e-4) is
run with and without damping; the decay rate is measured from the extrema of the total
momentum over two periods, and the undamped run's own (numerical) decay is subtracted.
Tolerance: 2 % of alpha (the extrema are located to about 1e-4 of a period)."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_damping")
ALPHA = 0.05


def decay_rate(alpha):
    out = mt.outdir(f"damping_{alpha:g}")
    mt.run(["run", mt.case("axial_bar.ini"), f"output.dir={out}", "grid.dx=0.5",
            "domain.hi=26 1", "geometry.bar.hi=25 1", "time.method=usl", "time.t_end=20",
            "solid.bar.velocity_field=1e-4*sin(pi*x/50); 0", f"physics.damping={alpha}",
            "output.snapshots=false", "run.progress=false"])
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    t, p = d["t"], np.abs(d["px"])
    peaks = [(t[i], p[i]) for i in range(1, len(t) - 1) if p[i] >= p[i - 1] and p[i] > p[i + 1]]
    (t0, p0), (t1, p1) = (0.0, p[0]), peaks[-1]
    return -2.0 * np.log(p1 / p0) / (t1 - t0)


numerical = decay_rate(0.0)
measured = decay_rate(ALPHA) - numerical
check(abs(measured - ALPHA) <= 0.02 * ALPHA,
      f"decay rate {measured:.5f} 1/s vs alpha = {ALPHA} (numerical decay of the undamped run "
      f"{numerical:.2e} 1/s subtracted; tolerance 2 %)")
sys.exit(check.finish())
