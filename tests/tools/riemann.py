"""Exact solution of the 1-D Riemann problem for an ideal gas (the tests' reference for shock
tubes), and the cell-wise comparison of a gas run against it.

The star pressure solves f_L(p) + f_R(p) + (u_R - u_L) = 0, where f_K is the velocity change
across a shock (Rankine-Hugoniot) or a rarefaction (isentropic) from state K to pressure p;
Newton's method from the two-rarefaction estimate converges in a few iterations. The solution
is self-similar in (x - x0) / t and is sampled wave by wave.
"""
import math

import numpy as np


class Riemann:
    def __init__(self, left, right, gamma=1.4, x0=0.5):
        (self.rl, self.ul, self.pl), (self.rr, self.ur, self.pr) = left, right
        self.g, self.x0 = gamma, x0
        self.cl = math.sqrt(gamma * self.pl / self.rl)
        self.cr = math.sqrt(gamma * self.pr / self.rr)
        self.p_star, self.u_star = self._star()
        g = gamma
        self.r_star_l = self._rho_star(self.rl, self.pl)
        self.r_star_r = self._rho_star(self.rr, self.pr)
        # Shock speeds (used when the wave on that side is a shock).
        self.s_l = self.ul - self.cl * math.sqrt((g + 1) / (2 * g) * self.p_star / self.pl
                                                 + (g - 1) / (2 * g))
        self.s_r = self.ur + self.cr * math.sqrt((g + 1) / (2 * g) * self.p_star / self.pr
                                                 + (g - 1) / (2 * g))

    def _f(self, p, r, pk, c):
        """Velocity change across the wave from (r, pk) to pressure p, and its derivative."""
        g = self.g
        if p > pk:  # shock
            a, b = 2 / ((g + 1) * r), (g - 1) / (g + 1) * pk
            q = math.sqrt(a / (p + b))
            return (p - pk) * q, q * (1 - 0.5 * (p - pk) / (p + b))
        e = (g - 1) / (2 * g)
        return (2 * c / (g - 1) * ((p / pk) ** e - 1),
                1 / (r * c) * (p / pk) ** (-(g + 1) / (2 * g)))

    def _star(self):
        g = self.g
        e = (g - 1) / (2 * g)
        du = self.ur - self.ul
        # Two-rarefaction estimate: exact when both waves are rarefactions.
        p = ((self.cl + self.cr - 0.5 * (g - 1) * du)
             / (self.cl / self.pl ** e + self.cr / self.pr ** e)) ** (1 / e)
        for _ in range(100):
            fl, dl = self._f(p, self.rl, self.pl, self.cl)
            fr, dr = self._f(p, self.rr, self.pr, self.cr)
            step = (fl + fr + du) / (dl + dr)
            p_new = max(p - step, 1e-14 * p)
            if abs(p_new - p) <= 1e-15 * (p_new + p):
                p = p_new
                break
            p = p_new
        fl, _ = self._f(p, self.rl, self.pl, self.cl)
        fr, _ = self._f(p, self.rr, self.pr, self.cr)
        return p, 0.5 * (self.ul + self.ur) + 0.5 * (fr - fl)

    def _rho_star(self, r, pk):
        g, p = self.g, self.p_star
        if p > pk:
            q = p / pk
            return r * (q + (g - 1) / (g + 1)) / ((g - 1) / (g + 1) * q + 1)
        return r * (p / pk) ** (1 / g)

    def shock_position(self, t):
        """Position of the right-going shock (the problem must have one)."""
        assert self.p_star > self.pr
        return self.x0 + self.s_r * t

    def contact_position(self, t):
        return self.x0 + self.u_star * t

    def sample(self, x, t):
        """(rho, u, p) at the points x (array) at time t > 0."""
        g = self.g
        s = (np.asarray(x, dtype=float) - self.x0) / t
        rho, u, p = np.empty_like(s), np.empty_like(s), np.empty_like(s)
        for k, sk in enumerate(s):
            rho[k], u[k], p[k] = self._sample(sk)
        return rho, u, p

    def _sample(self, s):
        g, ps, us = self.g, self.p_star, self.u_star
        if s <= us:  # left of the contact
            if ps > self.pl:
                return (self.r_star_l, us, ps) if s >= self.s_l else (self.rl, self.ul, self.pl)
            c_star = self.cl * (ps / self.pl) ** ((g - 1) / (2 * g))
            head, tail = self.ul - self.cl, us - c_star
            if s <= head:
                return self.rl, self.ul, self.pl
            if s >= tail:
                return self.r_star_l, us, ps
            u = 2 / (g + 1) * (self.cl + 0.5 * (g - 1) * self.ul + s)
            c = 2 / (g + 1) * (self.cl + 0.5 * (g - 1) * (self.ul - s))
            rho = self.rl * (c / self.cl) ** (2 / (g - 1))
            return rho, u, self.pl * (c / self.cl) ** (2 * g / (g - 1))
        if ps > self.pr:
            return (self.r_star_r, us, ps) if s <= self.s_r else (self.rr, self.ur, self.pr)
        c_star = self.cr * (ps / self.pr) ** ((g - 1) / (2 * g))
        head, tail = self.ur + self.cr, us + c_star
        if s >= head:
            return self.rr, self.ur, self.pr
        if s <= tail:
            return self.r_star_r, us, ps
        u = 2 / (g + 1) * (-self.cr + 0.5 * (g - 1) * self.ur + s)
        c = 2 / (g + 1) * (self.cr - 0.5 * (g - 1) * (self.ur - s))
        rho = self.rr * (c / self.cr) ** (2 / (g - 1))
        return rho, u, self.pr * (c / self.cr) ** (2 * g / (g - 1))

    def cell_averages(self, edges, t, sub=64):
        """Exact (rho, u, p) averaged over each cell [edges[k], edges[k+1]] (midpoint rule on
        `sub` points per cell: the discontinuities fall inside one cell, so the average is
        exact to 1/sub of a jump in that cell)."""
        n = len(edges) - 1
        h = np.diff(edges)
        xs = (edges[:-1, None] + h[:, None] * (np.arange(sub)[None, :] + 0.5) / sub).ravel()
        out = self.sample(xs, t)
        return tuple(q.reshape(n, sub).mean(axis=1) for q in out)


