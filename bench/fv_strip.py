#!/usr/bin/python3
"""The shock-tube problems of the gas benchmarks, and a reference finite-volume solver run on
them in mpmfsi's own strip: the anchor against which bench_sod.py prints mpmfsi's cost at
equal error.

Problems (gamma = 1.4, on [0, 1], a strip of N x 3 cells, exact solution from
tests/tools/riemann.py):
  sod           Sod: (1, 0, 1) | (0.125, 0, 0.1), x0 = 0.5, t = 0.2 (cases/sod.ini);
  toro3         Toro's test 3, the strong shock: (1, 0, 1000) | (1, 0, 0.01), x0 = 0.5,
                t = 0.012 (cases/strong_shock.ini);
  toro3_moving  Toro's test 5: test 3 in a frame moving at u = -19.59745 (the contact at rest,
                the shock crossing the grid at 3.92, the gas at 19.6 through it), x0 = 0.8,
                t = 0.012; the gas leaves through an outflow face at x = 0 and the cold state
                enters through a supersonic inflow face at x = 1 (neither reached by a wave).
                Its error against toro3's is the measure of Galilean invariance.

Solver: the MUSCL-Hancock / HLLC solver of bench/euler_reference.py (class Euler2D, imported,
not copied: van Leer limiter, unsplit, CFL 0.8 on the 2-D rate (|u| + c)/dx + (|v| + c)/dy)
on N x 3 cells of size 1/N, slip walls in y (the same as periodic for a 1-D problem), slip
walls at the x ends for the problems at rest, outflow / inflow for the moving one.

Metric: the one test_sod applies to mpmfsi (tests/tools/shocktube.py): L1 = sum over cells of
|rho_cell - rho_exact_cell| / N, rho_exact_cell the exact solution averaged over the cell
(riemann.Riemann.cell_averages), rho_cell the method's cell average: for mpmfsi the particle
densities joined linearly and averaged over the cell, here the finite-volume cell value (the
mean of the strip's 3 rows, which agree to roundoff). Shock position: riemann.shock_front, as
in test_sod. Star plateaux: the mean density over the middle half of the exact post-shock
plateau (between contact and shock) against the exact rho*_R, and over the middle half of the
left one (between the fan's tail and the contact) against rho*_L, as relative errors.

Wall and CPU time (process_time): the solver's step loop only (numpy, one core, freed memory kept in the heap as
tools/euler_aerofoil.py does), not the set-up nor the measure.

Usage: /usr/bin/python3 bench/fv_strip.py [--problem sod|toro3|toro3_moving|all]
[--cells 100,200,400,...]; prints L1, shock offset, plateau error, steps and wall time.
"""
import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "tools"))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tools"))
import euler_reference as er  # noqa: E402
from euler_aerofoil import keep_heap  # noqa: E402
from riemann import Riemann, cell_profile, shock_front  # noqa: E402

NY = 3  # cells across the strip, as tests/tools/shocktube.py
U_MOVE = -19.59745  # Toro's test 5: minus the star velocity of test 3


class Problem:
    """A Riemann problem on [0, 1]: states (rho, u, p), diaphragm x0, end time t, the mpmfsi
    case it is run from and the overrides that turn that case into this problem."""

    def __init__(self, name, left, right, x0, t, case, open_faces=False):
        self.name, self.left, self.right, self.x0, self.t = name, left, right, x0, t
        self.case, self.open_faces = case, open_faces
        self.exact = Riemann(left, right, gamma=1.4, x0=x0)

    def mpm_overrides(self):
        """Keys added to tests/tools/shocktube.py's own (which place the diaphragm)."""
        if not self.open_faces:
            return []
        return [f"gas.left.velocity={self.left[1]} 0", f"gas.right.velocity={self.right[1]} 0",
                "boundary.x_lo=outflow", "boundary.x_hi=inflow",
                f"freestream.density={self.right[0]}", f"freestream.pressure={self.right[2]}",
                f"freestream.velocity={self.right[1]} 0"]


PROBLEMS = {
    "sod": Problem("sod", (1.0, 0.0, 1.0), (0.125, 0.0, 0.1), 0.5, 0.2, "sod.ini"),
    "toro3": Problem("toro3", (1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), 0.5, 0.012,
                     "strong_shock.ini"),
    "toro3_moving": Problem("toro3_moving", (1.0, U_MOVE, 1000.0), (1.0, U_MOVE, 0.01), 0.8,
                            0.012, "strong_shock.ini", open_faces=True),
}


