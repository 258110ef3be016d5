#!/usr/bin/python3
"""Independent finite-volume reference for the gas-only version of the main scene
(cases/supersonic_bar.ini with the bar held rigid): Mach 2.5 air over a rigid rectangular
bar standing on the floor of a channel. It tells whether what the MPM gas does (bow shock
stand-off, drag, the channel unstarting) is physics of the inviscid problem or a numerical
artefact, and it checks itself on the Sod shock tube and on a smooth 2-D advection.

Problem (2-D inviscid Euler, ideal gas, gamma = 1.4):
  channel x in [0, 0.30] m, y in [0, H] (H = 0.18 m; --height and --length for other
  channels, --bar-x to move the bar);
  x = 0: supersonic inflow, fixed state p = 1.0e5 Pa, rho = 1.2 kg/m^3, u = 854 m/s, v = 0;
  x = 0.30: supersonic outflow (zero-gradient extrapolation);
  y = 0 and y = H: slip walls;
  obstacle x in [0.05, 0.056], y in [0, 0.03], rigid with slip walls;
  impulsive start: the whole channel (outside the obstacle) holds the free stream at t = 0.

Scheme: cell-centred finite volumes on a uniform Cartesian grid whose faces align with the
obstacle, MUSCL-Hancock (second order in space and time):
  1. slopes of the primitive variables (rho, u, v, p) in x and y, limited (van Leer or
     minmod), each from the two one-sided differences;
  2. a half-step predictor of the cell's primitive state with the quasi-linear primitive
     equations, using both slopes at once (dimensionally unsplit);
  3. face values = predicted state +- half a slope; where any face value of a cell has
     rho <= 0 or p <= 0 the cell falls back to first order (its four face values become the
     cell average);
  4. HLLC fluxes (Toro, ch. 10) with Einfeldt's wave-speed estimates at every face;
  5. conservative update of all fluid cells with the x- and y-flux differences at once.
If a step still produces a non-positive density or pressure anywhere, it is redone at first
order throughout (counted and reported as 'first-order steps'); first-order Godunov + HLLC
with Einfeldt's speeds keeps positivity at this CFL in practice, a floor catches the rest
(counted as 'floored cells', zero in every run reported).

Solid cells (the obstacle, and a ghost row below y = 0 and above y = H) are handled by
masking: wherever a slope or a face needs the state of a solid neighbour, the fluid cell's
own state (or its own face value) is used with the velocity component normal to that face
reversed: the usual reflecting ghost cell, built per fluid-solid pair so that a solid cell
touching fluid on two sides (the bar's top corners) mirrors each neighbour separately. The
Riemann problem at a wall face is then symmetric: the HLLC flux carries no mass and its
normal momentum flux is the wall pressure, which is what the force on the obstacle sums.
The inflow column holds the fixed free stream, the outflow column copies the last fluid
column (both with zero slope).

Time step: dt = CFL / max over fluid cells of ((|u| + c)/dx + (|v| + c)/dy), CFL = 0.8,
cut to land on output times.

Diagnostics, every --standoff-every seconds (default 0.05 ms), into <prefix>.csv:
  t; standoff: the MPM project's definition (tools/supersonic_bar.py): the density averaged
     over the cells of y in [0, 0.03] (the bar's height) for each column upstream of the bar,
     scanned from the inflow; x_s = first place it exceeds 1.5 x the free stream (linear
     interpolation between the two cell centres), stand-off = 0.05 - x_s (bar's x - x_s);
  Fx = F_front - F_back: the force on the obstacle in x per metre of span, the integral of
     the wall pressure over its upstream face minus that over its downstream face;
  Fy: the pressure force on its top face (its width times the pressure, pointing down, so
     Fy < 0; the bar stands on the floor, no pressure acts on its base);
  x_shock_floor, x_shock_top, x_shock_min: the first x, scanned from the inflow, where the
     density rises past 1.5 x the free stream in the floor row, the top-wall row, and the
     smallest over all rows (NaN where no cell exceeds it);
  x_subsonic_column: the most upstream column upstream of the bar in which the flow is
     subsonic over the full channel height (NaN if none): a normal shock spanning the channel;
  subsonic_frac_inflow, subsonic_frac_bar: the fraction of the first column, and of the
     column 5 mm upstream of the bar, where the flow is subsonic;
  unstarted: 1 once x_shock_floor < 0.005 m or x_subsonic_column is not NaN (the first
     fires as soon as the bow shock's foot reaches the inflow, which in the main scene's
     short upstream section happens long before the channel unstarts; the summary lists the
     two separately, and a third: the top-wall shock upstream of the bar's face);
  mdot_in, mdot_out: the mass flow through the inflow face and the outflow column over the
     free stream's rho u H (mdot_in < 1: a shock sits on the inflow, which then spills);
  astar_req: the sonic throat (over H) the flow crossing the column 5 mm upstream of the
     bar needs: sum of rho u / G*(p0, T0) over the column (free stream 0.379, behind a
     normal shock 0.760, the free area over the bar 0.833).
Also <prefix>_strip.png (density at 0.5, 1.0, ..., 3.0 ms; for other t_end six panels
evenly spaced, or --panels) and <prefix>.json (the run's summary);
bench/results/euler_reference_summary.md is rewritten from all the runs' JSON files (the
text after its NOTES line is kept: the hand-written interpretation).

Usage (from the repository root):
  /usr/bin/python3 bench/euler_reference.py --dx 0.001            # 1 mm run, t_end 3 ms
  /usr/bin/python3 bench/euler_reference.py --dx 0.002 --height 0.24
  /usr/bin/python3 bench/euler_reference.py --dx 0.002 --bar-x 0.15 --length 0.40 \\
      --t-end 0.03 --standoff-every 2e-4          # a long upstream section
  /usr/bin/python3 bench/euler_reference.py --sod                 # solver checks
  /usr/bin/python3 bench/euler_reference.py --report              # only rewrite the .md
--dx is in metres and must divide 0.006, 0.03 and the bar's x (0.05), the length and height.
The default output prefix is bench/results/euler_reference_dx<mm>, with _h<H>, _L<length>,
_bx<bar x>, _t<t_end> (mm / ms) appended where they differ from the main scene.
Speed (numpy, one core): about 25 ms a step on 300 x 180 cells, so the 1 mm run to 3 ms
(7300 steps) takes 3-5 minutes, the 2 mm run under 30 s, 0.5 mm about 15 minutes per ms.
"""
import argparse
import csv
import glob
import json
import math
import os
import sys
import time

import numpy as np

