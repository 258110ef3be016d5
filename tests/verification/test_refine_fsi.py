"""A gas beside a solid on a static refinement hierarchy (docs/refinement.md, "A gas beside a
solid"): the coupling scheme (velocity, monolithic, bs32 or usl) on every level's active nodes.

The scene (tests/tools/refine_scenes.py, fsi_case): a quasi-1-D strip periodic along y, slip
walls at the x ends; gas rho 1, p 1 (Z_g = c_g = 1.1832) on [0, 1] and [2.6, 3]; between them
a linear_elastic slab prestressed to the gas's pressure (initial_pressure = 1), rho_s = 0.25,
E = 22.4, nu = 0 (c_s = 8 c_g, Z_s = 2 Z_g); a level-1 band over x in [0.9, 2.7] (across the
periodic axis) holds the whole slab and gas on either side of it. Level 0 at dx = 0.02; the
uniform twins at 0.02 (coarse) and 0.01 (fine, the band's spacing).

Parts (one ctest each):
rest   Nothing but the scene (gas and slab at rest, the slab's stress balancing the gas's
       pressure), refined, to t = 0.2: every particle stays at rest to roundoff, as on the
       uniform grid; and coupling.csv's interface force balances.
pulse  A right-going acoustic pulse in the left column (p' = 1e-2 exp(-((x - 0.45) / 0.05)^2
       / 2)) strikes the slab inside the band; the slab is 2.8 long here (FSI_PULSE_L_S) so
       that its far face's echo comes back after the incident pulse's tail. Reflected
       amplitude: the integral of the gas's p - 1 over x in [0.2, 0.82] at t = 0.85 (the
       reflected pulse alone, on level 0 again) over the incident's; transmitted: Z_eff times
       the displacement of a slab particle next to the interface (probes.csv) from t = 0.25 to
       0.85 (the time integral of its grid velocity, before the echo) over the incident
       pressure's time integral. Against the acoustic impedance solution
       R = (Z - Z_g) / (Z + Z_g), T = 2 Z / (Z + Z_g) with the prestressed slab's impedance
       Z = Z_s / sqrt(F0) (the code's nominal stress M (F - 1) / F at F0 = M / (M + p), reference
       density rho_s F0) and against the twins; the interface momentum balance of coupling.csv
       on every step; mass and total energy drift against the twins'.
rest_usl, pulse_usl The rest and pulse parts under time.method = usl (FLIP), with their bounds.
traction The rest and pulse parts' refined runs under coupling.scheme = traction (the gas
       held to the solid's normal velocity, slip): in the quasi-1-D strip the normal is the whole
       velocity, so they give velocity's figures (at rest to roundoff; T, R within the same bounds;
       the balance).
restart The pulse scene refined to t = 0.4 (the pulse on the interface), restarted from its
       checkpoint at t = 0.2: bit for bit the run straight through, both phases.
regrid Regrids beside the solid (fluid.pressure = grid, usl, density criterion 1e-3 every 5
       steps; the slab flagged with its margin, mpm_refine.c): at rest to t = 0.2 to roundoff;
       the pulse part's scene against the impedance solution with its bounds, the balance,
       mass and energy, the region following the pulse (the level-1 particle count changes)
       and the slab on the finest level throughout (the run stops otherwise); a restart at
       t = 0.2 of the pulse to t = 0.4 bit for bit.
bar    The main job's scene on two levels, the box around the bar touching the floor, to 1 ms
       (the light-node rule, refill, regularisation, the light merges and the neighbourhood
       step on the levels, the case's own settings): it runs, the interface balanced.
input  Every refusal of a gas beside a solid on a hierarchy: exit 2, one line naming
       case.ini:LINE and the key.
Able to fail (measured while building it): with the coupling on level 0 only (the code before
this change, the refusal lifted) the rest part's kinetic energy reaches 1.7e-3 J by t = 0.05
(the gas runs into the slab; 1.7e-2 J by t = 0.2) and the pulse part sees no interface force
and a transmitted velocity 24 times the impedance solution's; the traction part alike (|v| 2.3 at
rest, T 31.9).
The transmitted measure before 2026-12-03 (the velocity's integral over [0.25, 0.62], a slab 1.6
long) cut off the trailing lobe that the pulse (sigma = 2.5 level-0 cells) grows while it crosses
level 0, and read one particle's FLIP velocity: T +7.0 % refined, +9.3 % coarse under bs32, and
under usl a coarse +2.3 % that its neighbours' velocities (+9.6 % .. +13.6 %) and its own
displacement (+7.9 %) contradict. A band that holds the pulse from the start (lo = 0.1) gave
-0.9 % then, the fine twin's -0.8 %.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import refine_scenes as rs  # noqa: E402

PART = sys.argv[1] if len(sys.argv) > 1 else "pulse"
check = mt.Checks(f"test_refine_fsi_{PART}")

H = 3 * rs.FSI_DX
C_G = Z_G = np.sqrt(1.4)
M_S = rs.FSI_E  # plane strain with nu = 0
Z_S = np.sqrt(rs.FSI_RHO_S * M_S)
F0 = M_S / (M_S + 1.0)
Z_EFF = Z_S / np.sqrt(F0)
T_AC = 2 * Z_EFF / (Z_EFF + Z_G)
R_AC = (Z_EFF - Z_G) / (Z_EFF + Z_G)
INCIDENT = rs.FSI_A * rs.FSI_SIGMA * np.sqrt(2 * np.pi)  # integral of p' dx


def run(name, text):
    return mt.run_text(name, text)


csv = mt.csv_rows


def balance(out):
    """The largest |F_solid + F_fluid| of coupling.csv over the largest |F_solid|, that
    largest |F_solid|, and the largest |F_solid + F_fluid| itself, N."""
    c = csv(out, "coupling.csv")
    worst = max(np.abs(c[f"F{a}_solid"] + c[f"F{a}_fluid"]).max() for a in "xy")
    fmax = np.abs(c["Fx_solid"]).max()
    return worst / max(fmax, 1e-300), fmax, worst


def traction(text):
    return text.replace("scheme = velocity", "scheme = traction")


def usl(text):
    return text.replace("[time]\n", "[time]\nmethod = usl\n")


def plain(text):
    return text


def part_rest(scheme=lambda text: text):
    out = run("refine_fsi_rest", scheme(rs.fsi_case(0.2, rs.FSI_BAND, interval=0.05)))
    vmax = 0.0
    for _, path in mt.snapshots(out):
        for phase in ("fluid", "solid"):
            vmax = max(vmax, float(np.abs(mt.particles(path, phase)["v"]).max()))
    d = csv(out, "diagnostics.csv")
    rel, fmax, worst = balance(out)
    print(f"info {mt.cost(out)}; largest |v| {vmax:.1e}, kinetic energy {d['kinetic'].max():.1e}"
          f", largest interface force {fmax:.1e}")
    # Measured 0 to 1e-16 (roundoff of the sums; the uniform twin alike): the slab's stress
    # balances the gas's pressure node by node on the band's lattice, where both meet. With the
    # coupling on level 0 only the gas runs into the slab at 0.1 c.
    check(vmax <= 1e-12, f"gas and slab at rest across the band: largest |v| {vmax:.1e} <= 1e-12"
          f" (c_g = 1.18)")
    check(d["kinetic"].max() <= 1e-24, f"kinetic energy {d['kinetic'].max():.1e} <= 1e-24 J "
          f"(total {d['total'][0]:.3g} J)")
    # At rest every interface force is roundoff (under the ERK pairs the relaxation of the
    # phases' own velocities adds its own, about 1e-15 N), so the balance is measured against
    # the gas's load on the slab's face, p0 H = 0.06 N (H the strip's 3 cells of 0.02).
    check(worst <= 1e-12 * 0.06, f"interface force balance {worst:.1e} N, {rel:.1e} of the "
          f"largest force {fmax:.1e} N (at most 1e-12 of p0 H = 0.06 N)")


# The transmitted wave's window at the probe: from before the pulse's front (t = 0.338) to
# before the echo of the slab's far face (its front, 3 sigma ahead, reaches the probe at
# 0.338 + (2 FSI_PULSE_L_S - 0.04) / c_s = 0.925); the trailing lobe the pulse grows on level 0
# has passed by 0.8 (window ends 0.8 and 0.85 agree to 0.4 %, measured).
WINDOW = (0.25, 0.85)


def transmitted(out):
    """Z_eff times the probe's displacement over WINDOW (its velocity's time integral, the
    grid's velocity under usl, where a particle's FLIP velocity carries noise the grid does not
    see), over the incident pressure's time integral at a point, I / c_g."""
    q = csv(out, "probes.csv")
    u = np.interp(WINDOW, q["t"], q["slab_ux"])
    return Z_EFF * (u[1] - u[0]) / (INCIDENT / C_G)


