"""Exact relations of 1-D ideal-gas waves (Toro, ch. 4) and of a 1-D elastic slab, shared by the
gas-solid wave tests (test_fsi_waves.py, test_fsi_reflection.py).

Every function takes the ratio of specific heats gamma (default 1.4)."""
import math


def sound(rho, p, gamma=1.4):
    return math.sqrt(gamma * p / rho)


def wave_du(p, rho, pk, gamma=1.4):
    """Velocity change across a wave from the state (rho, pk) to pressure p (f_K of Toro):
    positive for a shock (p > pk), negative for a rarefaction."""
    g = gamma
    if p > pk:
        a, b = 2 / ((g + 1) * rho), (g - 1) / (g + 1) * pk
        return (p - pk) * math.sqrt(a / (p + b))
    return 2 * sound(rho, pk, g) / (g - 1) * ((p / pk) ** ((g - 1) / (2 * g)) - 1)


def shock_density(rho0, p0, p1, gamma=1.4):
    """Density behind a shock of pressure p1 into (rho0, p0) (Rankine-Hugoniot)."""
    b = (gamma - 1) / (gamma + 1)
    q = p1 / p0
    return rho0 * (q + b) / (b * q + 1)


def shock_state(rho0, p0, p1, gamma=1.4):
    """(rho1, u1, speed) behind a right-going shock of pressure p1 into (rho0, 0, p0)."""
    g, q = gamma, p1 / p0
    rho1 = shock_density(rho0, p0, p1, g)
    s = sound(rho0, p0, g) * math.sqrt((g + 1) / (2 * g) * q + (g - 1) / (2 * g))
    return rho1, s * (1 - rho0 / rho1), s


def shock_pressure(mach, p0, gamma=1.4):
    """Pressure behind a shock of Mach number mach into gas at pressure p0."""
    return p0 * (1 + 2 * gamma / (gamma + 1) * (mach * mach - 1))


def bisect(f, lo, hi):
    flo = f(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        if (fm > 0) == (flo > 0):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def plane_strain_M(E, nu):
    return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