GAMMA = 1.4
HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")

# free stream and geometry of the main scene
RHO_INF, U_INF, P_INF = 1.2, 854.0, 1.0e5
LENGTH = 0.30
BAR_X0, BAR_X1, BAR_H = 0.05, 0.056, 0.03
SNAP_TIMES = (0.5e-3, 1.0e-3, 1.5e-3, 2.0e-3, 2.5e-3, 3.0e-3)


# ----------------------------------------------------------------------------------------
# Primitive <-> conserved variables; arrays are (4, ...) with rows rho, u, v, p (primitive)
# or rho, rho u, rho v, E (conserved).

def to_conserved(W, g=GAMMA):
    rho, u, v, p = W
    return np.array([rho, rho * u, rho * v, p / (g - 1.0) + 0.5 * rho * (u * u + v * v)])


def to_primitive(U, g=GAMMA):
    rho = U[0]
    u = U[1] / rho
    v = U[2] / rho
    p = (g - 1.0) * (U[3] - 0.5 * rho * (u * u + v * v))
    return np.array([rho, u, v, p])


def limiter(a, b, kind):
    """Limited slope from the backward difference a and the forward difference b."""
    if kind == "minmod":
        return (np.sign(a) + np.sign(b)) * 0.5 * np.minimum(np.abs(a), np.abs(b))
    # van Leer (harmonic mean): 2ab/(a+b) where a and b have the same sign, else 0;
    # (a|b| + |a|b) / (|a| + |b|) is the same in one expression
    aa, ab = np.abs(a), np.abs(b)
    return (a * ab + aa * b) / (aa + ab + 1e-300)


def hllc(rL, unL, utL, pL, rR, unR, utR, pR, g=GAMMA):
    """HLLC flux normal to a face (Toro, Riemann Solvers, 3rd ed., sect. 10.4), with
    Einfeldt's (Roe-average) bounds SL, SR for the outer waves. Inputs are the left/right
    densities, normal and tangential velocities and pressures; returns the fluxes of mass,
    normal momentum, tangential momentum and energy as a (4, ...) array.

    Written in one pass: K is the side of the contact the face lies on (left if S* >= 0);
    the flux is F_K + S'(U*_K - U_K) with S' = min(SL, 0) on the left, max(SR, 0) on the
    right, which is F_K where the outer wave has passed the face (S' = 0) and F*_K where
    it has not."""
    EL = pL / (g - 1.0) + 0.5 * rL * (unL * unL + utL * utL)
    ER = pR / (g - 1.0) + 0.5 * rR * (unR * unR + utR * utR)
    cL = np.sqrt(g * pL / rL)
    cR = np.sqrt(g * pR / rR)
    # Roe averages for Einfeldt's wave-speed estimates
    qL, qR = np.sqrt(rL), np.sqrt(rR)
    w = 1.0 / (qL + qR)
    un_roe = (qL * unL + qR * unR) * w
    ut_roe = (qL * utL + qR * utR) * w
    H_roe = (qL * (EL + pL) / rL + qR * (ER + pR) / rR) * w
    c_roe = np.sqrt(np.maximum((g - 1.0) * (H_roe - 0.5 * (un_roe ** 2 + ut_roe ** 2)), 0.0))
    SL = np.minimum(unL - cL, un_roe - c_roe)
    SR = np.maximum(unR + cR, un_roe + c_roe)
    # contact speed
    mL = rL * (SL - unL)
    mR = rR * (SR - unR)
    Ss = (pR - pL + mL * unL - mR * unR) / (mL - mR)
    # the upwind side of the contact
    left = Ss >= 0.0
    r = np.where(left, rL, rR)
    un = np.where(left, unL, unR)
    ut = np.where(left, utL, utR)
    p = np.where(left, pL, pR)
    E = np.where(left, EL, ER)
    SK = np.where(left, SL, SR)
    Sp = np.where(left, np.minimum(SL, 0.0), np.maximum(SR, 0.0))
    # star state of side K: density k, momenta k Ss, k ut, energy k e*
    den = SK - Ss
    k = r * (SK - un) / np.where(den == 0.0, 1.0, den)
    e_star = E / r + (Ss - un) * (Ss + p / (r * (SK - un)))
    out = np.empty((4,) + r.shape)
    m = r * un
    out[0] = m + Sp * (k - r)
    out[1] = m * un + p + Sp * (k * Ss - m)
    out[2] = m * ut + Sp * (k - r) * ut
    out[3] = un * (E + p) + Sp * (k * e_star - E)
    return out