def reflected(out):
    """The integral of the gas's p - 1 over x in [0.2, 0.82] at the last snapshot (bin means,
    62 bins), over the incident's."""
    g = mt.particles(mt.snapshots(out)[-1][1], "fluid")
    x, p = g["x"][:, 0], g["p"][:, 0]
    a, b, nb = 0.2, 0.82, 62
    sel = (x > a) & (x < b)
    k = ((x[sel] - a) / (b - a) * nb).astype(int)
    mean = np.bincount(k, p[sel] - 1, nb) / np.bincount(k, None, nb)
    return mean.sum() * (b - a) / nb / INCIDENT


def pulse_case(refine, dx=rs.FSI_DX):
    return rs.fsi_case(WINDOW[1], refine, dx=dx, pulse=rs.FSI_PULSE, extra=rs.FSI_PROBE,
                       slab=rs.FSI_PULSE_L_S)


def part_pulse(method=plain):
    runs = {"refined": run("refine_fsi_pulse", method(pulse_case(rs.FSI_BAND))),
            "coarse": run("refine_fsi_coarse", method(pulse_case(""))),
            "fine": run("refine_fsi_fine", method(pulse_case("", dx=rs.FSI_DX / 2)))}
    T, R, drift, mass = {}, {}, {}, {}
    for label, out in runs.items():
        T[label], R[label] = transmitted(out), reflected(out)
        d = csv(out, "diagnostics.csv")
        drift[label] = abs(d["total"] - d["total"][0]).max() / d["total"][0]
        mass[label] = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
        print(f"info {label}: {mt.cost(out)}; T {T[label]:.4f} ({100 * (T[label] / T_AC - 1):+.2f}"
              f" %), R {R[label]:.4f} ({R[label] - R_AC:+.4f}); total energy drift "
              f"{drift[label]:.2e}, mass drift {mass[label]:.1e}")
    print(f"info impedance solution: Z_s {Z_S:.4f}, prestressed {Z_EFF:.4f}, Z_g {Z_G:.4f}: "
          f"T {T_AC:.4f}, R {R_AC:.4f}")
    t, r = T["refined"], R["refined"]
    # Measured (bs32; usl): T -0.43 %, -0.44 % refined, -0.37 %, -0.39 % coarse, -0.63 %,
    # -0.65 % fine; R -0.001, +0.000 refined, +0.005, +0.006 coarse, +0.007, +0.007 fine. The
    # incident pulse crosses level 0 before the band, where it grows a trailing lobe that the
    # window holds; the interface spreads its coupling over the shared nodes (3 cells). The
    # refined T lies between its twins, its R 0.006 below both (the reflected pulse leaves the
    # band for level 0 as the coarse twin's does; not explained). Bounds:
    # T within 2 % (three times the fine twin's error; the old window's +7 % fails it), R within
    # 0.02, and within the twins' range with 1 % of T and 0.01 of R to spare.
    check(abs(t / T_AC - 1) <= 0.02, f"transmitted {t:.4f} against the impedance solution "
          f"{T_AC:.4f}: {100 * (t / T_AC - 1):+.2f} % (<= 2 %)")
    check(abs(r - R_AC) <= 0.02, f"reflected {r:.4f} against the impedance solution {R_AC:.4f}:"
          f" {r - R_AC:+.4f} (<= 0.02)")
    lo_t, hi_t = sorted((T["coarse"], T["fine"]))
    lo_r, hi_r = sorted((R["coarse"], R["fine"]))
    check(lo_t - 0.01 * T_AC <= t <= hi_t + 0.01 * T_AC and lo_r - 0.01 <= r <= hi_r + 0.01,
          f"refined between its twins: T {t:.4f} in [{lo_t:.4f}, {hi_t:.4f}], R {r:.4f} in "
          f"[{lo_r:.4f}, {hi_r:.4f}] (1 % of T, 0.01 of R to spare)")
    out = runs["refined"]
    rel, fmax, _ = balance(out)
    # Measured 2.9e-14: the exchange is per node, each level's (roundoff of the sums).
    check(rel <= 1e-12, f"interface momentum balance of coupling.csv: |F_solid + F_fluid| "
          f"{rel:.1e} of the largest force {fmax:.1e} N (<= 1e-12)")
    # Mass: constant particle masses (measured 3e-15). Energy: bs32 at its default tolerance
    # (or usl) and the velocity scheme's inelastic exchange lose 7.2e-6 refined, 7.2e-6 coarse,
    # 6.9e-6 fine (usl 7.2e-6, 7.2e-6, 7.1e-6); 2e-5 fails on an interface that creates or
    # loses a tenth of the pulse's energy (its energy is 2e-5 of the total).
    check(mass["refined"] <= 1e-12, f"mass drift {mass['refined']:.1e} <= 1e-12")
    check(drift["refined"] <= 2e-5, f"total energy drift {drift['refined']:.2e} <= 2e-5 (coarse "
          f"twin {drift['coarse']:.2e}, fine {drift['fine']:.2e})")


