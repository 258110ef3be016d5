"""Gas-solid waves through the coupler (cases/fsi_transmission.ini, cases/fsi_slab.ini).

Both scenes are quasi-1-D strips, 3 cells high, periodic in y, slip walls at the x ends,
linear_elastic solids (plane strain), gamma = 1.4; dx = 0.01 (`long`: 0.005). Arguments:
[long] [scheme:method ...]; default velocity:usl velocity:musl traction:usl traction:musl.

1. Transmission (cases/fsi_transmission.ini; the header explains the start-up). A right-going
   shock p = 1 -> 1.1 (exact Rankine-Hugoniot state) in gas rho = 1 hits a slab rho_s = 0.1,
   E = 42, nu = 0.3 (M = 56.54, c_s = 23.78; Z_s / Z_g = 2.01). The slab starts moving at
   w = p / Z_s towards the gas so that the ambient p does not launch a 1/3 p rarefaction.
   The code's small-strain model has the nominal stress P = M (F - 1) / F (V0 sigma in the
   forces), so at its prestrain p / M = 1.8 % its impedance is Z_s / F0 = 2.420 (ratio 2.045).
   Reference: the exact finite-amplitude answer (reflected shock in the gas, linear solid):
   p* = 1.13366, transmission T = 1.3366, reflection R = 0.3366 of the incident jump
   (acoustic 2 Z / (Z + Z_g) = 1.3432, (Z - Z_g) / (Z + Z_g) = 0.3432). Measured: the incident
   jump (gas p on either side of the shock at t = 0.06); the transmitted stress from F (and
   the particle velocity times Z) in the slab over the region that carries the interface's
   state from DELAY after the impact to t = 0.34, against the slab's ambient state at 0.06;
   the reflected jump from the gas between the reflected shock and the interface at 0.34.
2. Free slab (cases/fsi_slab.ini): rho_s = 50, E = 52, nu = 0.3 (Z_s / Z_g = 50), L = 0.2,
   gas p_L = 1.2 | p_R = 1, rho = 1. Mean acceleration from the slab's momentum (sum m v) over
   [0, 0.16] (before L / c_s = 0.169) against the exact (p_iL - p_iR) / (rho_s L) = 0.019395
   with the face pressures of the exact gas rarefactions against the stress-free slab;
   (p_L - p_R) / (rho_s L) = 0.02 is 3.1 % higher (printed). Also: the impulse of Fx_solid in
   coupling.csv equals the momentum gained.

Measured (dx = 0.01 | 0.005), error of T (stress; velocity), R - R_exact, error of a; the gas
with the PIC share of 0.02 a gas beside a solid takes under the classic update (2026-12-06):
  velocity usl    T +0.62 %, +0.50 % | +0.43 %, +0.30 %; R -0.023 | -0.050; a -0.14 % | +0.00 %
  velocity musl   T +1.12 %, +1.08 % | +0.76 %, +0.61 %; R -0.023 | -0.052; a -0.21 % | +0.01 %
  traction usl    T +0.62 %, +0.50 % | +0.43 %, +0.30 %; R -0.023 | -0.050; a -0.14 % | +0.00 %
  traction musl   T +1.12 %, +1.08 % | +0.76 %, +0.61 %; R -0.023 | -0.052; a -0.21 % | +0.01 %
(pure FLIP, before: T +0.70 % | +0.41 % usl, +1.21 % | +0.76 % musl; R -0.024 | -0.053.)
In a quasi-1-D strip the interface normal is the whole velocity, so traction (slip) and
velocity (no-slip) agree. (An earlier traction held the gas to the solid's velocity from before
the gas's load; it created energy at the interface and failed here with usl: T +7.1 %,
R +0.26. The wall now moves with the solid's velocity after the load; see coupling_traction.c.)
The interface force of coupling.csv gives T within 0.3-0.8 %.
Not good enough: the reflected jump measured in the gas falls short and the shortfall grows
with refinement (gas p* 1.1327 -> 1.1299 for velocity usl, while the interface force and the
slab give 1.136): at 0.005 it is -0.050/-0.052, just inside the 0.06 tolerance.
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
from gaswaves import bisect, plane_strain_M, shock_state, sound, wave_du  # noqa: E402

check = mt.Checks("test_fsi_waves")
ARGS = sys.argv[1:]
LONG = bool(ARGS) and ARGS[0] == "long"
if LONG:
    ARGS = ARGS[1:]
# scheme:method pairs
PAIRS = [a.split(":") for a in ARGS] or [("velocity", "usl"), ("velocity", "musl"),
                                         ("traction", "usl"), ("traction", "musl")]
DX = 0.005 if LONG else 0.01
H = 3 * DX  # strip height: 3 cells, the fewest a periodic axis allows with quadratic splines


def mean_in(x, q, a, b):
    sel = (x >= a) & (x <= b)
    if not sel.any():
        raise SystemExit(f"no particles in [{a}, {b}]")
    return float(q[sel].mean())


def snapshot_at(out, t):
    return min(mt.snapshots(out), key=lambda s: abs(s[0] - t))


def run(case, name, scheme, method, extra):
    out = mt.outdir(f"{name}_{scheme}_{method}")
    mt.run(["run", mt.case(case), f"output.dir={out}", f"grid.dx={DX}", f"coupling.scheme={scheme}",
            f"time.method={method}", "run.progress=false"] + list(extra))
    print(f"cost {name} {scheme} {method} dx = {DX}: {mt.cost(out)}")
    return out


def coupling_csv(out):
    return np.genfromtxt(os.path.join(out, "coupling.csv"), delimiter=",", names=True)


# ---- check 1: transmission into a slab --------------------------------------------------------
RHO_G, P_A, P1 = 1.0, 1.0, 1.1
RHO_S, E_S, NU_S = 0.1, 42.0, 0.3
X_S, X_I, L_S, T1_END = 1.0, 1.2, 6.2, 0.34
M_S = plane_strain_M(E_S, NU_S)
C_S = math.sqrt(M_S / RHO_S)
Z_G = RHO_G * sound(RHO_G, P_A)
Z_S = math.sqrt(RHO_S * M_S)
RHO1, U1, S_I = shock_state(RHO_G, P_A, P1)
T_HIT = (X_I - X_S) / S_I
W = P_A / Z_S  # the slab's initial speed towards the gas: the interface starts at rest
# The code's small-strain model puts V0 sigma into the nodal forces: its nominal stress in
# uniaxial strain is P = sigma / F = M (F - 1) / F, so the slab held at p has F0 = M / (M + p)
# and impedance sqrt(rho_s dP/dF) = Z_s / F0 (1.8 % above Z_s at this prestrain).
F0 = M_S / (M_S + P_A)
Z_EFF = Z_S / F0
T_AC = 2 * Z_EFF / (Z_EFF + Z_G)
R_AC = (Z_EFF - Z_G) / (Z_EFF + Z_G)
# Exact for the finite shock: a reflected shock into the incident state (rho1, u1, p1) leaves
# the gas at u*, p*; the linear solid behind the interface holds p* = p_a + Z_eff u*.
P_STAR = bisect(lambda p: (U1 - wave_du(p, RHO1, P1)) - (p - P_A) / Z_EFF, P1, 2 * P1)
U_STAR = (P_STAR - P_A) / Z_EFF
T_EX = (P_STAR - P_A) / (P1 - P_A)
R_EX = (P_STAR - P1) / (P1 - P_A)
C1 = sound(RHO1, P1)


def transmission(scheme, method):
    extra = [f"domain.hi={X_I + L_S + 2 * DX} {H}", f"geometry.shocked.hi={X_S} {H}",
             f"geometry.ambient.hi={X_I} {H}", f"geometry.slab.hi={X_I + L_S} {H}",
             f"gas.shocked.density={RHO1!r}", f"gas.shocked.velocity={U1!r} 0",
             f"solid.slab.velocity={-W!r} 0", f"time.t_end={T1_END}"]
    out = run("fsi_transmission.ini", "transmission", scheme, method, extra)
    tag = f"transmission {scheme} {method}"
    # Incident jump: ahead of and behind the incident shock half way to the interface.
    t0, path0 = snapshot_at(out, 0.06)
    g0, s0 = mt.particles(path0, "fluid"), mt.particles(path0, "solid")
    xsh = X_S + S_I * t0
    p0 = mean_in(g0["x"][:, 0], g0["p"][:, 0], xsh + 3 * DX, X_I - 4 * DX)
    # Solid ambient (held at p by the compression front that left at t = 0), same snapshot.
    F0m = s0["F"][:, 0]
    xs0 = s0["x"][:, 0]
    P0_s = mean_in(xs0, M_S * (F0m - 1) / F0m, X_I + 0.1, X_I + C_S * t0 - 0.3)
    v0_s = mean_in(xs0, s0["v"][:, 0], X_I + 0.1, X_I + C_S * t0 - 0.3)
    # Final state.
    tf, pathf = mt.snapshots(out)[-1]
    g, s = mt.particles(pathf, "fluid"), mt.particles(pathf, "solid")
    xg, pg = g["x"][:, 0], g["p"][:, 0]
    x_head = (C1 + U1) * tf  # head of the rarefaction from the left wall
    x_refl = X_I - (sound(RHO1, P_STAR) - U_STAR) * (tf - T_HIT)  # about: the reflected shock
    p1 = mean_in(xg, pg, x_head + 4 * DX, x_refl - 5 * DX)
    p_star = mean_in(xg, pg, x_refl + 5 * DX, X_I - 4 * DX)
    dp_i = p1 - p0
    # Transmitted wave: the slab from the interface to where it holds the interface's state
    # DELAY after the impact (the rise of the smeared shock), in current positions.
    xs, Fs = s["x"][:, 0], s["F"][:, 0]
    lo, hi = X_I + 0.1, X_I + C_S * (tf - T_HIT - DELAY)
    P_T = mean_in(xs, M_S * (Fs - 1) / Fs, lo, hi)
    v_T = mean_in(xs, s["v"][:, 0], lo, hi)
    dP = P0_s - P_T  # compression positive
    # The interface force (coupling.csv), over the same interface times.
    c = coupling_csv(out)
    win = (c["t"] >= T_HIT + DELAY) & (c["t"] <= tf)
    p_if = float(np.mean(c["Fx_solid"][win])) / H
    before = (c["t"] >= 0.25 * T_HIT) & (c["t"] <= 0.5 * T_HIT)
    p_if0 = float(np.mean(c["Fx_solid"][before])) / H
    T_m, R_m, Tv_m = dP / dp_i, (p_star - p1) / dp_i, Z_EFF * (v_T - v0_s) / dp_i
    T_if = (p_if - p_if0) / dp_i
    print(f"info {tag}: incident p0 {p0:.5f} -> p1 {p1:.5f} (dp_I {dp_i:.5f}, exact 0.1); slab "
          f"ambient P {P0_s:.5f} (exact -{P_A}), v {v0_s:+.5f} (exact 0); gas p* {p_star:.5f} "
          f"(exact {P_STAR:.5f}); slab P {P_T:.5f}, v {v_T:.5f} (exact u* {U_STAR:.5f}); "
          f"interface force / H {p_if0:.5f} -> {p_if:.5f}")
    eT, eR = T_m / T_EX - 1, R_m - R_EX
    check(abs(eT) <= TOL_T, f"{tag}: transmitted stress / incident jump {T_m:.4f}, exact {T_EX:.4f} "
          f"(acoustic {T_AC:.4f}): {100 * eT:+.2f} % (<= {100 * TOL_T:g} %)")
    check(abs(Tv_m / T_EX - 1) <= TOL_T, f"{tag}: Z_s x transmitted velocity / incident jump "
          f"{Tv_m:.4f} vs {T_EX:.4f}: {100 * (Tv_m / T_EX - 1):+.2f} % (<= {100 * TOL_T:g} %)")
    check(abs(eR) <= TOL_R, f"{tag}: reflected jump / incident jump {R_m:.4f}, exact {R_EX:.4f} "
          f"(acoustic {R_AC:.4f}): off by {eR:+.4f} (<= {TOL_R:g})")
    print(f"info {tag}: interface force: transmission {T_if:.4f} ({100 * (T_if / T_EX - 1):+.2f} %)")
    return T_m, R_m


# ---- check 2: a free slab between two gas columns ----------------------------------------------
P_L, P_R, RHO_SL, E_SL, NU_SL = 1.2, 1.0, 50.0, 52.0, 0.3
X_L, L_SL = 0.3, 0.2
M_SL = plane_strain_M(E_SL, NU_SL)
Z_SL, C_SL = math.sqrt(RHO_SL * M_SL), math.sqrt(M_SL / RHO_SL)
T2_END = 0.16  # before L / c_s = 0.169, when the compression waves reach the opposite faces
# Face pressures: a rarefaction into each gas column, the stress-free slab's face moving at
# p_i / Z_s (left face into +x, right face into -x).
P_IL = bisect(lambda p: -wave_du(p, RHO_G, P_L) - p / Z_SL, 1e-6, P_L)
P_IR = bisect(lambda p: -wave_du(p, RHO_G, P_R) - p / Z_SL, 1e-6, P_R)
A_EX = (P_IL - P_IR) / (RHO_SL * L_SL)
A_SIMPLE = (P_L - P_R) / (RHO_SL * L_SL)


def slab(scheme, method):
    extra = [f"domain.hi=0.8 {H}", f"geometry.left.hi={X_L} {H}",
             f"geometry.slab.hi={X_L + L_SL} {H}", f"geometry.right.hi=0.8 {H}",
             f"time.t_end={T2_END}"]
    out = run("fsi_slab.ini", "slab", scheme, method, extra)
    tag = f"slab {scheme} {method}"
    snaps = mt.snapshots(out)
    mass = None
    ts, Ps = [], []
    for t, path in snaps:
        s = mt.particles(path, "solid")
        mass = float(s["m"].sum())
        ts.append(t)
        Ps.append(float((s["m"][:, 0] * s["v"][:, 0]).sum()))
    ts, Ps = np.array(ts), np.array(Ps)
    a_mom = (Ps[-1] - Ps[0]) / (mass * (ts[-1] - ts[0]))
    # Least-squares slope over the later half (free of the start-up of the smeared faces).
    late = ts >= 0.5 * ts[-1]
    a_fit = np.polyfit(ts[late], Ps[late], 1)[0] / mass
    c = coupling_csv(out)
    imp = float(np.sum(c["Fx_solid"] * c["dt"]))
    a_F = imp / (mass * c["t"][-1])
    print(f"info {tag}: solid momentum {Ps[-1]:.6e} at t = {ts[-1]:g}; impulse of Fx_solid "
          f"{imp:.6e}; slope of the later half {a_fit:.5f}")
    e = a_mom / A_EX - 1
    check(abs(e) <= TOL_A, f"{tag}: mean acceleration {a_mom:.5f}, exact {A_EX:.5f} "
          f"((p_L - p_R) / (rho_s L) = {A_SIMPLE:.5f}): {100 * e:+.2f} % (<= {100 * TOL_A:g} %)")
    check(abs(a_F / a_mom - 1) <= 1e-9 or abs(a_F - a_mom) <= 1e-9 * A_EX,
          f"{tag}: impulse of the interface force in coupling.csv = momentum gained "
          f"({a_F:.8f} vs {a_mom:.8f})")
    print(f"info {tag}: acceleration from the later-half slope {a_fit:.5f} "
          f"({100 * (a_fit / A_EX - 1):+.2f} %)")
    return a_mom


# The smeared incident shock (and the band of shared nodes) makes the interface pressure rise
# over about 6 cells of gas travel around the impact; averages start 5 cells (of c_g) after it.
DELAY = 5 * DX / sound(RHO_G, P_A)
# Tolerances (measured at dx = 0.01 / 0.005; see the header):
# TOL_T 3 %: the interface pressure rings after the impact (+-0.025, a fifth of the jump,
#   period ~0.07); the averages span about two periods. Measured |error| <= 1.2 %.
# TOL_R 0.06 of the incident jump (18 % of R): the reflected jump is the difference of two gas
#   pressures, each carrying the FLIP noise and heating of the classic updates (p1 comes out
#   0.17 % high, bins scatter by +-3 % next to the interface). Measured -0.023 at dx = 0.01;
#   it grows to -0.050 ... -0.052 at 0.005 (reported above).
# TOL_A 1 %: the start-up of the smeared faces; measured <= 0.21 %. It separates the exact
#   answer from (p_L - p_R) / (rho_s L), 3.1 % higher.
TOL_T, TOL_R, TOL_A = 0.03, 0.06, 0.01

print(f"info transmission: Z_g {Z_G:.5f}, Z_s {Z_S:.5f}, code impedance Z_s / F0 {Z_EFF:.5f} "
      f"(ratio {Z_EFF / Z_G:.4f}); exact p* {P_STAR:.6f}: T {T_EX:.5f}, R {R_EX:.5f}; acoustic "
      f"T {T_AC:.5f}, R {R_AC:.5f}; impact at t = {T_HIT:.4f}")
print(f"info slab: face pressures {P_IL:.6f}, {P_IR:.6f}; a exact {A_EX:.6f}, simple "
      f"{A_SIMPLE:.6f}")
for scheme, method in PAIRS:
    transmission(scheme, method)
    slab(scheme, method)

sys.exit(check.finish())