# ----------------------------------------------------------------------------------------
class Euler2D:
    """Second-order finite-volume Euler solver on a uniform grid of nx x ny cells with one
    layer of ghost cells all round. Boundaries per side: 'wall' (slip, the ghost layer is
    solid), 'inflow' (fixed state), 'outflow' (zero gradient). `solid` (nx, ny) marks the
    cells of rigid obstacles."""

    def __init__(self, nx, ny, dx, dy, solid, bc, W_fill, limiter_kind="vanleer", cfl=0.8,
                 g=GAMMA):
        self.nx, self.ny, self.dx, self.dy = nx, ny, dx, dy
        self.g, self.cfl, self.lim = g, cfl, limiter_kind
        self.bc = bc  # dict: xlo, xhi, ylo, yhi -> 'wall' | 'outflow' | ('inflow', W)
        NX, NY = nx + 2, ny + 2
        # obstacle mask on the padded grid (obstacles only: forces are summed over these)
        self.body = np.zeros((NX, NY), bool)
        self.body[1:-1, 1:-1] = solid
        # all solid cells: obstacles plus the ghost layers of wall sides
        self.solid = self.body.copy()
        if bc["xlo"] == "wall":
            self.solid[0, :] = True
        if bc["xhi"] == "wall":
            self.solid[-1, :] = True
        if bc["ylo"] == "wall":
            self.solid[:, 0] = True
        if bc["yhi"] == "wall":
            self.solid[:, -1] = True
        self.fluid = ~self.solid
        self.fluid[0, :] = self.fluid[-1, :] = False  # ghost layers are never updated
        self.fluid[:, 0] = self.fluid[:, -1] = False
        self.W_fill = np.asarray(W_fill, float)  # a benign state kept in solid cells
        self.U = np.empty((4, NX, NY))
        self.U[:] = to_conserved(self.W_fill.reshape(4, 1, 1) * np.ones((1, NX, NY)), g)
        self.t = 0.0
        self.steps = 0
        self.first_order_steps = 0
        self.floored = 0
        self.F = self.G = None  # the last step's face fluxes (for the forces)
        self._prepare_masks()

    # --- state access -------------------------------------------------------------------
    def set_interior(self, W):
        """Set the primitive state of the interior cells (solid ones keep the fill)."""
        U = to_conserved(W, self.g)
        inner = self.fluid[1:-1, 1:-1]
        self.U[:, 1:-1, 1:-1] = np.where(inner, U, self.U[:, 1:-1, 1:-1])
        self.fill_ghosts()

    def primitive(self):
        return to_primitive(self.U, self.g)

    def fill_ghosts(self):
        U = self.U
        for side, sl_ghost, sl_in in (("xlo", (slice(None), 0), (slice(None), 1)),
                                      ("xhi", (slice(None), -1), (slice(None), -2)),
                                      ("ylo", (slice(None), slice(None), 0),
                                       (slice(None), slice(None), 1)),
                                      ("yhi", (slice(None), slice(None), -1),
                                       (slice(None), slice(None), -2))):
            kind = self.bc[side]
            if kind == "outflow":
                U[sl_ghost] = U[sl_in]
            elif isinstance(kind, tuple) and kind[0] == "inflow":
                U[sl_ghost] = to_conserved(np.asarray(kind[1], float), self.g)[:, None]
            # walls: the ghost layer is solid and keeps the fill state

    # --- time step ------------------------------------------------------------------------
    def max_dt(self):
        rho, u, v, p = self.primitive()
        c = np.sqrt(self.g * p / rho)
        rate = (np.abs(u) + c) / self.dx + (np.abs(v) + c) / self.dy
        return self.cfl / rate[self.fluid].max()

    def _prepare_masks(self):
        """Index lists of the solid-fluid pairs, computed once (cheaper than boolean masks
        over the whole grid at every step)."""
        S = self.solid
        self.idx = {}
        # slopes: interior cells (padded index c) whose lower/upper neighbour is solid
        self.idx["sx_m"] = np.nonzero(S[:-2, :])   # in the (NX-2, NY) arrays of x slopes
        self.idx["sx_p"] = np.nonzero(S[2:, :])
        self.idx["sy_m"] = np.nonzero(S[:, :-2])   # in the (NX, NY-2) arrays of y slopes
        self.idx["sy_p"] = np.nonzero(S[:, 2:])
        self.idx["solid"] = np.nonzero(S)
        # faces: x faces (NX-1, NY-2), y faces (NX-2, NY-1)
        for name, sL, sR in (("fx", S[:-1, 1:-1], S[1:, 1:-1]),
                             ("fy", S[1:-1, :-1], S[1:-1, 1:])):
            self.idx[name + "_R"] = np.nonzero(sR & ~sL)  # solid on the right
            self.idx[name + "_L"] = np.nonzero(sL & ~sR)  # solid on the left
            self.idx[name + "_both"] = np.nonzero(sL & sR)
        self.fluid_inner = self.fluid[1:-1, 1:-1].astype(float)

    def _slopes(self, W, axis):
        """Limited slopes along axis (1 = x, 2 = y) on the padded grid; zero in ghost and
        solid cells. A solid neighbour counts as the mirror image of the cell itself: equal
        density, tangential velocity and pressure, normal velocity reversed, so the one-sided
        difference towards it is (0, -+2 u_n, 0, 0)."""
        s = np.zeros_like(W)
        if axis == 1:
            Wc = W[:, 1:-1, :]
            dL = Wc - W[:, :-2, :]
            dR = W[:, 2:, :] - Wc
            im, ip, nrm = self.idx["sx_m"], self.idx["sx_p"], 1
        else:
            Wc = W[:, :, 1:-1]
            dL = Wc - W[:, :, :-2]
            dR = W[:, :, 2:] - Wc
            im, ip, nrm = self.idx["sy_m"], self.idx["sy_p"], 2
        for d, ii, sign in ((dL, im, 2.0), (dR, ip, -2.0)):
            if len(ii[0]):
                d[:, ii[0], ii[1]] = 0.0
                d[nrm, ii[0], ii[1]] = sign * Wc[nrm, ii[0], ii[1]]
        if axis == 1:
            s[:, 1:-1, :] = limiter(dL, dR, self.lim)
            s[:, -1, :] = 0.0
            s[:, 0, :] = 0.0
        else:
            s[:, :, 1:-1] = limiter(dL, dR, self.lim)
            s[:, :, -1] = 0.0
            s[:, :, 0] = 0.0
        i0, i1 = self.idx["solid"]
        s[:, i0, i1] = 0.0
        return s

    def _face_fluxes(self, xm, xp, ym, yp):
        """HLLC fluxes on all x faces (4, NX-1, ny) and y faces (4, nx, NY-1) from the face
        values xm/xp (left/right x face of each cell) and ym/yp."""
        # x faces between padded cells (i, i+1), interior rows
        L = xp[:, :-1, 1:-1].copy()
        R = xm[:, 1:, 1:-1].copy()
        self._mirror(L, R, "fx", 1)
        F = hllc(L[0], L[1], L[2], L[3], R[0], R[1], R[2], R[3], self.g)
        # y faces between padded cells (j, j+1), interior columns
        L = yp[:, 1:-1, :-1].copy()
        R = ym[:, 1:-1, 1:].copy()
        self._mirror(L, R, "fy", 2)
        Gn = hllc(L[0], L[2], L[1], L[3], R[0], R[2], R[1], R[3], self.g)
        Gn[[1, 2]] = Gn[[2, 1]]  # back to (mass, x-mom, y-mom, energy)
        return F, Gn

    def _mirror(self, L, R, name, nrm):
        """Replace the solid side of each fluid-solid face by the mirror of the fluid side."""
        a0, a1 = self.idx[name + "_R"]  # solid on the right: R = mirror(L)
        R[:, a0, a1] = L[:, a0, a1]
        R[nrm, a0, a1] *= -1.0
        b0, b1 = self.idx[name + "_L"]  # solid on the left: L = mirror(R)
        L[:, b0, b1] = R[:, b0, b1]
        L[nrm, b0, b1] *= -1.0
        c0, c1 = self.idx[name + "_both"]  # flux unused; keep the arithmetic benign
        L[:, c0, c1] = self.W_fill[:, None]
        R[:, c0, c1] = self.W_fill[:, None]

    def _update(self, dt, order):
        """One MUSCL-Hancock (order 2) or Godunov (order 1) step; returns the new U and the
        face fluxes."""
        W = self.primitive()
        if order == 2:
            sx = self._slopes(W, 1)
            sy = self._slopes(W, 2)
            rho, u, v, p = W
            g = self.g
            ax, ay = 0.5 * dt / self.dx, 0.5 * dt / self.dy
            # half-step predictor with the primitive quasi-linear equations
            # W_t + A(W) W_x + B(W) W_y = 0, both directions at once
            Wh = np.empty_like(W)
            Wh[0] = rho - ax * (u * sx[0] + rho * sx[1]) - ay * (v * sy[0] + rho * sy[2])
            Wh[1] = u - ax * (u * sx[1] + sx[3] / rho) - ay * (v * sy[1])
            Wh[2] = v - ax * (u * sx[2]) - ay * (v * sy[2] + sy[3] / rho)
            Wh[3] = p - ax * (u * sx[3] + g * p * sx[1]) - ay * (v * sy[3] + g * p * sy[2])
            sx *= 0.5
            sy *= 0.5
            xm, xp = Wh - sx, Wh + sx
            ym, yp = Wh - sy, Wh + sy
            # positivity safeguard: first order in cells with a non-physical face value
            lo = np.minimum(np.minimum(xm[[0, 3]], xp[[0, 3]]),
                            np.minimum(ym[[0, 3]], yp[[0, 3]])).min(axis=0)
            bad = np.nonzero(lo <= 0.0)
            if len(bad[0]):
                for f in (xm, xp, ym, yp):
                    f[:, bad[0], bad[1]] = W[:, bad[0], bad[1]]
        else:
            xm = xp = ym = yp = W
        F, G = self._face_fluxes(xm, xp, ym, yp)
        U = self.U.copy()
        dU = (F[:, 1:, :] - F[:, :-1, :]) * (-dt / self.dx)
        dU -= (G[:, :, 1:] - G[:, :, :-1]) * (dt / self.dy)
        dU *= self.fluid_inner
        U[:, 1:-1, 1:-1] += dU
        return U, F, G

    def _positive(self, U):
        rho = U[0][self.fluid]
        p = (self.g - 1.0) * (U[3] - 0.5 * (U[1] ** 2 + U[2] ** 2) / U[0])[self.fluid]
        return bool(np.all(rho > 0.0) and np.all(p > 0.0) and np.all(np.isfinite(p)))

    def step(self, dt):
        with np.errstate(invalid="ignore", divide="ignore"):
            U, F, G = self._update(dt, 2)
            if not self._positive(U):
                self.first_order_steps += 1
                U, F, G = self._update(dt, 1)
                if not self._positive(U):  # last resort: floor density and pressure
                    W = to_primitive(U, self.g)
                    badc = self.fluid & ~((W[0] > 0) & (W[3] > 0))
                    self.floored += int(badc.sum())
                    W[0] = np.where(badc, 1e-6 * RHO_INF, W[0])
                    W[3] = np.where(badc, 1e-6 * P_INF, W[3])
                    W[1] = np.where(badc, 0.0, W[1])
                    W[2] = np.where(badc, 0.0, W[2])
                    U = to_conserved(W, self.g)
        self.U = U
        self.F, self.G = F, G
        self.fill_ghosts()
        self.t += dt
        self.steps += 1

    # --- forces on the obstacle --------------------------------------------------------
    def body_forces(self):
        """(F_front, F_back, Fy) per metre of span from the last step's face fluxes: the
        normal momentum flux at a fluid-obstacle face is the wall pressure. F_front sums the
        x faces with fluid on the left (upstream faces), F_back those with fluid on the
        right; Fy the y-face pressures (fluid above pushes down)."""
        B, Fl = self.body, self.fluid
        F, G = self.F, self.G
        front = float(F[1][Fl[:-1, 1:-1] & B[1:, 1:-1]].sum() * self.dy)
        back = float(F[1][B[:-1, 1:-1] & Fl[1:, 1:-1]].sum() * self.dy)
        up = float(G[2][Fl[1:-1, :-1] & B[1:-1, 1:]].sum() * self.dx)    # fluid below a body
        down = float(G[2][B[1:-1, :-1] & Fl[1:-1, 1:]].sum() * self.dx)  # fluid above a body
        return front, back, up - down