def part_traction():
    part_rest(traction)
    out = run("refine_fsi_traction", traction(pulse_case(rs.FSI_BAND)))
    t, r = transmitted(out), reflected(out)
    rel, fmax, _ = balance(out)
    print(f"info traction: {mt.cost(out)}; T {t:.4f}, R {r:.4f}, balance {rel:.1e}")
    # Measured T 1.3372, R 0.3420 (velocity's to 4 digits), balance 2.9e-14; the bounds of the
    # pulse part.
    check(abs(t / T_AC - 1) <= 0.02 and abs(r - R_AC) <= 0.02, f"traction: transmitted {t:.4f} "
          f"({100 * (t / T_AC - 1):+.2f} %, <= 2 %), reflected {r:.4f} ({r - R_AC:+.4f}, <= 0.02)")
    check(rel <= 1e-12, f"traction: interface momentum balance {rel:.1e} (<= 1e-12)")


def part_restart(name="refine_fsi_restart", refine=rs.FSI_BAND, method=plain, label=""):
    """As mt.restart_difference, both phases from one pair of runs."""
    out, t_end = mt.outdir(name), 0.4
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(method(rs.fsi_case(t_end, refine, pulse=rs.FSI_PULSE)))
    full, rest = (os.path.join(out, d) for d in ("full", "restarted"))
    common = ["run.progress=false"]
    mt.run(["run", path, f"output.dir={full}", f"output.checkpoint_interval={t_end / 2}"] + common)
    mt.run(["restart", os.path.join(full, "checkpoint_000001.h5"), f"output.dir={rest}"] + common)
    for phase in ("solid", "fluid"):
        a, b = (mt.particles(mt.snapshots(d)[-1][1], phase) for d in (full, rest))
        same = np.array_equal(a["id"], b["id"])
        worst = mt.worst_difference(a, b)[0] if same else float("inf")
        check(same and worst == 0.0, f"{label}{phase}: restarted at t = {t_end / 2:g}: worst "
              f"difference {worst:.1e} (want 0)")


