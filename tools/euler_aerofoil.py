"""Inviscid reference for an aerofoil: a steady 2-D Euler solution on a body-fitted O-grid.

The RAE 2822 case (cases/rae2822.ini) is inviscid, and the experiment it is compared with is
not: this solver gives the converged inviscid solution at the same Mach number and angle, so
that the gas module's error (MPM against Euler, under refinement) can be told apart from the
model's (Euler against the experiment). It is a reference tool, not part of the framework.

Method (Jameson, Schmidt & Turkel 1981, AIAA 81-1259): cell-centred finite volumes; central
fluxes with blended second/fourth-difference dissipation on (rho, rho u, rho v, rho H) scaled by
the face's spectral radius (kappa2 = 1/2, kappa4 = 1/32), a shock sensor on the pressure; the
4-stage Runge-Kutta scheme with local time steps towards the steady state; slip wall (pressure
flux only); far field by Riemann invariants, the free stream corrected by the compressible point
vortex of the current lift (Usab & Murman 1983). The grid: Hermite transfinite lines from the
surface (leaving it along its normal) to a circle of radius --radius chords; --ni points around
(clustered at the leading and trailing edges), --nj cells out, the first --wall chords thick.

Writes CSV: x/c, side, Cp at the wall faces (cp: linear from the first two cells; cp_cell: the
first cell's); prints Cl, Cd (from each), the density residual.
  /usr/bin/python3 tools/euler_aerofoil.py [--coords cases/rae2822_coordinates.csv]
      [--mach 0.729] [--alpha 2.31] [--ni 320] [--nj 96] [--out cp.csv] [--json out.json]
"""
import argparse
import ctypes
import csv
import json
import math
import os
import sys
import time

import numpy as np
from scipy.interpolate import CubicSpline

GAMMA = 1.4
K2, K4 = 0.5, 1.0 / 32.0
STAGES = (0.25, 1.0 / 3.0, 0.5, 1.0)


def keep_heap():
    """Keep freed memory in the heap. Each numpy temporary here is a few hundred KiB, above
    glibc's mmap and trim thresholds, so every operation would map fresh pages and unmap them
    again: measured on the NACA 0012 check (192 x 64, 300 iterations), 17.9 s of CPU time, a
    third of it in the kernel, against 4.8 s with the heap kept. No effect off glibc."""
    try:
        libc = ctypes.CDLL(None)
        libc.mallopt(-1, 1 << 30)  # M_TRIM_THRESHOLD
        libc.mallopt(-3, 1 << 30)  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):
        pass


def read_outline(path):
    """The outline's points (x, y), upper surface from the trailing edge, then lower."""
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    head = rows[0]
    ix, iy = head.index("x_over_c"), head.index("y_over_c")
    return np.array([[float(r[ix]), float(r[iy])] for r in rows[1:]])


def naca4(t, n=201):
    """A symmetric NACA 4-digit outline of thickness t with a closed trailing edge, in the
    same order as read_outline."""
    x = 0.5 * (1 - np.cos(np.linspace(0.0, np.pi, n)))
    y = 5 * t * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    up = np.stack([x[::-1], y[::-1]], 1)
    lo = np.stack([x[1:], -y[1:]], 1)
    return np.vstack([up, lo])


def surface_points(outline, ni):
    """ni points on a cubic spline through the outline (by arc length), cosine-clustered at
    the leading and trailing edges; the trailing edge once (point 0)."""
    d = np.hypot(*np.diff(outline, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(d)])
    sx, sy = CubicSpline(s, outline[:, 0]), CubicSpline(s, outline[:, 1])
    ss = np.linspace(0, s[-1], 20001)
    s_le = ss[np.argmin(sx(ss))]
    half = ni // 2
    u = np.linspace(0.0, 1.0, half + 1)
    w = 0.5 * (1 - np.cos(np.pi * u))
    g = 0.85 * w + 0.15 * u
    t = np.concatenate([s_le * g[:-1], s_le + (s[-1] - s_le) * g])
    t = t[:-1]  # the trailing edge once
    return np.stack([sx(t), sy(t)], 1)