# ----------------------------------------------------------------------------------------
# Exact Riemann solver for the ideal-gas Euler equations (Toro, ch. 4)

def exact_riemann(WL, WR, S, g=GAMMA):
    """Exact solution (rho, u, p) at the similarity coordinates S = x/t of the Riemann
    problem with left/right primitive states WL, WR = (rho, u, p)."""
    rL, uL, pL = WL
    rR, uR, pR = WR
    cL, cR = math.sqrt(g * pL / rL), math.sqrt(g * pR / rR)

    def f_and_df(p, r, pk, c):
        if p > pk:  # shock
            A, B = 2.0 / ((g + 1.0) * r), (g - 1.0) / (g + 1.0) * pk
            q = math.sqrt(A / (p + B))
            return (p - pk) * q, q * (1.0 - 0.5 * (p - pk) / (B + p))
        # rarefaction
        f = 2.0 * c / (g - 1.0) * ((p / pk) ** ((g - 1.0) / (2.0 * g)) - 1.0)
        return f, 1.0 / (r * c) * (p / pk) ** (-(g + 1.0) / (2.0 * g))

    # initial guess: primitive-variable (PVRS) estimate, kept positive
    p = max(0.5 * (pL + pR) - 0.125 * (uR - uL) * (rL + rR) * (cL + cR), 1e-8)
    for _ in range(100):
        fL, dL = f_and_df(p, rL, pL, cL)
        fR, dR = f_and_df(p, rR, pR, cR)
        pn = max(p - (fL + fR + uR - uL) / (dL + dR), 1e-10)
        if abs(pn - p) < 1e-14 * (pn + p):
            p = pn
            break
        p = pn
    fL, _ = f_and_df(p, rL, pL, cL)
    fR, _ = f_and_df(p, rR, pR, cR)
    ps, us = p, 0.5 * (uL + uR) + 0.5 * (fR - fL)
    gm = (g - 1.0) / (g + 1.0)

    out = np.empty((3, len(S)))
    for k, s in enumerate(S):
        if s <= us:  # left of the contact
            if ps > pL:  # left shock
                SLs = uL - cL * math.sqrt((g + 1.0) / (2.0 * g) * ps / pL + (g - 1.0) / (2.0 * g))
                if s <= SLs:
                    out[:, k] = rL, uL, pL
                else:
                    out[:, k] = rL * (ps / pL + gm) / (gm * ps / pL + 1.0), us, ps
            else:  # left rarefaction
                cs = cL * (ps / pL) ** ((g - 1.0) / (2.0 * g))
                if s <= uL - cL:
                    out[:, k] = rL, uL, pL
                elif s >= us - cs:
                    out[:, k] = rL * (ps / pL) ** (1.0 / g), us, ps
                else:  # inside the fan
                    u = 2.0 / (g + 1.0) * (cL + (g - 1.0) / 2.0 * uL + s)
                    c = 2.0 / (g + 1.0) * (cL + (g - 1.0) / 2.0 * (uL - s))
                    r = rL * (c / cL) ** (2.0 / (g - 1.0))
                    out[:, k] = r, u, pL * (c / cL) ** (2.0 * g / (g - 1.0))
        else:  # right of the contact
            if ps > pR:  # right shock
                SRs = uR + cR * math.sqrt((g + 1.0) / (2.0 * g) * ps / pR + (g - 1.0) / (2.0 * g))
                if s >= SRs:
                    out[:, k] = rR, uR, pR
                else:
                    out[:, k] = rR * (ps / pR + gm) / (gm * ps / pR + 1.0), us, ps
            else:  # right rarefaction
                cs = cR * (ps / pR) ** ((g - 1.0) / (2.0 * g))
                if s >= uR + cR:
                    out[:, k] = rR, uR, pR
                elif s <= us + cs:
                    out[:, k] = rR * (ps / pR) ** (1.0 / g), us, ps
                else:
                    u = 2.0 / (g + 1.0) * (-cR + (g - 1.0) / 2.0 * uR + s)
                    c = 2.0 / (g + 1.0) * (cR - (g - 1.0) / 2.0 * (uR - s))
                    r = rR * (c / cR) ** (2.0 / (g - 1.0))
                    out[:, k] = r, u, pR * (c / cR) ** (2.0 * g / (g - 1.0))
    return out


