#!/usr/bin/python3
"""Particle noise of the gas: the relative scatter of density in a region where the exact
solution is uniform (issue 50, item 3). Run with Debian's /usr/bin/python3 (h5py):

    /usr/bin/python3 tools/gas_noise.py RUN_FOLDER | SNAPSHOT.h5 [--region wedge|bar]
                     [--margin CELLS] [--json]

The region (default: from the case stored in the snapshot, cases/wedge.ini or
cases/supersonic_bar.ini):
  wedge  the uniform post-shock region of the Mach 2.5 wedge (theta-beta-M: shock angle
         36.94 deg from the foot at (0.2, 0), rho2 = 1.8663 rho1 = 2.6128 at rho1 = 1.4), for
         0.4 <= x <= 1 - margin dx, at least `margin` cells (default 4) from the ramp and from
         the exact shock line; the measured shock of dx = 0.01 lies within 1.5 deg of it,
         2 cells at the exit, inside the margin.
  bar    the main job's shocked layer above the bar, behind its bow shock and below the
         expansion off the bar's top: the box x in [80, 100] mm, y in [50, 75] mm (at least 6
         cells behind the shock from 1 ms on, 10 cells above the bar's top). There the exact
         flow is smooth, not uniform (the density falls by about a quarter across the box),
         so the scatter is taken about a least-squares quadratic in x and y fitted to the
         box's values (the quadratic takes the smooth flow; what is left is noise).
For each density it prints the relative standard deviation (std / mean; for `bar` the RMS
residual of the quadratic over the mean) and the mean against the exact value where known:
  particle   the particles' own density m / (V0 J) (the snapshot's `rho`);
  grid       the snapshot's `rho_grid`, the grid's density mapped back to the particles
             (docs/gas.md; snapshots written before 2026-12-02 have none);
  cells      the density strip's field (tools/supersonic_bar.py): the density (rho_grid when
             the snapshot has it, else rho) mass-weighted over each cell, over the cells whose
             centres lie inside the region.
A folder gives its last snapshot. Exit 2 with one line on a bad argument.
"""
import argparse
import glob
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_fields import config_value  # noqa: E402

BETA, THETA, FOOT = 36.94, 15.0, 0.2
RHO1_WEDGE, RHO_RATIO_WEDGE = 1.4, 1.8663  # theta-beta-M, gamma = 1.4, M = 2.5, 15 deg
BAR_BOX = ((0.080, 0.100), (0.050, 0.075))


def fail(msg):
    print(f"gas_noise: {msg}", file=sys.stderr)
    sys.exit(2)


def load(path):
    import h5py
    if os.path.isdir(path):
        snaps = sorted(glob.glob(os.path.join(path, "snap_*.h5")))
        if not snaps:
            fail(f"{path}: no snap_*.h5 in it: give a run folder or a snapshot")
        path = snaps[-1]
    if not os.path.isfile(path):
        fail(f"{path}: no such file or folder")
    with h5py.File(path, "r") as f:
        if "fluid" not in f:
            fail(f"{path}: the snapshot has no gas (group 'fluid')")
        g = f["fluid"]
        P = {k: g[k][()] for k in g if k != "id"}
        cfg = f.attrs["config"]
        P["time"] = float(f.attrs["time"])
    P["config"] = cfg.decode() if isinstance(cfg, bytes) else str(cfg)
    P["path"] = path
    return P


def region_mask(kind, x, y, dx, margin):
    if kind == "wedge":
        tw, tb = math.tan(math.radians(THETA)), math.tan(math.radians(BETA))
        d_ramp = (y - (x - FOOT) * tw) * math.cos(math.radians(THETA))
        d_shock = ((x - FOOT) * tb - y) * math.cos(math.radians(BETA))
        return (x >= 0.4) & (x <= 1.0 - margin * dx) & (d_ramp >= margin * dx) & (
            d_shock >= margin * dx)
    (x0, x1), (y0, y1) = BAR_BOX
    return (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)