def make_grid(outline, ni, nj, wall, radius, lead=2.0, smooth=1000):
    """Node coordinates X[i, j, :] (i around, periodic; j = 0 on the surface, nj on the circle)."""
    S = surface_points(outline, ni)
    # the surface's outward normal at each point (central differences; the trailing edge takes
    # the bisector of its two sides)
    T = np.roll(S, -1, axis=0) - np.roll(S, 1, axis=0)
    N = np.stack([T[:, 1], -T[:, 0]], 1)
    N /= np.hypot(*N.T)[:, None]
    centre = np.array([0.5, 0.0])
    if np.dot(N[ni // 4], S[ni // 4] - centre) < 0:
        N = -N
    theta = np.unwrap(np.arctan2(S[:, 1] - centre[1], S[:, 0] - centre[0]))
    C = centre + radius * np.stack([np.cos(theta), np.sin(theta)], 1)
    # geometric ring distances from the wall, normalised to 1 at the circle
    lo, hi = 1.0, 1.5
    for _ in range(200):
        r = 0.5 * (lo + hi)
        total = wall * (r**nj - 1) / (r - 1)
        lo, hi = (r, hi) if total < radius else (lo, r)
    dist = np.concatenate([[0.0], wall * np.cumsum(r ** np.arange(nj))])
    g = dist / dist[-1]
    X = np.empty((ni, nj + 1, 2))
    sp = np.linspace(0.0, 1.0, 4001)
    h00, h10 = 2 * sp**3 - 3 * sp**2 + 1, sp**3 - 2 * sp**2 + sp
    h01, h11 = -2 * sp**3 + 3 * sp**2, sp**3 - sp**2
    for i in range(ni):
        L = np.hypot(*(C[i] - S[i]))
        er = (C[i] - centre) / radius
        P = (h00[:, None] * S[i] + h10[:, None] * lead * N[i] + h01[:, None] * C[i]
             + h11[:, None] * L * er)
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(P, axis=0).T))])
        at = g * arc[-1]
        X[i, :, 0] = np.interp(at, arc, P[:, 0])
        X[i, :, 1] = np.interp(at, arc, P[:, 1])
    X[:, 0] = S
    # smooth each ring along itself, little near the wall (the lines leave it along the normal)
    # and fully from a chord out: this takes the crossings out of the lines that leave the
    # concave aft lower surface and the trailing edge
    # (the circle too, put back on it after each pass)
    w = np.minimum(1.0, dist / 1.0)[None, 1:, None] ** 2
    for _ in range(smooth):
        X[:, 1:] += 0.5 * w * (0.5 * (np.roll(X, 1, axis=0) + np.roll(X, -1, axis=0))[:, 1:]
                               - X[:, 1:])
        out = X[:, -1] - centre
        X[:, -1] = centre + radius * out / np.hypot(*out.T)[:, None]
    return X


class Mesh:
    """Cell volumes and centres, and the face area vectors of an O-grid's nodes X: i-faces
    (along the rings' normals, pointing from cell i-1 to cell i) and j-faces (pointing out,
    face 0 the wall and face nj the far circle)."""

    def __init__(self, X):
        self.X = X
        ni, nj1, _ = X.shape
        self.ni, self.nj = ni, nj1 - 1
        A = X[:, :-1]
        B = np.roll(X, -1, axis=0)[:, :-1]
        Cn = np.roll(X, -1, axis=0)[:, 1:]
        D = X[:, 1:]
        self.vol = 0.5 * ((Cn[..., 0] - A[..., 0]) * (D[..., 1] - B[..., 1])
                          - (Cn[..., 1] - A[..., 1]) * (D[..., 0] - B[..., 0]))
        sign = np.sign(self.vol.mean())
        self.vol *= sign
        if (self.vol <= 0).any():
            k = np.argwhere(self.vol <= 0)[0]
            raise SystemExit(f"euler_aerofoil: the grid folds at cell {tuple(k)}: lower --radius "
                             "or raise --ni")
        self.xc = 0.25 * (A + B + Cn + D)
        # i-faces: face i is the edge X[i, j] -> X[i, j+1], between cells i-1 and i
        e = X[:, 1:] - X[:, :-1]
        self.Si = np.stack([e[..., 1], -e[..., 0]], 0)  # (2, ni, nj)
        # j-faces: face j is the edge X[i, j] -> X[i+1, j], between cells j-1 and j
        e = np.roll(X, -1, axis=0) - X
        self.Sj = np.stack([-e[..., 1], e[..., 0]], 0)  # (2, ni, nj+1)
        # orient: i-faces point from cell i-1 to cell i, j-faces outward
        di = self.xc - np.roll(self.xc, 1, axis=0)
        if (self.Si[0] * di[..., 0] + self.Si[1] * di[..., 1]).mean() < 0:
            self.Si = -self.Si
        out = X[:, 1] - X[:, 0]
        if (self.Sj[0, :, 0] * out[:, 0] + self.Sj[1, :, 0] * out[:, 1]).mean() < 0:
            self.Sj = -self.Sj
        wall = self.Sj[:, :, 0]
        self.nw = wall / np.hypot(*wall)  # unit outward (into the gas) normal at the wall
        far = self.Sj[:, :, -1]
        self.nf = far / np.hypot(*far)
        self.wall_mid = 0.5 * (X[:, 0] + np.roll(X, -1, axis=0)[:, 0])
        self.far_mid = 0.5 * (X[:, -1] + np.roll(X, -1, axis=0)[:, -1])