def run_sod(n, along="x", t_end=0.2, limiter_kind="vanleer", cfl=0.8):
    """Sod's shock tube on [0, 1] (diaphragm at 0.5, t = 0.2) with n cells along x (or y),
    4 cells across with slip walls: the 2-D code path. Returns the L1 density error
    against the exact solution averaged over each cell (20 samples per cell)."""
    m = 4
    nx, ny = (n, m) if along == "x" else (m, n)
    h = 1.0 / n
    bc = {"xlo": "wall", "xhi": "wall", "ylo": "outflow", "yhi": "outflow"} if along == "y" \
        else {"xlo": "outflow", "xhi": "outflow", "ylo": "wall", "yhi": "wall"}
    s = Euler2D(nx, ny, h, h, np.zeros((nx, ny), bool), bc, (1.0, 0.0, 0.0, 1.0),
                limiter_kind, cfl)
    xc = (np.arange(n) + 0.5) * h
    left = xc < 0.5
    W1 = np.array([np.where(left, 1.0, 0.125), 0 * xc, 0 * xc, np.where(left, 1.0, 0.1)])
    W = W1[:, :, None] * np.ones((1, 1, m)) if along == "x" else W1[:, None, :] * np.ones((1, m, 1))
    if along == "y":  # the tube runs along y: the velocity along it is v
        W = W[[0, 2, 1, 3]]
    s.set_interior(W)
    while s.t < t_end - 1e-14:
        s.step(min(s.max_dt(), t_end - s.t))
    rho = s.primitive()[0, 1:-1, 1:-1]
    rho1 = rho.mean(axis=1) if along == "x" else rho.mean(axis=0)
    spread = float(np.ptp(rho, axis=1 if along == "x" else 0).max())
    sub = 20
    xs = ((np.arange(n * sub) + 0.5) / (n * sub))
    ex = exact_riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1), (xs - 0.5) / t_end)[0]
    ex = ex.reshape(n, sub).mean(axis=1)
    return float(np.sum(np.abs(rho1 - ex)) * h), spread, s.steps


def gauss_cell_average(n, c, w):
    """Cell averages of exp(-((x - c)/w)^2) over n equal cells of [0, 1]."""
    e = np.array([math.erf((k / n - c) / w) for k in range(n + 1)])
    return 0.5 * math.sqrt(math.pi) * w * np.diff(e) * n


def run_advection(n, t_end=0.3, limiter_kind="vanleer", cfl=0.8):
    """Smooth check of the unsplit 2-D path: a Gaussian density bump (amplitude 0.5, width
    0.08) in uniform pressure advected diagonally at u = v = 1 on n x n cells of [0, 1]^2
    (outflow on all sides; the bump stays clear of them) from (0.35, 0.35) to
    (0.65, 0.65). The exact solution is the shifted bump; returns the L1 density error."""
    h = 1.0 / n
    bc = {"xlo": "outflow", "xhi": "outflow", "ylo": "outflow", "yhi": "outflow"}
    s = Euler2D(n, n, h, h, np.zeros((n, n), bool), bc, (1.0, 1.0, 1.0, 1.0),
                limiter_kind, cfl)
    w, c0 = 0.08, 0.35

    def rho(c):
        g1 = gauss_cell_average(n, c, w)
        return 1.0 + 0.5 * g1[:, None] * g1[None, :]
    one = np.ones((n, n))
    s.set_interior(np.array([rho(c0), one, one, one]))
    while s.t < t_end - 1e-14:
        s.step(min(s.max_dt(), t_end - s.t))
    err = np.abs(s.primitive()[0, 1:-1, 1:-1] - rho(c0 + t_end)).sum() * h * h
    return float(err), s.steps


def sod_check(limiter_kind):
    rows = []
    print(f"Sod shock tube, t = 0.2, MUSCL-Hancock + HLLC, {limiter_kind} limiter, CFL 0.8")
    for along in ("x", "y"):
        prev = None
        for n in (100, 200, 400, 800):
            t0 = time.time()
            e, spread, steps = run_sod(n, along, limiter_kind=limiter_kind)
            order = math.log2(prev / e) if prev else float("nan")
            prev = e
            rows.append({"along": along, "cells": n, "L1_rho": e, "order": order,
                         "steps": steps, "transverse_spread": spread,
                         "wall_s": time.time() - t0})
            print(f"  along {along}: {n:4d} cells  L1(rho) = {e:.4e}  order {order:5.2f}"
                  f"  ({steps} steps, transverse spread {spread:.1e})")
    print("Smooth check: Gaussian density bump advected diagonally (u = v = 1) to t = 0.3")
    adv, prev = [], None
    for n in (32, 64, 128, 256):
        e, steps = run_advection(n, limiter_kind=limiter_kind)
        order = math.log2(prev / e) if prev else float("nan")
        prev = e
        adv.append({"cells": n, "L1_rho": e, "order": order, "steps": steps})
        print(f"  {n:3d} x {n:3d} cells  L1(rho) = {e:.4e}  order {order:5.2f}")
    with open(os.path.join(RESULTS, "euler_reference_sod.json"), "w") as f:
        json.dump({"limiter": limiter_kind, "rows": rows, "advection": adv}, f, indent=1)
    return rows