def scatter(kind, x, y, v, w=None):
    """Relative scatter of v: std / mean for the wedge, RMS residual of a quadratic fit for
    bar."""
    w = np.ones_like(v) if w is None else w
    mean = float(np.average(v, weights=w))
    if kind == "wedge":
        r = v - mean
    else:
        X, Y = (x - BAR_BOX[0][0]) / 0.01, (y - BAR_BOX[1][0]) / 0.01
        A = np.column_stack([np.ones_like(X), X, Y, X * X, X * Y, Y * Y])
        sw = np.sqrt(w)
        coef = np.linalg.lstsq(A * sw[:, None], v * sw, rcond=None)[0]
        r = v - A @ coef
    return float(np.sqrt(np.average(r * r, weights=w)) / mean), mean


def measure(P, kind, margin):
    dx = float(config_value(P["config"], "grid", "dx"))
    lo = [float(s) for s in config_value(P["config"], "domain", "lo").split()]
    hi = [float(s) for s in config_value(P["config"], "domain", "hi").split()]
    x, y = P["x"][:, 0], P["x"][:, 1]
    m = P["m"][:, 0]
    raw = P["m"][:, 0] / (P["V0"][:, 0] * P["J"][:, 0])
    out = P["rho_grid"][:, 0] if "rho_grid" in P else None
    sel = region_mask(kind, x, y, dx, margin)
    if sel.sum() < 20:
        fail(f"{P['path']}: only {sel.sum()} particles in the {kind} region: not a run of the "
             f"{'wedge' if kind == 'wedge' else 'supersonic bar'} case?")
    res = {"snapshot": P["path"], "time": P["time"], "region": kind, "dx": dx,
           "margin_cells": margin, "particles": int(sel.sum())}
    res["particle"], res["particle_mean"] = scatter(kind, x[sel], y[sel], raw[sel])
    if out is not None:
        res["grid"], res["grid_mean"] = scatter(kind, x[sel], y[sel], out[sel])
    else:
        out = raw
    # The strip's cell field: rho mass-weighted over each cell, cells whose centre is inside.
    nx, ny = int(round((hi[0] - lo[0]) / dx)), int(round((hi[1] - lo[1]) / dx))
    rng = ((lo[0], hi[0]), (lo[1], hi[1]))
    M = np.histogram2d(x, y, bins=(nx, ny), range=rng, weights=m)[0]
    R = np.histogram2d(x, y, bins=(nx, ny), range=rng, weights=m * out)[0]
    cx = lo[0] + (np.arange(nx) + 0.5) * dx
    cy = lo[1] + (np.arange(ny) + 0.5) * dx
    CX, CY = np.meshgrid(cx, cy, indexing="ij")
    csel = region_mask(kind, CX, CY, dx, margin) & (M > 0)
    res["cells"], res["cells_mean"] = scatter(kind, CX[csel], CY[csel], R[csel] / M[csel])
    res["ncells"] = int(csel.sum())
    if kind == "wedge":
        res["exact"] = RHO1_WEDGE * RHO_RATIO_WEDGE
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("path", help="a run folder (its last snapshot) or a snapshot .h5")
    ap.add_argument("--region", choices=("wedge", "bar"), help="default: from the case name")
    ap.add_argument("--margin", type=float, default=4.0,
                    help="wedge: cells kept from the shock, the ramp and the exit (default 4)")
    ap.add_argument("--json", action="store_true", help="print the figures as one JSON line")
    a = ap.parse_args()
    P = load(a.path)
    kind = a.region
    if kind is None:
        name = config_value(P["config"], "run", "name", "")
        kind = "wedge" if "wedge" in name else "bar" if "supersonic_bar" in name else None
        if kind is None:
            fail(f"{P['path']}: run.name '{name}' is neither wedge nor supersonic_bar: give "
                 "--region")
    r = measure(P, kind, a.margin)
    if a.json:
        print(json.dumps(r))
        return 0
    exact = f", exact {r['exact']:.4f}" if "exact" in r else ""
    print(f"{r['snapshot']} t = {r['time']:g}, region {kind} ({r['particles']} particles, "
          f"{r['ncells']} cells{exact})")
    for k in ("particle", "grid", "cells"):
        if k in r:
                print(f"  {k:9s} relative scatter {100 * r[k]:6.3f} %  mean {r[k + '_mean']:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