REGRID = "[refine]\nlevels = 2\ncriterion = density\nthreshold = 0.001\nevery = 5\n"


def regridded(text):
    return usl(text.replace("gamma = 1.4", "gamma = 1.4\npressure = grid"))


def part_regrid():
    out = run("refine_fsi_regrid_rest", regridded(rs.fsi_case(0.2, REGRID, interval=0.05)))
    vmax = max(float(np.abs(mt.particles(path, phase)["v"]).max())
               for _, path in mt.snapshots(out) for phase in ("fluid", "solid"))
    # Measured ~1e-14 (the static band's roundoff): the regions are the slab's margin alone.
    check(vmax <= 1e-12, f"regridded, at rest: largest |v| {vmax:.1e} <= 1e-12 (c_g = 1.18)")
    out = run("refine_fsi_regrid", regridded(pulse_case(REGRID)))
    t, r = transmitted(out), reflected(out)
    rel, fmax, _ = balance(out)
    d = csv(out, "diagnostics.csv")
    drift = abs(d["total"] - d["total"][0]).max() / d["total"][0]
    mass = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
    counts = sorted(set(d["particles_l1"].astype(int)))
    print(f"info regridded: {mt.cost(out)}; T {t:.4f} ({100 * (t / T_AC - 1):+.2f} %), R {r:.4f} "
          f"({r - R_AC:+.4f}); level 1 holds {counts[0]} to {counts[-1]} particles")
    # Measured: T -0.31 %, R -0.0024 (the fine grid-pressure twin -0.34 %, +0.0028; the static
    # band with the grid pressure +0.94 %, +0.0212: the pulse crosses level 0 there); the pulse
    # part's bounds.
    check(abs(t / T_AC - 1) <= 0.02 and abs(r - R_AC) <= 0.02, f"regridded: transmitted "
          f"{t:.4f} ({100 * (t / T_AC - 1):+.2f} %, <= 2 %), reflected {r:.4f} ({r - R_AC:+.4f}, "
          f"<= 0.02)")
    check(rel <= 1e-12, f"regridded: interface momentum balance {rel:.1e} (<= 1e-12)")
    check(mass <= 1e-12 and drift <= 2e-5, f"regridded: mass drift {mass:.1e} (<= 1e-12), total "
          f"energy drift {drift:.2e} (<= 2e-5, the pulse part's bound)")
    check(len(counts) > 2, f"regridded: the region follows the pulse ({len(counts)} level-1 "
          f"particle counts over the run; want more than 2)")
    part_restart("refine_fsi_regrid_restart", REGRID, regridded, "regridded, ")


