#!/usr/bin/env python3
"""Artificial viscosity forms side by side (fluid.av_form = vnr | riemann) on Sod and Toro's
test 3 (cases/sod.ini, cases/strong_shock.ini), as tests/tools/shocktube.py measures them.

Per run: L1 density error (the test_sod metric), shock position and its error in cells, the
relative scatter of the particle density in the post-shock plateau (std / mean of the particle
densities between the contact and the shock, 3 cells clear of each), and the cost (steps, RHS
evaluations, wall time from summary.json).

  bench/bench_av.py [--cells 200 400 800] [--methods usl bs32] [--forms vnr riemann]
                    [--cases sod toro3] [--extra key=value ...]

Run it from an ignored folder (out/ or build/): each run writes its output folder there.
Needs MPMFSI_BIN (the mpmfsi binary) and /usr/bin/python3 with h5py.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "tools"))
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

CASES = {
    "sod": ("sod.ini", Riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), gamma=1.4, x0=0.5), 0.2),
    "toro3": ("strong_shock.ini", Riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01), gamma=1.4, x0=0.5),
              0.012),
}


def plateau_scatter(P, exact, t, N):
    """std / mean of the particle densities between the contact and the shock, 3 cells clear."""
    x, rho = P["x"][:, 0], P["rho"][:, 0]
    a, b = exact.contact_position(t) + 3.0 / N, exact.shock_position(t) - 3.0 / N
    r = rho[(x > a) & (x < b)]
    return float(np.std(r) / np.mean(r)), float(np.mean(r) / exact.r_star_r - 1.0)


def one(case, N, method, form, extra):
    ini, exact, t = CASES[case]
    out = shocktube.run(ini, N, method, t, 1,
                        [f"output.interval={t}", f"fluid.av_form={form}"] + list(extra))
    l1, xs, P = shocktube.measure(out, N, exact, t)
    sc, bias = plateau_scatter(P, exact, t, N)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    return {"case": case, "N": N, "method": method, "form": form, "L1": l1, "xs": xs,
            "dxs_cells": (xs - exact.shock_position(t)) * N, "scatter": sc, "plateau_bias": bias,
            "steps": s["steps"], "rhs": s["rhs_evals"], "wall": s["wall_s"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[200, 400, 800])
    ap.add_argument("--methods", nargs="+", default=["usl", "bs32"])
    ap.add_argument("--forms", nargs="+", default=["vnr", "riemann"])
    ap.add_argument("--cases", nargs="+", default=["sod", "toro3"])
    ap.add_argument("--extra", nargs="*", default=[])
    a = ap.parse_args()
    print("case   N    method form     L1        shock    dxs/cells scatter  bias     steps "
          "rhs    wall_s")
    for case in a.cases:
        for N in a.cells:
            for method in a.methods:
                for form in a.forms:
                    r = one(case, N, method, form, a.extra)
                    print(f"{r['case']:6s} {N:<4d} {method:6s} {form:8s} {r['L1']:.3e} "
                          f"{r['xs']:.5f}  {r['dxs_cells']:+6.2f}   {r['scatter']:.2e} "
                          f"{r['plateau_bias']:+.1e} {r['steps']:<5d} {r['rhs']:<6d} "
                          f"{r['wall']:.2f}", flush=True)


if __name__ == "__main__":
    main()