def cell_profile(x, q, edges, sub=64):
    """Cell averages of a particle quantity q along x: the piecewise-linear interpolant
    through the particle values (ordered by x; constant beyond the outermost particles)
    averaged over each cell [edges[k], edges[k+1]] on `sub` midpoints, as in
    Riemann.cell_averages. Interpolating between particles rather than binning them keeps
    cells that hold no particle (where the gas has expanded past one particle per cell) in the
    measure."""
    order = np.argsort(x, kind="stable")
    n = len(edges) - 1
    h = np.diff(edges)
    xs = (edges[:-1, None] + h[:, None] * (np.arange(sub)[None, :] + 0.5) / sub).ravel()
    return np.interp(xs, x[order], q[order]).reshape(n, sub).mean(axis=1)


def shock_front(xc, rho, rho_pre, rho_post, x_from):
    """Position where the cell density profile last crosses the mid-value between the
    pre- and post-shock densities, searching right of x_from (linear interpolation between
    cell centres)."""
    mid = 0.5 * (rho_pre + rho_post)
    idx = [k for k in range(len(xc) - 1)
           if xc[k] >= x_from and (rho[k] - mid) * (rho[k + 1] - mid) <= 0 and rho[k] != rho[k + 1]]
    if not idx:
        return float("nan")
    k = idx[-1]
    return float(xc[k] + (mid - rho[k]) / (rho[k + 1] - rho[k]) * (xc[k + 1] - xc[k]))