# ----------------------------------------------------------------------------------------
# The main scene

def first_crossing(profile, x, threshold):
    """First x (linear interpolation between cell centres), scanning from the start of the
    profile, where it exceeds threshold; NaN if nowhere. At the first cell: x[0]."""
    above = np.nonzero(profile > threshold)[0]
    if len(above) == 0:
        return float("nan")
    k = above[0]
    if k == 0:
        return float(x[0])
    return float(x[k - 1] + (x[k] - x[k - 1]) * (threshold - profile[k - 1])
                 / (profile[k] - profile[k - 1]))


class Scene:
    """Geometry of the main scene: channel [0, length] x [0, height], bar of the project's
    size (6 mm x 30 mm) on the floor with its upstream face at bar_x (0.05 by default)."""

    def __init__(self, height=0.18, length=LENGTH, bar_x=BAR_X0):
        self.height, self.length = height, length
        self.x0, self.x1, self.h = bar_x, bar_x + (BAR_X1 - BAR_X0), BAR_H


def standoff(rho, dx, dy, sc):
    """The MPM project's stand-off (tools/supersonic_bar.py): distance from the upstream face
    to where the density averaged over the bar's height first exceeds 1.5 x free stream,
    scanning from the inflow (linear interpolation between the two cell centres); a
    crossing in the first cell counts as x_s = 0 (stand-off = the whole upstream length),
    as in the project."""
    band = rho[:, : int(round(sc.h / dy))].mean(axis=1)
    i_face = int(round(sc.x0 / dx))
    x = (np.arange(len(band)) + 0.5) * dx
    above = np.nonzero(band[:i_face] > 1.5 * RHO_INF)[0]
    if len(above) == 0:
        return float("nan")
    k = above[0]
    if k == 0:
        return sc.x0
    xs = x[k - 1] + dx * (1.5 * RHO_INF - band[k - 1]) / (band[k] - band[k - 1])
    return sc.x0 - xs


def diagnostics(s, sc):
    dx, dy = s.dx, s.dy
    rho, u, v, p = s.primitive()[:, 1:-1, 1:-1]
    solid = s.body[1:-1, 1:-1]
    x = (np.arange(s.nx) + 0.5) * dx
    thr = 1.5 * RHO_INF
    rows_x = np.array([first_crossing(np.where(solid[:, j], 0.0, rho[:, j]), x, thr)
                       for j in range(s.ny)])
    i_face = int(round(sc.x0 / dx))
    mach = np.sqrt(u * u + v * v) / np.sqrt(GAMMA * p / rho)
    sub_cols = np.nonzero((mach[:i_face] < 1.0).all(axis=1))[0]
    x_sub = float(x[sub_cols[0]]) if len(sub_cols) else float("nan")
    front, back, fy = s.body_forces()
    ref = RHO_INF * U_INF * sc.height
    mdot_out = float((rho[-1] * u[-1]).sum() * dy / ref)
    mdot_in = float(s.F[0, 0, :].sum() * dy / ref)  # mass flux through the inflow face
    # The throat the flow crossing the column 5 mm upstream of the bar would need to pass
    # choked (isentropically from there on), over the channel height: the sum over the
    # column of rho u / G*, G* = the sonic mass flux at the cell's total pressure and
    # temperature. Free stream: 1/2.637 = 0.379; behind a normal shock: 0.760. If it
    # exceeds the effective throat over the bar (at most the free area, 0.833), the flow
    # cannot pass and the shock system must move upstream.
    i5 = max(i_face - int(round(0.005 / dx)), 0)
    r5, u5, v5, p5 = rho[i5], u[i5], v[i5], p[i5]
    m2 = (u5 * u5 + v5 * v5) * r5 / (GAMMA * p5)
    k = 1.0 + 0.5 * (GAMMA - 1.0) * m2
    p0 = p5 * k ** (GAMMA / (GAMMA - 1.0))
    RT0 = p5 / r5 * k
    crit = (2.0 / (GAMMA + 1.0)) ** ((GAMMA + 1.0) / (2.0 * (GAMMA - 1.0)))
    Gs = p0 * np.sqrt(GAMMA / RT0) * crit
    astar = float((r5 * u5 / Gs).sum() * dy / sc.height)
    x_floor = float(rows_x[0])
    d = {"astar_req": astar, "t": s.t, "standoff": standoff(rho, dx, dy, sc), "Fx": front - back,
         "F_front": front, "F_back": back, "Fy": fy, "x_shock_floor": x_floor,
         "x_shock_top": float(rows_x[-1]),
         "x_shock_min": float(np.nanmin(rows_x)) if np.isfinite(rows_x).any() else float("nan"),
         "x_subsonic_column": x_sub,
         "subsonic_frac_inflow": float((mach[0] < 1.0).mean()),
         "subsonic_frac_bar": float((mach[i5] < 1.0).mean()),
         "mdot_in": mdot_in, "mdot_out": mdot_out}
    d["unstarted"] = int((np.isfinite(x_floor) and x_floor < 0.005) or np.isfinite(x_sub))
    return d


def mm_tag(v):
    return f"{v * 1e3:g}"


