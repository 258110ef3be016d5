"""Incompressible lift of an aerofoil by the Hess-Smith panel method, for checking
tools/euler_aerofoil.py in the low-Mach limit.

Constant-strength sources on each panel of the outline and one vortex strength common to all,
the flow tangent at the panel midpoints and the Kutta condition (equal tangential speeds on the
two trailing-edge panels). Prints Cl (Kutta-Joukowski) and its Prandtl-Glauert and
Karman-Tsien corrections to --mach (the latter applied to the Cp distribution and integrated).
  /usr/bin/python3 tools/panel_aerofoil.py [--coords cases/rae2822_coordinates.csv]
      [--alpha 2.31] [--mach 0.3] [--naca 0.12]
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import euler_aerofoil  # noqa: E402


def panel_solution(outline, alpha_deg):
    """Cp at the panel midpoints, their unit normals (out of the body) and lengths, and Cl.
    The outline runs counter-clockwise, so the normal to the right of each panel points out;
    each panel's frame (along it, then that normal) is left-handed, which turns the sign of the
    vortex's velocity and of its Kutta-Joukowski lift."""
    P = outline
    x1, y1, x2, y2 = P[:-1, 0], P[:-1, 1], P[1:, 0], P[1:, 1]
    ln = np.hypot(x2 - x1, y2 - y1)
    tx, ty = (x2 - x1) / ln, (y2 - y1) / ln
    nx, ny = ty, -tx
    mx, my = 0.5 * (x1 + x2), 0.5 * (y1 + y2)
    # in each panel's frame: the field point relative to its start
    X = (mx[:, None] - x1) * tx + (my[:, None] - y1) * ty
    Y = (mx[:, None] - x1) * nx + (my[:, None] - y1) * ny
    lg = np.log(np.hypot(X, Y) / np.hypot(X - ln, Y)) / (2 * np.pi)
    dth = (np.arctan2(Y, X - ln) - np.arctan2(Y, X)) / (2 * np.pi)
    np.fill_diagonal(dth, 0.5)  # a panel's own midpoint: the outer side
    # velocity induced at the midpoints by unit sources (s) and unit vortices (v) on each panel
    sx, sy = lg * tx + dth * nx, lg * ty + dth * ny
    vx, vy = (dth * tx - lg * nx).sum(1), (dth * ty - lg * ny).sum(1)
    a = math.radians(alpha_deg)
    ux, uy = math.cos(a), math.sin(a)
    n = len(ln)
    A = np.zeros((n + 1, n + 1))
    b = np.zeros(n + 1)
    A[:n, :n] = sx * nx[:, None] + sy * ny[:, None]
    A[:n, n] = vx * nx + vy * ny
    b[:n] = -(ux * nx + uy * ny)
    for i in (0, n - 1):  # the Kutta condition
        A[n, :n] += sx[i] * tx[i] + sy[i] * ty[i]
        A[n, n] += vx[i] * tx[i] + vy[i] * ty[i]
        b[n] -= ux * tx[i] + uy * ty[i]
    sol = np.linalg.solve(A, b)
    vt = (ux + sx @ sol[:n] + vx * sol[n]) * tx + (uy + sy @ sol[:n] + vy * sol[n]) * ty
    return 1 - vt * vt, nx, ny, ln, -2 * sol[n] * ln.sum()


def karman_tsien(cp0, mach):
    b = math.sqrt(1 - mach * mach)
    return cp0 / (b + mach * mach / (1 + b) * cp0 / 2)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--coords", default=os.path.join(root, "cases", "rae2822_coordinates.csv"))
    ap.add_argument("--naca", type=float, default=0.0)
    ap.add_argument("--alpha", type=float, default=2.31)
    ap.add_argument("--mach", type=float, default=0.3)
    ap.add_argument("--refine", type=int, default=400, help="panels on the spline outline")
    a = ap.parse_args()
    o = euler_aerofoil.naca4(a.naca) if a.naca > 0 else euler_aerofoil.read_outline(a.coords)
    S = euler_aerofoil.surface_points(o, a.refine)
    S = np.vstack([S, S[:1]])  # closed at the trailing edge
    cp, nx, ny, ln, cl = panel_solution(S, a.alpha)
    al = math.radians(a.alpha)
    kt = karman_tsien(cp, a.mach)
    fx, fy = -(kt * nx * ln).sum(), -(kt * ny * ln).sum()
    fx0, fy0 = -(cp * nx * ln).sum(), -(cp * ny * ln).sum()
    lift0, lift = fy0 * math.cos(al) - fx0 * math.sin(al), fy * math.cos(al) - fx * math.sin(al)
    print(f"incompressible Cl {cl:.5f} (pressure integral {lift0:.5f}); at M {a.mach}: "
          f"Prandtl-Glauert {cl / math.sqrt(1 - a.mach**2):.5f}, Karman-Tsien {lift:.5f}")


if __name__ == "__main__":
    main()
