"""The gas's stable-step estimates (fluid.stable_step, fluid/fluid_module.c and fluid_stable.c).

Case: cases/gas_box.ini (periodic unit square, 32 x 32 cells, 4 particles per cell, usl, its
pressure bump p = 1 + 0.5 exp(-r^2 / 0.01)) with a light, hot spot: rho = 1 - 0.999
exp(-r^2 / 0.001) about the centre (particle masses follow the density; the sound speed
sqrt(gamma p / rho) reaches 46 against 1.18 far from it). Runs to t = 0.05. The first step of a classic update is time.cfl (0.4) times the estimate at
t = 0, so diagnostics.csv's first dt gives the estimate exactly. Checks:

1. `particle`: the first dt equals 0.4 dx / max_p (c_p + |v_p|) computed here from the t = 0
   snapshot, to 1e-12 relative (the same formula in another order of operations; at rest and
   before any compression the artificial-viscosity term is 0).
2. `neighbourhood`: the first dt equals 0.4 dx / max_c (sqrt(sum m c^2 / sum m) + sum m |v| /
   sum m) over the 3 x 3 cells around each cell (periodic), computed here, to 1e-12.
3. The spot's light particles set the particle estimate but not the neighbourhood one: the
   neighbourhood step is at least twice the particle step (measured 2.52: the spot is about
   one cell wide, so the 3 x 3 block around its centre is light too, but its heavier rim
   cells carry most of the block's mass; a particle-wise estimate gives 1.0).
4. Uniform gas at rest (p = 1, rho = 1): both estimates give the same step, to 1e-12 (for
   equal particles the mass-weighted means are the particle values).
5. 2 ranks give the neighbourhood step of 1 rank, to 1e-12 (the per-cell sums are taken on
   the rank owning the cell and shared by the halo), and the run to t = 0.05 stays stable:
   its total energy in diagnostics.csv changes by under 1e-10 relative (a periodic box at
   rest conserves it to roundoff under usl, as test_gas_conservation measures).
"""
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_stable_step")
CASE = mt.case("gas_box.ini")
DX, CFL, GAMMA, N = 1.0 / 32, 0.4, 1.4, 32
SPOT = "1 - 0.999*exp(-((x-0.5)^2 + (y-0.5)^2)/0.001)"
BASE = ["time.method=usl", "output.interval=0.05", "time.t_end=0.05"]


def case_with_density(out, density):
    """gas_box.ini with its constant density replaced by an expression."""
    with open(CASE) as f:
        text = f.read()
    assert "\ndensity = 1\n" in text
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(text.replace("\ndensity = 1\n", f"\ndensity_field = {density}\n"))
    return path


def run(name, estimate, density, ranks=1, extra=()):
    out = mt.outdir(name)
    case = case_with_density(out, density)
    args = ["run", case, f"output.dir={out}/run", f"fluid.stable_step={estimate}"] + BASE
    args += list(extra)
    out = os.path.join(out, "run")
    mt.run(args, ranks=ranks)
    with open(os.path.join(out, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    return out, rows


def estimates(out):
    """(particle, neighbourhood) steps computed from the t = 0 snapshot."""
    p = mt.particles(mt.snapshots(out)[0][1], "fluid")
    c = np.sqrt(GAMMA * (GAMMA - 1.0) * np.abs(p["e"][:, 0]))
    speed = np.hypot(p["v"][:, 0], p["v"][:, 1])
    m = p["m"][:, 0]
    particle = CFL * DX / np.max(c + speed)
    cell = np.clip(np.floor(p["x"] / DX).astype(int), 0, N - 1)
    sums = np.zeros((3, N, N))
    for k, w in enumerate((m, m * c * c, m * speed)):
        np.add.at(sums[k], (cell[:, 0], cell[:, 1]), w)
    block = sum(np.roll(np.roll(sums, i, axis=1), j, axis=2)
                for i in (-1, 0, 1) for j in (-1, 0, 1))
    s = np.sqrt(block[1] / block[0]) + block[2] / block[0]
    return particle, CFL * DX / np.max(s)


def first_dt(rows):
    return float(rows[1]["dt"])


def rel(a, b):
    return abs(a - b) / abs(b)


out_p, rows_p = run("stable_particle", "particle", SPOT)
exp_p, exp_n = estimates(out_p)
check(rel(first_dt(rows_p), exp_p) < 1e-12,
      f"particle: first dt {first_dt(rows_p):.6e} s, computed {exp_p:.6e} s "
      f"(difference {rel(first_dt(rows_p), exp_p):.1e}, tolerance 1e-12)")
out_n, rows_n = run("stable_neighbourhood", "neighbourhood", SPOT)
check(rel(first_dt(rows_n), exp_n) < 1e-12,
      f"neighbourhood: first dt {first_dt(rows_n):.6e} s, computed {exp_n:.6e} s "
      f"(difference {rel(first_dt(rows_n), exp_n):.1e}, tolerance 1e-12)")
ratio = first_dt(rows_n) / first_dt(rows_p)
check(ratio >= 2.0, f"light hot spot: neighbourhood step / particle step = {ratio:.2f} (>= 2)")

UNIFORM = ["gas.air.pressure_field=1"]
_, rows_up = run("stable_uniform_p", "particle", "1", extra=UNIFORM)
_, rows_un = run("stable_uniform_n", "neighbourhood", "1", extra=UNIFORM)
d = rel(first_dt(rows_un), first_dt(rows_up))
check(d < 1e-12, f"uniform gas: both estimates {first_dt(rows_up):.6e} s "
      f"(difference {d:.1e}, tolerance 1e-12)")

_, rows_2 = run("stable_neighbourhood_np2", "neighbourhood", SPOT, ranks=2)
d = rel(first_dt(rows_2), first_dt(rows_n))
check(d < 1e-12, f"2 ranks: first dt {first_dt(rows_2):.6e} s against 1 rank's "
      f"(difference {d:.1e}, tolerance 1e-12)")
E = np.array([float(r["total"]) for r in rows_2])
drift = np.max(np.abs(E - E[0])) / abs(E[0])
check(float(rows_2[-1]["t"]) >= 0.05 - 1e-12 and drift < 1e-10,
      f"2 ranks to t = {float(rows_2[-1]['t']):.3f} in {len(rows_2) - 1} steps: total energy "
      f"drift {drift:.1e} (tolerance 1e-10)")
sys.exit(check.finish())