BAR_LEVELS = ["time.t_end=0.001", "grid.dx=0.006", "fluid.pressure=grid",
              "refine.levels=2", "refine.box.level=1",
              "refine.box.lo=0.072 0", "refine.box.hi=0.156 0.078"]


def part_bar():
    """The main job's scene on two levels (cases/supersonic_bar.ini, level 0 at 6 mm, a level-1
    box around the bar touching the floor, so the bar's floor wall and its clamp act on level
    1): with the case's gas settings (refill, regularisation, the light merges, the
    neighbourhood step and the light-node rule, fluid.light_node_mass = 0.05, each level's nodes
    against the mean at its spacing), it runs to 1 ms with the interface's momentum balanced to
    roundoff. The same run without the light-node rule is printed as information: with the
    refill and the neighbourhood step off it stopped at 0.08 ms (a gas particle's e <= 0 beside
    the bar); with them (since 2026-12-06) it completes."""
    with open(os.path.join(mt.SOURCE, "cases", "supersonic_bar.ini")) as f:
        text = f.read()
    out = mt.run_text("refine_fsi_bar", text, BAR_LEVELS)
    print(f"info refined: {mt.cost(out)}")
    worst, peak, _ = balance(out)
    tip = csv(out, "probes.csv")
    print(f"info tip displacement at {tip['t'][-1] * 1e3:.2f} ms: {tip['tip_ux'][-1] * 1e3:.2f} mm")
    check(abs(tip["t"][-1] - 1e-3) <= 1e-9, f"bar on 2 levels: reached t = {tip['t'][-1]:.3g} s "
          f"(want 1e-3)")
    snaps = mt.snapshots(out)
    x0, x1 = (mt.particles(snaps[k][1], "solid")["x"] for k in (0, -1))  # (sorted by id)
    base = x0[:, 1] < x0[:, 1].min() + 1e-3  # the bar's lowest particle row, on the floor
    moved = np.abs(x1 - x0)[base].max()
    # The clamp holds the bar's root on level 1 (the floor's pad nodes mirrored with every
    # component negated): its lowest row moves by a small part of the tip's 3.2 mm (measured
    # 0.045 mm, 1.4 %); without the clamp on level 1 the run blew up at 0.49 ms (with the
    # case's expansion settings off).
    check(moved <= 0.1 * abs(tip["tip_ux"][-1]), f"bar on 2 levels: its lowest particle row "
          f"moved {moved * 1e3:.3f} mm, <= 10 % of the tip's {tip['tip_ux'][-1] * 1e3:.2f} mm")
    # The velocity scheme's balance is exact node by node (measured 1e-14 on the uniform grid).
    check(worst <= 1e-12, f"bar on 2 levels: interface momentum balance {worst:.1e} <= 1e-12 of "
          f"the largest interface force ({peak:.3g} N)")
    bare = mt.outdir("refine_fsi_bar_bare")
    path = os.path.join(bare, "case.ini")
    with open(path, "w") as f:
        f.write(text)
    p = mt.run(["run", path, f"output.dir={bare}/run", "run.progress=false",
                "fluid.light_node_mass=0"] + BAR_LEVELS, check=False)
    last = [line for line in (p.stdout + p.stderr).splitlines() if line.startswith(("done",
                                                                                    "error"))]
    print(f"info without the light-node rule: exit {p.returncode}; {last[0] if last else ''}")