def primitive(W):
    rho = W[0]
    u, v = W[1] / rho, W[2] / rho
    p = (GAMMA - 1) * (W[3] - 0.5 * rho * (u * u + v * v))
    return rho, u, v, p


def flux(W, p, S):
    rho, u, v = W[0], W[1] / W[0], W[2] / W[0]
    un = u * S[0] + v * S[1]
    return np.stack([rho * un, W[1] * un + p * S[0], W[2] * un + p * S[1], (W[3] + p) * un])


def face_fluxes(W, p, S):
    """The JST flux through faces with area vectors S, each between cells -1 and 0 of the four
    consecutive cells whose states W and pressures p are given (cells -2, -1, 0, +1): the
    central flux less the blended dissipation of (rho, rho u, rho v, rho H), scaled by the
    face's spectral radius; and that radius."""
    u = [w[1] / w[0] for w in W]
    v = [w[2] / w[0] for w in W]
    c = [np.sqrt(GAMMA * np.maximum(pk, 1e-12) / w[0]) for w, pk in zip(W, p)]
    H = [np.concatenate([w[:3], (w[3] + pk)[None]]) for w, pk in zip(W, p)]
    F = 0.5 * (flux(W[1], p[1], S) + flux(W[2], p[2], S))
    # the pressure sensor of cells -1 and 0 (cell -1's reads cell -2 and 0; cell 0's, cell +1)
    nu_m = np.abs(p[2] - 2 * p[1] + p[0]) / (p[2] + 2 * p[1] + p[0])
    nu_0 = np.abs(p[3] - 2 * p[2] + p[1]) / (p[3] + 2 * p[2] + p[1])
    e2 = K2 * np.maximum(nu_m, nu_0)
    e4 = np.maximum(0.0, K4 - e2)
    lam = 0.5 * (np.abs(u[1] * S[0] + v[1] * S[1]) + np.abs(u[2] * S[0] + v[2] * S[1])) \
        + 0.5 * (c[1] + c[2]) * np.hypot(*S)
    d1 = H[2] - H[1]
    d3 = H[3] - 3 * H[2] + 3 * H[1] - H[0]
    return F - lam * (e2 * d1 - e4 * d3), lam


