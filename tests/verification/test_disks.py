"""Two elastic disks colliding head-on (cases/two_disks.ini: E = 1000, nu = 0.3, rho = 1000,
radius 0.2, velocities +-(0.1, 0.1)), under each time method.

- Total momentum starts at zero and must stay at roundoff: |p(t)| <= 1e-12 of the momentum
  scale sum(m |v|) (the grid and particle transfers conserve momentum exactly; only
  additions in a different order remain).
- The total (kinetic + elastic) energy over time is reported for each method, with its
  largest relative change, and plotted (disks_energy.png in the test folder; pass a path as
  the first argument to write it elsewhere).
"""
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_disks")
png = sys.argv[1] if len(sys.argv) > 1 else os.path.abspath("disks_energy.png")
runs = []
for method in ("usl", "musl", "bs32", "zonneveld43", "dp54"):
    out = mt.outdir(f"disks_{method}")
    mt.run(["run", mt.case("two_disks.ini"), f"output.dir={out}", f"time.method={method}",
            "time.t_end=1.5", "output.snapshots=false", "run.progress=false"])
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    scale = d["mass"][0] * np.hypot(0.1, 0.1)
    p = np.hypot(d["px"], d["py"]).max() / scale
    e = d["total"]
    drift = np.abs(e - e[0]).max() / e[0]
    check(p <= 1e-12, f"{method}: max |total momentum| = {p:.2e} of the momentum scale")
    print(f"info {method}: total energy {e[0]:.6e} J at t = 0, largest relative change "
          f"{100 * drift:.3f} %, final {100 * (e[-1] - e[0]) / e[0]:+.3f} %")
    runs.append(f"{method}={out}")

tool = os.path.join(mt.SOURCE, "tools", "plot_series.py")
plot = subprocess.run([sys.executable, tool, png, "total"] + runs, capture_output=True, text=True)
check(plot.returncode == 0 and os.path.exists(png), f"energy plot written to {png}")
sys.exit(check.finish())