def part_input():
    text = rs.fsi_case(0.1, rs.FSI_BAND)
    band = "lo = 0.9 0\nhi = 2.7 0.06"
    cases = [
        ("staggered", text.replace("scheme = velocity", "scheme = velocity\ntime = staggered"),
         "coupling.time", "time = staggered", "not carried"),
        ("multirate", text.replace("scheme = velocity", "scheme = velocity\ntime = multirate"),
         "coupling.time", "time = multirate", "not carried"),
        ("slab off the finest level", text.replace(band, "lo = 0.9 0\nhi = 2.5 0.06"),
         "solid.slab.geometry", "geometry = slab", "finest"),
        ("box not across the periodic axis", text.replace(band, "lo = 0.9 0.01\nhi = 2.7 0.05"),
         "refine.band.lo", "lo = 0.9 0.01", "periodic axis y"),
        ("contact", usl(text.replace("scheme = velocity", "scheme = contact")),
         "coupling.scheme", "scheme = contact", "not carried"),
        ("sharp", usl(text.replace("scheme = velocity", "scheme = sharp")),
         "coupling.scheme", "scheme = sharp", "not carried"),
        ("MUSL", text.replace("t_end = 0.1", "t_end = 0.1\nmethod = musl"),
         "time.method", "method = musl", "not carried"),
        ("two bodies", text.replace("hi = 2.6 0.06", "hi = 1.8 0.06") +
         "\n[geometry.slab2]\ntype = box\nlo = 1.8 0\nhi = 2.6 0.06\n\n"
         "[solid.slab2]\ngeometry = slab2\nmaterial = linear_elastic\ndensity = 0.25\nE = 22.4\n"
         "nu = 0\n", "refine.levels", "levels = 2", "bodies"),
    ]
    for name, t, key, start, words in cases:
        mt.expect_input_error(check, name, t, key, mt.line_starting(t, start), words)


if PART == "rest":
    part_rest()
elif PART == "pulse":
    part_pulse()
elif PART == "rest_usl":
    part_rest(usl)
elif PART == "pulse_usl":
    part_pulse(usl)
elif PART == "traction":
    part_traction()
elif PART == "restart":
    part_restart()
elif PART == "regrid":
    part_regrid()
elif PART == "bar":
    part_bar()
elif PART == "input":
    part_input()
else:
    raise SystemExit(f"unknown part {PART}")
sys.exit(check.finish())