class Solver:
    """The conserved state W (rho, rho u, rho v, rho E) per cell, non-dimensional: free-stream
    density 1 and speed of sound 1, so p = 1/gamma and the speed is the Mach number."""

    def __init__(self, mesh, mach, alpha_deg, cfl=2.5):
        self.m, self.mach, self.cfl = mesh, mach, cfl
        self.alpha = math.radians(alpha_deg)
        self.rho0, self.p0 = 1.0, 1.0 / GAMMA  # c = 1
        self.u0 = mach * np.array([math.cos(self.alpha), math.sin(self.alpha)])
        ni, nj = mesh.ni, mesh.nj
        W = np.empty((4, ni, nj))
        W[0] = self.rho0
        W[1], W[2] = self.rho0 * self.u0[0], self.rho0 * self.u0[1]
        W[3] = self.p0 / (GAMMA - 1) + 0.5 * self.rho0 * mach**2
        self.W = W
        self.cl = 0.0
        self.q = 0.5 * self.rho0 * mach**2

    def far_state(self):
        """The free stream at the far faces, with the compressible point vortex of Cl."""
        m = self.m
        xr = m.far_mid - np.array([0.25, 0.0])
        r = np.hypot(*xr.T)
        th = np.arctan2(xr[:, 1], xr[:, 0])
        beta = math.sqrt(1 - self.mach**2)
        gam = 0.5 * self.mach * self.cl  # circulation, chord 1
        f = gam * beta / (2 * math.pi * r) / (1 - self.mach**2 * np.sin(th - self.alpha) ** 2)
        u = self.u0[0] + f * np.sin(th)
        v = self.u0[1] - f * np.cos(th)
        c2 = 1.0 + 0.5 * (GAMMA - 1) * (self.mach**2 - u * u - v * v)
        rho = self.rho0 * c2 ** (1 / (GAMMA - 1))
        return rho, u, v, rho * c2 / GAMMA

    def padded(self, W):
        """W with two ghost layers at the wall (mirrored) and two at the far field."""
        m = self.m
        rho, u, v, p = primitive(W[:, :, -1])
        rf, uf, vf, pf = self.far_state()
        nx, ny = m.nf[0], m.nf[1]
        ce, cf = np.sqrt(GAMMA * p / rho), np.sqrt(GAMMA * pf / rf)
        une, unf = u * nx + v * ny, uf * nx + vf * ny
        rp = une + 2 * ce / (GAMMA - 1)
        rm = unf - 2 * cf / (GAMMA - 1)
        un = 0.5 * (rp + rm)
        cb = 0.25 * (GAMMA - 1) * (rp - rm)
        inflow = un < 0
        ent = np.where(inflow, pf / rf**GAMMA, p / rho**GAMMA)
        ut = np.where(inflow, -uf * ny + vf * nx, -u * ny + v * nx)
        rb = (cb * cb / (GAMMA * ent)) ** (1 / (GAMMA - 1))
        pb = rb * cb * cb / GAMMA
        ub, vb = un * nx - ut * ny, un * ny + ut * nx
        Wb = np.stack([rb, rb * ub, rb * vb, pb / (GAMMA - 1) + 0.5 * rb * (ub * ub + vb * vb)])
        ni, nj = m.ni, m.nj
        P = np.empty((4, ni, nj + 4))
        P[:, :, 2:-2] = W
        P[:, :, -2] = Wb
        P[:, :, -1] = Wb
        for g, src in ((1, 0), (0, 1)):
            Wc = W[:, :, src]
            un = (Wc[1] * m.nw[0] + Wc[2] * m.nw[1])
            P[0, :, g] = Wc[0]
            P[1, :, g] = Wc[1] - 2 * un * m.nw[0]
            P[2, :, g] = Wc[2] - 2 * un * m.nw[1]
            P[3, :, g] = Wc[3]
        return P

    def residual(self, W):
        """Sum of the outgoing fluxes of each cell, and the local time step."""
        m = self.m
        P = self.padded(W)
        p = primitive(P)[3]
        # --- j direction (faces 0..nj between padded cells f+1 and f+2)
        nf = m.nj + 1
        F, lam = face_fluxes([P[:, :, k:k + nf] for k in range(4)],
                             [p[:, k:k + nf] for k in range(4)], m.Sj)
        # the wall: the pressure alone
        pw = p[:, 2]
        F[:, :, 0] = 0.0
        F[1, :, 0] = pw * m.Sj[0, :, 0]
        F[2, :, 0] = pw * m.Sj[1, :, 0]
        Rj = F[:, :, 1:] - F[:, :, :-1]
        lamj = 0.5 * (lam[:, 1:] + lam[:, :-1])
        # --- i direction (periodic; face i between cells i-1 and i)
        Wc, pc = P[:, :, 2:-2], p[:, 2:-2]
        G, lam = face_fluxes([np.roll(Wc, k, axis=-2) for k in (2, 1, 0, -1)],
                             [np.roll(pc, k, axis=-2) for k in (2, 1, 0, -1)], m.Si)
        Ri = np.roll(G, -1, axis=-2) - G
        lami = 0.5 * (lam + np.roll(lam, -1, axis=-2))
        dt = self.cfl * m.vol / (lami + lamj)
        return Ri + Rj, dt, pw

    def step(self):
        W0 = self.W
        R, dt, _ = self.residual(W0)
        for k, a in enumerate(STAGES):
            if k:
                R, _, _ = self.residual(self.W)
            self.W = W0 - a * (dt / self.m.vol) * R
        return R

    def loads(self, cell=False):
        """Cl, Cd, and the wall pressure: linear from the first two cells, or (cell) the first
        cell's, which the wall flux uses, so that its forces close the discrete momentum
        balance (a subsonic flow's drag then comes out near zero; the linear one's does not),
        while the linear one follows the steep normal gradient round the nose."""
        m = self.m
        _, _, _, p = primitive(self.W[:, :, :2])
        pw = p[:, 0] if cell else 1.5 * p[:, 0] - 0.5 * p[:, 1]
        # the wall's face normals point into the gas: the force on the body is -p S
        Fx = -(pw * m.Sj[0, :, 0]).sum()
        Fy = -(pw * m.Sj[1, :, 0]).sum()
        ca, sa = math.cos(self.alpha), math.sin(self.alpha)
        cl = (Fy * ca - Fx * sa) / self.q
        cd = (Fx * ca + Fy * sa) / self.q
        return cl, cd, pw