def run_scene(dx, t_end, sc, prefix, every, limiter_kind, cfl, panels=None):
    for L in (sc.x0, sc.x1 - sc.x0, sc.h, sc.length, sc.height):
        if abs(L / dx - round(L / dx)) > 1e-9:
            sys.exit(f"dx = {dx} does not divide {L}")
    nx, ny = int(round(sc.length / dx)), int(round(sc.height / dx))
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dx
    solid = ((x[:, None] > sc.x0) & (x[:, None] < sc.x1)) & (y[None, :] < sc.h)
    W_inf = (RHO_INF, U_INF, 0.0, P_INF)
    bc = {"xlo": ("inflow", W_inf), "xhi": "outflow", "ylo": "wall", "yhi": "wall"}
    s = Euler2D(nx, ny, dx, dx, solid, bc, W_inf, limiter_kind, cfl)
    s.set_interior(np.array(W_inf)[:, None, None] * np.ones((1, nx, ny)))

    print(f"{prefix}: {nx} x {ny} cells, dx = {dx * 1e3:g} mm, t_end = {t_end * 1e3:g} ms",
          flush=True)
    hist, snaps = [], {}
    n_out = int(round(t_end / every))
    out_times = [round(k * every, 12) for k in range(1, n_out + 1)]
    # density panels: by default six, at 0.5, 1.0, ..., 3.0 ms for the standard t_end = 3 ms
    if panels:
        snap_times = [round(t, 12) for t in panels if t <= t_end + 1e-12]
    else:
        snap_times = [round(k * t_end / 6, 12) for k in range(1, 7)]
    targets = sorted(set(out_times + snap_times))
    t0 = time.time()
    for target in targets:
        while s.t < target - 1e-13:
            s.step(min(s.max_dt(), target - s.t))
        s.t = target  # exact output time (removes round-off drift)
        d = diagnostics(s, sc)
        if target in out_times:
            hist.append(d)
        if target in snap_times:
            snaps[target] = (s.primitive()[0, 1:-1, 1:-1].copy(), d["standoff"])
        if (target in out_times and len(hist) % 4 == 0) or target in snap_times:
            print(f"  t = {target * 1e3:5.2f} ms  step {s.steps:6d}  stand-off "
                  f"{d['standoff'] * 1e3:6.2f} mm  Fx {d['Fx']:8.1f} N/m  shock floor/top "
                  f"{d['x_shock_floor'] * 1e3:6.1f}/{d['x_shock_top'] * 1e3:6.1f} mm  "
                  f"subsonic at inflow {d['subsonic_frac_inflow']:.2f}  mdot in/out "
                  f"{d['mdot_in']:.3f}/{d['mdot_out']:.3f}  A*/H {d['astar_req']:.3f}  "
                  f"[{time.time() - t0:6.1f} s]",
                  flush=True)
    wall = time.time() - t0

    keys = ["t", "standoff", "Fx", "F_front", "F_back", "Fy", "x_shock_floor", "x_shock_top",
            "x_shock_min", "x_subsonic_column", "subsonic_frac_inflow", "subsonic_frac_bar",
            "unstarted", "mdot_in", "mdot_out", "astar_req"]
    with open(prefix + ".csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for d in hist:
            w.writerow([f"{d[k]:.6g}" if isinstance(d[k], float) else d[k] for k in keys])
    plot_strip(snaps, sc, prefix + "_strip.png",
               f"Euler reference (MUSCL-Hancock + HLLC), dx = {dx * 1e3:g} mm, "
               f"H = {sc.height * 1e3:g} mm, bar at x = {sc.x0 * 1e3:g} mm")

    def at(tq):
        for d in hist:
            if abs(d["t"] - tq) < 1e-9:
                return d["standoff"]
        return float("nan")
    unstart = [d for d in hist if d["unstarted"]]
    floor_in = [d for d in hist if np.isfinite(d["x_shock_floor"]) and d["x_shock_floor"] < 0.005]
    subcol = [d for d in hist if np.isfinite(d["x_subsonic_column"])]
    top_up = [d for d in hist if np.isfinite(d["x_shock_top"]) and d["x_shock_top"] < sc.x0]
    late = [d["Fx"] for d in hist if 2e-3 - 1e-9 <= d["t"] <= 3e-3 + 1e-9]
    summary = {"prefix": os.path.basename(prefix), "dx": dx, "height": sc.height,
               "length": sc.length, "bar_x": sc.x0, "nx": nx,
               "ny": ny, "t_end": t_end, "steps": s.steps, "wall_s": wall, "cfl": cfl,
               "limiter": limiter_kind, "first_order_steps": s.first_order_steps,
               "floored_cells": s.floored,
               "standoff": {f"{tq * 1e3:g}": at(tq) for tq in (0.5e-3, 1e-3, 2e-3, 3e-3)},
               "unstart_t": unstart[0]["t"] if unstart else None,
               "floor_shock_inflow_t": floor_in[0]["t"] if floor_in else None,
               "subsonic_column_t": subcol[0]["t"] if subcol else None,
               "top_shock_upstream_t": top_up[0]["t"] if top_up else None,
               "mean_Fx_2_3ms": float(np.mean(late)) if late else None,
               "final": hist[-1] if hist else None}
    with open(prefix + ".json", "w") as f:
        json.dump(summary, f, indent=1)
    print(f"  wall time {wall:.1f} s, {s.steps} steps, first-order steps "
          f"{s.first_order_steps}, floored cells {s.floored}")
    print(f"  wrote {prefix}.csv, {prefix}_strip.png, {prefix}.json")
    return summary


def plot_strip(snaps, sc, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle
    times = sorted(snaps)
    if not times:
        return
    aspect = sc.height / sc.length
    fig, axes = plt.subplots(len(times), 1, figsize=(7.5, 0.6 + 6.6 * aspect * len(times)),
                             squeeze=False, sharex=True)
    im = None
    for ax, t in zip(axes[:, 0], times):
        rho, so = snaps[t]
        im = ax.imshow(rho.T, origin="lower", extent=(0, sc.length, 0, sc.height), vmin=0.0,
                       vmax=6.0, cmap="viridis", interpolation="nearest")
        ax.add_patch(Rectangle((sc.x0, 0), sc.x1 - sc.x0, sc.h, color="black"))
        ax.set_title(f"t = {t * 1e3:.2f} ms   stand-off {so * 1e3:.1f} mm", fontsize=9)
        ax.set_ylabel("y (m)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("x (m)", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.subplots_adjust(right=0.86, hspace=0.35, top=0.95)
    cax = fig.add_axes([0.89, 0.12, 0.025, 0.76])
    fig.colorbar(im, cax=cax, label="density (kg/m$^3$)")
    fig.savefig(path, dpi=130)
    plt.close(fig)


# ----------------------------------------------------------------------------------------
def write_report():
    """Rewrite bench/results/euler_reference_summary.md from the runs' JSON files, keeping the
    hand-written text after the NOTES line."""
    path = os.path.join(RESULTS, "euler_reference_summary.md")
    notes = ""
    if os.path.exists(path):
        with open(path) as fh:
            text = fh.read()
        k = text.find("<!-- NOTES -->")
        if k >= 0:
            notes = text[k:]
    if not notes:
        notes = "<!-- NOTES -->\n"

    def f(v, scale=1e3, fmt="{:.1f}"):
        return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) \
            else fmt.format(v * scale)
    lines = ["# Euler reference for the main scene (bench/euler_reference.py)", "",
             "Gas only, rigid bar: 2-D inviscid Euler, MUSCL-Hancock + HLLC, unsplit, "
             "CFL 0.8 on dt = CFL / max((|u|+c)/dx + (|v|+c)/dy). Stand-off as in "
             "tools/supersonic_bar.py. Wall times on the shared 2-core machine (loaded by "
             "other jobs, so they vary by up to 2x), one process.", ""]
    sod = os.path.join(RESULTS, "euler_reference_sod.json")
    if os.path.exists(sod):
        with open(sod) as fh:
            S = json.load(fh)
        lines += [f"## Solver check: Sod shock tube (t = 0.2, {S['limiter']} limiter)", "",
                  "| along | cells | L1(rho) | order |", "|---|---|---|---|"]
        for r in S["rows"]:
            o = "–" if not np.isfinite(r["order"]) else f"{r['order']:.2f}"
            lines.append(f"| {r['along']} | {r['cells']} | {r['L1_rho']:.3e} | {o} |")
        lines.append("")
        if S.get("advection"):
            lines += ["Smooth check: a Gaussian density bump advected diagonally (u = v = 1, "
                      "t = 0.3) on n x n cells, the unsplit 2-D path:", "",
                      "| cells | L1(rho) | order |", "|---|---|---|"]
            for r in S["advection"]:
                o = "–" if not np.isfinite(r["order"]) else f"{r['order']:.2f}"
                lines.append(f"| {r['cells']}^2 | {r['L1_rho']:.3e} | {o} |")
            lines.append("")
    runs = []
    for p in sorted(glob.glob(os.path.join(RESULTS, "euler_reference_*.json"))):
        if not p.endswith("_sod.json"):
            with open(p) as fh:
                runs.append(json.load(fh))
    runs.sort(key=lambda r: (r.get("bar_x", 0.05), r["height"], r["t_end"], -r["dx"]))

    def when(v):
        return "no" if v is None else f"{v * 1e3:.2f} ms"
    lines += ["## Runs", "",
              "Unstart indicators, first time in the history: (a) the shock below x = 5 mm in "
              "the floor row (the bow shock's foot at the inflow), (b) a column upstream of "
              "the bar subsonic over the whole height, (c) the shock on the top wall upstream "
              "of the bar's face (the Mach stem ahead of the throat). Final: the top-wall "
              "shock's x, the throat needed A*/H (5 mm ahead of the bar), the inflow's mass "
              "flow over rho u H.", "",
              "| run | dx (mm) | H (mm) | bar x (mm) | t_end (ms) | cells | steps | wall (s) "
              "| stand-off 0.5 / 1 / 2 / 3 ms (mm) | (a) | (b) | (c) | mean Fx 2–3 ms (N/m) "
              "| final x top (mm) | final A*/H | final mdot_in |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        so = " / ".join(f(r["standoff"].get(k)) for k in ("0.5", "1", "2", "3"))
        fin = r.get("final") or {}
        lines.append(
            f"| {r['prefix']} | {r['dx'] * 1e3:g} | {r['height'] * 1e3:g} | "
            f"{r.get('bar_x', 0.05) * 1e3:g} | {r['t_end'] * 1e3:g} | {r['nx']}x{r['ny']} "
            f"| {r['steps']} | {r['wall_s']:.0f} | {so} | {when(r['floor_shock_inflow_t'])} | "
            f"{when(r['subsonic_column_t'])} | {when(r.get('top_shock_upstream_t'))} | "
            f"{f(r['mean_Fx_2_3ms'], 1, '{:.0f}')} | {f(fin.get('x_shock_top'))} | "
            f"{f(fin.get('astar_req'), 1, '{:.3f}')} | {f(fin.get('mdot_in'), 1, '{:.3f}')} |")
    bad = [r["prefix"] for r in runs if r["first_order_steps"] or r["floored_cells"]]
    lines += ["", "Steps redone at first order / floored cells: "
              + (", ".join(bad) if bad else "none in any run") + "."]
    lines += ["", "Histories: `<run>.csv`, density strips `<run>_strip.png`, summaries "
              "`<run>.json` (run names: dx, then _h<H>, _L<length>, _bx<bar x>, _t<t_end> "
              "where not the main scene's; mm).", "", notes.rstrip() + "\n"]
    with open(path, "w") as fh:
        fh.write("\n".join(lines))
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dx", type=float, default=0.002, help="cell size, m (default 0.002)")
    ap.add_argument("--t-end", type=float, default=3e-3, help="end time, s (default 0.003)")
    ap.add_argument("--height", type=float, default=0.18, help="channel height, m")
    ap.add_argument("--length", type=float, default=LENGTH, help="channel length, m")
    ap.add_argument("--bar-x", type=float, default=BAR_X0,
                    help="x of the bar's upstream face, m (default 0.05)")
    ap.add_argument("--out-prefix", default=None,
                    help="output prefix (default bench/results/euler_reference_dx<mm>"
                         "[_h<mm> if the height is not 0.18])")
    ap.add_argument("--standoff-every", type=float, default=5e-5,
                    help="interval of the CSV history, s (default 5e-5)")
    ap.add_argument("--panels", default=None,
                    help="times of the density panels, ms, comma-separated (default: six, "
                         "evenly spaced up to t_end)")
    ap.add_argument("--cfl", type=float, default=0.8)
    ap.add_argument("--limiter", choices=("vanleer", "minmod"), default="vanleer")
    ap.add_argument("--sod", action="store_true", help="run the Sod check only")
    ap.add_argument("--report", action="store_true", help="only rewrite the summary .md")
    a = ap.parse_args()
    os.makedirs(RESULTS, exist_ok=True)
    if a.sod:
        sod_check(a.limiter)
    elif not a.report:
        tag = f"euler_reference_dx{mm_tag(a.dx)}"
        tag += "" if abs(a.height - 0.18) < 1e-12 else f"_h{mm_tag(a.height)}"
        tag += "" if abs(a.length - LENGTH) < 1e-12 else f"_L{mm_tag(a.length)}"
        tag += "" if abs(a.bar_x - BAR_X0) < 1e-12 else f"_bx{mm_tag(a.bar_x)}"
        tag += "" if abs(a.t_end - 3e-3) < 1e-12 else f"_t{mm_tag(a.t_end)}"
        prefix = a.out_prefix or os.path.join(RESULTS, tag)
        run_scene(a.dx, a.t_end, Scene(a.height, a.length, a.bar_x), prefix,
                  a.standoff_every, a.limiter, a.cfl,
                  [float(t) * 1e-3 for t in a.panels.split(",")] if a.panels else None)
    write_report()


if __name__ == "__main__":
    main()