def measure(problem, xc, prof, N):
    """(L1, shock offset in cells, star-plateau relative errors (right, left)) of a cell
    profile."""
    ex, t = problem.exact, problem.t
    edges = np.linspace(0.0, 1.0, N + 1)
    l1 = float(np.sum(np.abs(prof - ex.cell_averages(edges, t)[0])) / N)
    xs = shock_front(xc, prof, ex.rr, ex.r_star_r, ex.contact_position(t) + 0.02)
    return l1, (xs - ex.shock_position(t)) * N, (plateau_error(problem, xc, prof),
                                                 plateau_error(problem, xc, prof, "left"))


def plateau_error(problem, xc, prof, side="right"):
    """Mean density over the cells whose centres lie in the middle half of an exact star
    plateau, relative to its density (NaN if no cell centre lies there): side 'right', the
    contact-shock plateau (rho*_R); 'left', between the left fan's tail and the contact
    (rho*_L; the problems here have a left rarefaction)."""
    ex, t = problem.exact, problem.t
    if side == "right":
        a, b, ref = ex.contact_position(t), ex.shock_position(t), ex.r_star_r
    else:
        c_star = ex.cl * (ex.p_star / ex.pl) ** ((ex.g - 1) / (2 * ex.g))
        a = ex.x0 + (ex.u_star - c_star) * t
        b, ref = ex.contact_position(t), ex.r_star_l
    sel = (xc >= a + 0.25 * (b - a)) & (xc <= b - 0.25 * (b - a))
    if not sel.any():
        return float("nan")
    return float(prof[sel].mean() / ref - 1.0)


def mpm_measure(problem, P, N):
    """The metric on mpmfsi's final particles P (tests/tools/shocktube.py's profile)."""
    edges = np.linspace(0.0, 1.0, N + 1)
    xc = 0.5 * (edges[1:] + edges[:-1])
    return measure(problem, xc, cell_profile(P["x"][:, 0], P["rho"][:, 0], edges), N)


def solve(name, N, cfl=0.8, limiter="vanleer"):
    """The finite-volume run of problem `name` on N x 3 cells; returns a row of the bench
    (cells, method 'fv', l1, shock_offset_cells, plateau_err, wall_s, steps, rhs_evals = flux
    evaluations = steps, particle_steps = cell-steps)."""
    keep_heap()
    pr = PROBLEMS[name]
    h = 1.0 / N
    ends = ("outflow", ("inflow", (pr.right[0], pr.right[1], 0.0, pr.right[2]))) \
        if pr.open_faces else ("wall", "wall")
    bc = {"xlo": ends[0], "xhi": ends[1], "ylo": "wall", "yhi": "wall"}
    s = er.Euler2D(N, NY, h, h, np.zeros((N, NY), bool), bc,
                   (pr.left[0], 0.0, 0.0, pr.left[2]), limiter, cfl)
    xc = (np.arange(N) + 0.5) * h
    W = np.array([np.where(xc < pr.x0, a, b) for a, b in
                  zip((pr.left[0], pr.left[1], 0.0, pr.left[2]),
                      (pr.right[0], pr.right[1], 0.0, pr.right[2]))])
    s.set_interior(W[:, :, None] * np.ones((1, 1, NY)))
    t0, c0 = time.perf_counter(), time.process_time()
    while s.t < pr.t * (1 - 1e-12):
        s.step(min(s.max_dt(), pr.t - s.t))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    rho = s.primitive()[0, 1:-1, 1:-1]
    l1, off, plat = measure(pr, xc, rho.mean(axis=1), N)
    return {"cells": N, "method": "fv", "particles": N * NY, "l1": l1,
            "shock_offset_cells": off, "plateau_err": plat[0], "plateau_l_err": plat[1],
            "wall_s": wall, "cpu_s": cpu,
            "steps": s.steps,
            "rhs_evals": s.steps, "particle_steps": s.steps * N * NY,
            "first_order_steps": s.first_order_steps,
            "transverse_spread": float(np.ptp(rho, axis=1).max())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--problem", choices=list(PROBLEMS) + ["all"], default="all")
    ap.add_argument("--cells", default="100,200,400,800,1600")
    a = ap.parse_args()
    for name in PROBLEMS if a.problem == "all" else [a.problem]:
        for N in (int(v) for v in a.cells.split(",")):
            r = solve(name, N)
            print(f"{name:<13} N {N:5d}  L1 {r['l1']:.3e}  shock {r['shock_offset_cells']:+.2f}"
                  f" cells  plateaux {100 * r['plateau_l_err']:+.2f} % | "
                  f"{100 * r['plateau_err']:+.2f} %  steps {r['steps']:5d}"
                  f"  wall {r['wall_s']:.3f} s  (first-order steps {r['first_order_steps']},"
                  f" transverse spread {r['transverse_spread']:.1e})", flush=True)


if __name__ == "__main__":
    main()