def solve(outline, mach, alpha, ni, nj, wall, radius, iters, tol, cfl, log=True):
    """March from the free stream until the RMS density residual has fallen to tol times its
    value at iteration 100 (checked every 100) or iters have run. Returns the solver, the mesh,
    Cl, Cd and the wall pressure (extrapolated), the history (iteration, residual drop, Cl, Cd)
    and the wall time."""
    keep_heap()
    mesh = Mesh(make_grid(outline, ni, nj, wall, radius))
    s = Solver(mesh, mach, alpha, cfl)
    t0 = time.time()
    r0 = None
    hist = []
    for it in range(1, iters + 1):
        R = s.step()
        if it % 20 == 0:
            s.cl = s.loads()[0]
        if it % 100 == 0:
            res = math.sqrt(np.mean((R[0] / mesh.vol) ** 2))
            r0 = r0 or res
            cl, cd, _ = s.loads()
            hist.append((it, res / r0, cl, cd))
            if log:
                print(f"  {it:6d}  residual {res / r0:.2e}  Cl {cl:.5f}  Cd {cd:.5f}  "
                      f"{time.time() - t0:.0f} s", file=sys.stderr, flush=True)
            if not np.isfinite(res):
                raise SystemExit("euler_aerofoil: the solution blew up: lower --cfl")
            if res / r0 < tol:
                break
    cl, cd, pw = s.loads()
    return s, mesh, cl, cd, pw, hist, time.time() - t0


def sides(mesh):
    """Each wall face's side: upper from the trailing edge to the leading edge (the least x),
    lower after it."""
    return np.where(np.arange(mesh.ni) < int(np.argmin(mesh.X[:, 0, 0])), "upper", "lower")


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--coords", default=os.path.join(root, "cases", "rae2822_coordinates.csv"))
    ap.add_argument("--naca", type=float, default=0.0,
                    help="a symmetric NACA 4-digit section of this thickness instead of --coords")
    ap.add_argument("--mach", type=float, default=0.729)
    ap.add_argument("--alpha", type=float, default=2.31)
    ap.add_argument("--ni", type=int, default=320)
    ap.add_argument("--nj", type=int, default=96)
    ap.add_argument("--wall", type=float, default=0.002, help="first cell's thickness, chords")
    ap.add_argument("--radius", type=float, default=40.0)
    ap.add_argument("--iters", type=int, default=20000)
    ap.add_argument("--tol", type=float, default=1e-6, help="stop at this drop of the residual")
    ap.add_argument("--cfl", type=float, default=2.5)
    ap.add_argument("--out", help="surface Cp CSV")
    ap.add_argument("--json", help="figures as JSON")
    a = ap.parse_args()
    outline = naca4(a.naca) if a.naca > 0 else read_outline(a.coords)
    s, mesh, cl, cd, pw, hist, wall = solve(outline, a.mach, a.alpha, a.ni, a.nj, a.wall,
                                            a.radius, a.iters, a.tol, a.cfl)
    cl_cell, cd_cell, pw_cell = s.loads(cell=True)
    cp, cp_cell = (pw - s.p0) / s.q, (pw_cell - s.p0) / s.q
    xm, side = mesh.wall_mid, sides(mesh)
    res = {"mach": a.mach, "alpha": a.alpha, "ni": a.ni, "nj": a.nj, "wall": a.wall,
           "radius": a.radius, "iterations": hist[-1][0], "residual_drop": hist[-1][1],
           "cl": cl, "cd": cd, "cl_cell": cl_cell, "cd_cell": cd_cell, "wall_time": wall}
    print(json.dumps(res, indent=1))
    if a.out:
        with open(a.out, "w", newline="") as f:
            f.write("# " + json.dumps(res) + "\n")
            w = csv.writer(f)
            w.writerow(["x_over_c", "y_over_c", "side", "cp", "cp_cell"])
            for k in range(mesh.ni):
                w.writerow([f"{xm[k, 0]:.6f}", f"{xm[k, 1]:.6f}", side[k], f"{cp[k]:.5f}",
                            f"{cp_cell[k]:.5f}"])
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res | {"history": hist}, f, indent=1)


if __name__ == "__main__":
    main()
