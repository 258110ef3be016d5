"""The gas on a static refinement hierarchy (refine.levels = 2; docs/refinement.md).

A 2-D strip, periodic along x, slip walls along y, level 0 at dx = 0.05; one level-1 box (spacing
0.025) in its middle, three cells clear of the walls. Default gas settings (bs32, strain rate
current; fluid.pressure = auto, so the refined runs integrate the pressure on the grid and their
particles split and merge as they cross the box's edge). Each run is compared with its uniform twins: the same strip without refinement at
dx = 0.05 (coarse) and at dx = 0.025 (fine). The argument picks the part (one ctest each):

uniform  A uniform gas (rho 1, p 1, u = 0.5 c along x) crossing the box about three times its
         width: the largest deviation of the particles' density, pressure and velocity from the
         initial state (relative), and the conservation of mass, momentum and total energy in
         diagnostics.csv (part c of the brief); at every snapshot no particle of another
         level's size beyond one coarse particle spacing of the box's faces (the lag split and
         merge leave at a face the stream crosses).
pulse    A right-running acoustic pulse (amplitude 1e-3, c = 1, gaussian of width 0.2 = 4 coarse
         cells) crossing the box: the energy of the left-running (reflected) component against
         that of the pulse, after the pulse has left the box, from the particle p and u binned
         along x; and conservation as above.
uniform3d The uniform stream in 3-D (x and z periodic, slip walls along y; a level-1 box in the
         middle) to t = 0.45 (the box crossed once and a half): the same deviation, level and
         conservation checks; the same source as 2-D.
dynamic  A nonlinear pulse (amplitude 5e-2) refined dynamically (refine.criterion = density,
         threshold 4e-3, a regrid every 10 steps) to t = 1.2: the refined region follows the pulse
         (the densest particle of the rows the region can reach, 4 cells from the walls, is a
         level-1 particle at the start and at the end, 1.1 m further on), and mass, momentum and
         energy are conserved across every regrid; its density along the box's rows against the
         uniform twins' is printed.
compression The same pulse regridded by the compression criterion (threshold 3e-3: the pulse's
         front drops the velocity by 1e-2 of c per cell at the start, 4e-3 at t = 1.2): at every
         snapshot the particles of the band's rows within a cell of the steepest velocity drop
         are on level 1; conservation as above (~3 s).
vorticity A shear layer (u = 0.3 tanh((y - 0.3) / 0.05), the velocity jumping by up to 0.23 c
         between neighbouring cells) regridded by the vorticity criterion to t = 0.3: with
         threshold 0.05 the particles within half a cell of the layer's middle are on level 1,
         with threshold 0.5 (above every jump) no particle is refined (~3 s).
starvation An expanding gas (refine_scenes.EXPANSION: a square periodic on every face whose
         centre expands) regridded by starvation (min_particles 2.5), by compression (0.05)
         alone and by both: with starvation listed the 9 x 9 cells around the centre keep at
         least 2 particles at every snapshot, without it they empty; the combined run refines
         at least what either does alone; starvation's region stays in the centre; a disc of
         gas at rest in empty space is not refined; a restart of the combined run is bit for
         bit; mass, momentum and energy as for dynamic (~8 s). Able to fail: with the
         starvation flags switched off the centre empties (4 checks fail); without the
         neighbour rule the disc's edge and the empty space are refined.
restart  The same dynamic run to t = 0.4, restarted from its checkpoint at t = 0.2 (between
         regrids), and again regridded every step: each ends bit for bit as the run straight
         through (short: it also runs under the sanitizers).
ranks    The grid pressure without refinement on 1 and 2 ranks (the pulse of `dynamic` to
         t = 0.5, no [refine], fixed bs32 steps): the same particles, fields within 1e-12 (the
         level-0 halos of its nodal pressure, forces and rates; the sums only change order).
periodic Levels across periodic faces (the strip periodic along x and y): a uniform gas moving
         diagonally (u = (0.5, 0.3) c) through a level-1 band x in [0.3, 0.9] spanning the
         period along y, a level-2 band x in [0.5, 0.7] inside it, and a level-1 box across
         the x faces (x in [-0.15, 0.1]), to t = 0.6: it stays uniform to roundoff, particles
         sit on every level within half a cell of the y faces and of the x faces, and mass,
         momentum and energy are conserved (~5 s).
wrap     Regrids on a periodic strip: the nonlinear pulse of `dynamic` on a strip 3 cells high,
         periodic along x and y (quasi-1-D, as the shock-tube cases), starting at x = 2.6 and
         running through the x faces, refined to 3 levels by the density criterion every 10
         steps at a fixed bs32 step: levels 1 and 2 hold every particle row of the period along
         y at every snapshot (a level-2 region once lost the rows of the half span below y = 0),
         the refined region crosses the x faces
         when the pulse does, and mass, momentum and energy are conserved across every regrid;
         a restart at t = 0.25 (the region across the x faces) ends bit for bit as the run
         through, to t = 0.5 (~5 s).
input    Every refusal: exit 2, one line naming case.ini:LINE and the key (part d).
identity refine.levels = 1 gives the same output as no [refine] section, bit for bit (part e);
         a refined run restarted from its checkpoint ends bit for bit as the run through.
output   The refined output (issue 51 item 6): a three-level run with grid fields checked file by
         file: /levels/<l> of every snapshot (lattice, spacing, origin on the level's node
         lattice, masks, m and v), the particle field level against the level of each position
         computed here from the boxes, and against the own mask; diagnostics.csv's per-level
         counts (sum and the snapshot's); timers.csv's restrict and prolong; the XDMF index of
         every level; and, when pvpython is on the PATH, ParaView's three XDMF readers opening
         each level as its own block. An unrefined twin keeps the old columns and layout.
Able to fail: with the restriction switched off (coupler/mpm_cycle.c) the uniform part's run
blows up at t = 0.11.
A second argument sets fluid.ppc of the uniform and pulse runs (2 by default; 4 in the long
tests). The figures and tolerances are stated at each check and in docs/refinement.md.
"""
import os
import shutil
import subprocess
import sys
import time

READERS = ("XDMFReader", "Xdmf3ReaderS", "Xdmf3ReaderT")


def paraview_blocks(index):
    """Under pvpython: one line per reader and block at the last time (name points arrays, and
    the sum of the mask own)."""
    from paraview import servermanager as sm
    from paraview import simple
    for name in READERS:
        if name == "XDMFReader":
            reader = simple.XDMFReader(FileNames=[index])
        else:
            reader = getattr(simple, name)(FileName=[index])
        t = list(reader.TimestepValues)[-1]
        reader.UpdatePipeline(t)
        d = sm.Fetch(reader)
        it = d.NewIterator()
        it.UnRegister(None)
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            o, pd = it.GetCurrentDataObject(), it.GetCurrentDataObject().GetPointData()
            arrays = sorted(pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays()))
            own = pd.GetArray("own")
            total = sum(own.GetValue(k) for k in range(own.GetNumberOfTuples())) if own else -1
            print(f"PV {name} {o.GetNumberOfPoints()} {','.join(arrays)} {total}")
            it.GoToNextItem()
        simple.Delete(reader)


if len(sys.argv) == 3 and sys.argv[1] == "--in-paraview":
    paraview_blocks(sys.argv[2])
    sys.exit(0)

import h5py  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402
import refine_scenes as rs  # noqa: E402
from refine_scenes import (BOX, BOX_3D, C0, CASE_3D, DYNAMIC, EXPAND_V, EXPANSION,  # noqa: E402
                           PULSE_5, STARVE, case_text)

PART = sys.argv[1] if len(sys.argv) > 1 else "uniform"
PPC = int(sys.argv[2]) if len(sys.argv) > 2 else 2  # fluid.ppc of the uniform and pulse runs
check = mt.Checks(f"test_refine_gas_{PART}")
FLUID = f"[fluid]\nppc = {PPC}\n"
def run(name, text, ranks=1):
    out = mt.outdir(name)
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(text)
    t0 = time.time()
    mt.run(["run", path, f"output.dir={out}/run", "run.progress=false"], ranks)
    return os.path.join(out, "run"), time.time() - t0


def final(out):
    return mt.particles(mt.snapshots(out)[-1][1], "fluid")


def diagnostics(out):
    return np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)


def drifts(out):
    """Relative drift of mass, momentum (against sum m |v| at the start) and total energy."""
    d = diagnostics(out)
    scale = max(abs(d["px"][0]) + abs(d["py"][0]), 1e-300)
    p = max(abs(d["px"] - d["px"][0]).max(), abs(d["py"] - d["py"][0]).max()) / scale
    return (abs(d["mass"] - d["mass"][0]).max() / d["mass"][0], p,
            abs(d["total"] - d["total"][0]).max() / d["total"][0], int(d["step"][-1]))


def twins(name, length, t_end, gas, x0, x1, extra=""):
    """The refined run and its coarse and fine uniform twins: {label: (out, wall s)}."""
    extra += FLUID
    return {"refined": run(name + "_refined", case_text(length, t_end, gas,
                                                        BOX.format(x0=x0, x1=x1), extra=extra)),
            "coarse": run(name + "_coarse", case_text(length, t_end, gas, "", extra=extra)),
            "fine": run(name + "_fine", case_text(length, t_end, gas, "", 0.025, extra=extra))}


def report_cost(runs):
    for label, (out, wall) in runs.items():
        print(f"info {label}: {mt.cost(out)}; {wall:.2f} s wall for the whole command")


def conservation(runs, tol_mass, tol_p, tol_e):
    for label, (out, _) in runs.items():
        dm, dp, de, steps = drifts(out)
        print(f"info {label}: {steps} steps, mass drift {dm:.2e}, momentum {dp:.2e} (of sum m|v|),"
              f" total energy {de:.2e}")
        if label != "refined":
            continue
        check(dm <= tol_mass, f"refined: mass drift {dm:.2e} <= {tol_mass:g}")
        check(dp <= tol_p, f"refined: momentum drift {dp:.2e} <= {tol_p:g} of sum m|v|")
        check(de <= tol_e, f"refined: total energy drift {de:.2e} <= {tol_e:g}")




def part_uniform3d():
    u0 = 0.5 * C0
    runs = {"refined": run("refine_uniform3d", CASE_3D.format(u0=u0, refine=BOX_3D, dx=0.075)),
            "coarse": run("refine_uniform3d_coarse", CASE_3D.format(u0=u0, refine="", dx=0.075))}
    report_cost(runs)
    p = final(runs["refined"][0])
    got = max(np.abs(p["rho"] - 1).max(), np.abs(p["p"] - 1).max(),
              np.abs(p["v"][:, 0] - u0).max() / u0, np.abs(p["v"][:, 1:]).max() / u0)
    counts = set(diagnostics(runs["refined"][0])["particles"].astype(int))
    # Roundoff, as in 2-D (measured 3e-15); a disturbance of the box's corners and edges would be
    # O(1e-2) by t = 0.45.
    check(got <= 1e-10 and len(counts) > 1, f"3-D uniform gas across the box: deviation "
          f"{got:.2e} <= 1e-10 at t = {p['time']:g}; {len(counts)} distinct particle counts "
          f"(splits and merges)")
    conservation(runs, 1e-12, 1e-12, 1e-10)  # energy measured 7e-15: as in 2-D


def part_uniform():
    u0 = 0.5 * C0
    gas = f"density = 1\npressure = 1\nvelocity = {u0!r} 0"
    runs = twins("refine_uniform", 2, 1.4, gas, 0.8, 1.2)
    report_cost(runs)
    dev = {}
    for label, (out, _) in runs.items():
        p = final(out)
        n0 = len(mt.particles(mt.snapshots(out)[0][1], "fluid")["id"])
        dev[label] = max(np.abs(p["rho"] - 1).max(), np.abs(p["p"] - 1).max(),
                         np.abs(p["v"][:, 0] - u0).max() / u0, np.abs(p["v"][:, 1]).max() / u0)
        print(f"info {label}: {n0} particles, largest deviation from the uniform state at "
              f"t = {p['time']:g}: {dev[label]:.2e} (relative)")
    return runs, dev


def reflected_fraction(out, rest, length):
    """refine_scenes.reflected_energy of the run out's last snapshot (rest: the run at rest)."""
    return rs.reflected_energy(final(out), final(rest) if rest else None, length)


def part_pulse():
    gas = rs.pulse_gas()
    runs = twins("refine_pulse", 3, 2.4, gas, 1.6, 2.4)
    rest, _ = run("refine_rest", case_text(3, 2.4, "density = 1\npressure = 0.714285714285714",
                                           BOX.format(x0=1.6, x1=2.4),
                                           extra=FLUID))
    report_cost(runs)
    r = final(rest)
    print(f"info refined, gas at rest: largest |p - p0| / p0 {np.abs(r['p'] * 1.4 - 1).max():.2e},"
          f" |v| / c {np.abs(r['v']).max():.2e} at t = {r['time']:g}")
    frac = {}
    for label, (out, _) in runs.items():
        frac[label] = reflected_fraction(out, rest if label == "refined" else None, 3)
        print(f"info {label}: reflected energy fraction {frac[label]:.3e}")
    return runs, frac




def row_density(out, nbins=60):
    """The gas density binned along x over the rows 0.2 < y < 0.4 (inside the refined band)."""
    p = final(out)
    x, y = p["x"][:, 0], p["x"][:, 1]
    sel = (y > 0.2) & (y < 0.4)
    k = np.minimum((x[sel] / 3 * nbins).astype(int), nbins - 1)
    return (np.bincount(k, p["m"].ravel()[sel], nbins) /
            np.bincount(k, (p["m"] / p["rho"]).ravel()[sel], nbins))


def part_dynamic():
    runs = {"refined": run("refine_dynamic", case_text(3, 1.2, PULSE_5, DYNAMIC)),
            "coarse": run("refine_dynamic_coarse", case_text(3, 1.2, PULSE_5, "")),
            "fine": run("refine_dynamic_fine", case_text(3, 1.2, PULSE_5, "", 0.025))}
    report_cost(runs)
    out = runs["refined"][0]
    size0 = (0.05 / 2) ** 2
    for t, f in (mt.snapshots(out)[0], mt.snapshots(out)[-1]):
        p = mt.particles(f, "fluid")
        band = np.flatnonzero((p["x"][:, 1] > 0.2) & (p["x"][:, 1] < 0.4))
        k = band[int(np.argmax(p["rho"][band, 0]))]
        level = int(np.rint(np.log2(size0 * p["rho"][k, 0] / p["m"][k, 0]) / 2))
        check(level == 1, f"t = {p['time']:g}: the densest particle of the rows 0.2 < y < 0.4 "
              f"(x = {p['x'][k, 0]:.3f}) is a level-{level} particle (want 1: the region follows "
              f"the pulse; the region keeps 4 level-0 cells from the walls)")
    d = diagnostics(out)
    counts = set(d["particles"].astype(int))
    check(len(counts) > 2, f"{len(counts)} distinct particle counts over the run (regrids, splits "
          f"and merges; want more than 2)")
    # After the last step no particle is coarser than its level (splits repeat), and only those
    # waiting for the rest of a merge group (a slot holding fewer than 2^dim of them) are finer.
    p = final(out)
    size = np.rint(np.log2(size0 * p["rho"].ravel() / p["m"].ravel()) / 2)
    level = p["level"].ravel()
    coarser, finer = int(np.sum(size < level)), int(np.sum(size > level))
    check(coarser == 0 and finer <= 0.01 * len(size), f"t = 1.2: {coarser} particles coarser "
          f"than their level (want 0), {finer} of {len(size)} finer (waiting to merge; want at "
          f"most 1 %)")
    per_level = d["particles_l0"] + d["particles_l1"]
    check(np.array_equal(per_level, d["particles"]) and d["particles_l1"].min() > 0,
          f"diagnostics.csv: the per-level counts sum to the particle count in all {len(d)} rows "
          f"(level 1 holds {int(d['particles_l1'].min())} to {int(d['particles_l1'].max())})")
    ref = row_density(runs["fine"][0])
    for label in ("refined", "coarse"):
        err = np.abs(row_density(runs[label][0]) - ref).mean()
        print(f"info {label}: mean |rho - rho_fine| over the rows 0.2 < y < 0.4 at t = 1.2: "
              f"{err:.2e}")
    # Energy: measured 6.4e-11, bs32's error (rtol 1e-6) on a steepening pulse; 1e-8 keeps a
    # margin for the machine's other steps and fails on a work-energy mismatch.
    conservation(runs, 1e-12, 1e-12, 1e-8)


def part_compression():
    text = case_text(3, 1.2, PULSE_5, DYNAMIC.replace("criterion = density", "criterion = "
                                                      "compression").replace("0.004", "0.003"))
    out, _ = run("refine_compression", text)
    for t, f in mt.snapshots(out):
        p = mt.particles(f, "fluid")
        x, y = p["x"][:, 0], p["x"][:, 1]
        band = (y > 0.2) & (y < 0.4)
        k = np.minimum((x[band] / 0.05).astype(int), 59)
        u = (np.bincount(k, (p["m"].ravel() * p["v"][:, 0])[band], 60) /
             np.bincount(k, p["m"].ravel()[band], 60))
        front = 0.05 * (np.argmin(np.diff(u)) + 1)  # the face of the steepest drop
        near = band & (np.abs(x - front) < 0.05)
        levels = set(p["level"].ravel()[near].astype(int))
        check(levels == {1}, f"compression, t = {p['time']:g}: the band's particles within a cell "
              f"of the steepest velocity drop (x = {front:.2f}) are on levels {sorted(levels)} "
              f"(want [1])")
    d = diagnostics(out)
    check(len(set(d["particles"].astype(int))) > 2, "compression: the particle count changes "
          "(regrids, splits, merges)")
    dm, dp, de, _ = drifts(out)
    check(dm <= 1e-12 and dp <= 1e-12 and de <= 1e-8, f"compression: drifts of mass {dm:.1e}, "
          f"momentum {dp:.1e}, energy {de:.1e} (bounds 1e-12, 1e-12, 1e-8 as for density)")


def part_vorticity():
    gas = "density = 1\npressure = 0.714285714285714\nvelocity_field = 0.3*tanh((y-0.3)/0.05); 0"
    counts = {}
    for thr in ("0.05", "0.5"):
        refine = DYNAMIC.replace("criterion = density", "criterion = vorticity").replace(
            "0.004", thr)
        out, _ = run(f"refine_vorticity_{thr}", case_text(3, 0.3, gas, refine))
        p = final(out)
        x, y = p["x"][:, 0], p["x"][:, 1]
        mid = (np.abs(y - 0.3) < 0.025) & (x > 0.3) & (x < 2.7)  # 4 cells clear of x = 0, 3
        # (a run never refined writes no particle level: its hierarchy never existed)
        levels = p["level"].ravel()[mid] if "level" in p else np.zeros(int(mid.sum()))
        counts[thr] = (set(levels.astype(int)), int(diagnostics(out)["particles_l1"].max()))
    check(counts["0.05"][0] == {1}, f"vorticity, threshold 0.05: the particles at the layer's "
          f"middle are on levels {sorted(counts['0.05'][0])} at t = 0.3 (want [1])")
    check(counts["0.5"][1] == 0, f"vorticity, threshold 0.5: at most {counts['0.5'][1]} "
          f"particles on level 1 over the run (want 0: no jump reaches it)")


def centre_counts(p):
    """The particles in each of the 9 x 9 level-0 cells (nearest node) around the centre of the
    expansion (1, 1): within 0.225 of it along each axis."""
    j = np.rint(p["x"] / 0.05).astype(int) - 16
    inside = ((j >= 0) & (j < 9)).all(axis=1)
    c = np.zeros((9, 9), int)
    np.add.at(c, (j[inside, 1], j[inside, 0]), 1)
    return c


def expansion_run(name, refine, geometry="all", velocity=EXPAND_V, t_end=1.2):
    """The expansion scene: (folder, [(t, smallest centre count, particles, level-1 particles,
    the largest distance of one from the centre)] per snapshot)."""
    text = EXPANSION.format(t_end=t_end, interval=t_end / 4, geometry=geometry,
                            velocity=velocity, refine=refine)
    out, _ = run(name, text)
    rows = []
    for _, f in mt.snapshots(out):
        p = mt.particles(f, "fluid")
        l1 = p["level"].ravel() == 1 if "level" in p else np.zeros(len(p["x"]), bool)
        r = np.hypot(p["x"][:, 0] - 1, p["x"][:, 1] - 1)
        rows.append((p["time"], int(centre_counts(p).min()), len(p["x"]), int(l1.sum()),
                     float(r[l1].max()) if l1.any() else 0.0))
    for r in rows:
        print(f"info {name}: t = {r[0]:.2f}: fewest particles in a centre cell {r[1]}, "
              f"{r[2]} particles, {r[3]} on level 1 (the farthest {r[4]:.2f} from the centre)")
    return out, rows


def part_starvation():
    k = 2  # half the 2 x 2 particles a cell is seeded with
    comp = STARVE.replace("starvation\n", "compression, starvation\nthreshold = 0.05\n")
    runs = {"starvation": expansion_run("refine_starvation", STARVE),
            "none": expansion_run("refine_starvation_none", ""),
            "compression, starvation": expansion_run("refine_starvation_both", comp),
            "compression": expansion_run("refine_starvation_comp", comp.replace(
                ", starvation", "").replace("min_particles = 2.5\n", ""))}
    fewest = {label: min(r[1] for r in rows) for label, (_, rows) in runs.items()}
    check(fewest["none"] < k and fewest["compression"] < k,
          f"unrefined and compression alone: the centre's cells fall to {fewest['none']} and "
          f"{fewest['compression']} particles by t = 1.2 (want < {k}: the gas starves)")
    for label in ("starvation", "compression, starvation"):
        check(fewest[label] >= k, f"{label}: the centre's cells keep at least {fewest[label]} "
              f"particles at every snapshot (want >= {k}: split before they empty)")
    # The union of the flags: the compression ring's level-1 particles and the centre's.
    last = {label: rows[-1] for label, (_, rows) in runs.items()}
    both, alone = last["compression, starvation"][3], (last["compression"][3],
                                                       last["starvation"][3])
    check(both >= max(alone) and both > min(alone) > 0, f"compression, starvation: {both} "
          f"particles on level 1 at t = 1.2, compression alone {alone[0]}, starvation alone "
          f"{alone[1]} (want at least either: the union of their regions)")
    # Starvation flags the thinned centre alone: beyond r = 0.6 the gas barely moves (|u| <
    # 0.011) and keeps its 4 particles a cell, while the flags (dilated by 2 cells) reach r = 0.5.
    far = max(r[4] for r in runs["starvation"][1])
    check(0 < far < 0.6, f"starvation: the farthest level-1 particle over the run is {far:.2f} "
          f"from the centre (want < 0.6: the centre is refined, not the resting gas around it)")
    # A disc of gas at rest in empty space: its edge cells hold few particles but border empty
    # cells, and empty cells are never flagged, so nothing is refined.
    disc, _ = expansion_run("refine_starvation_disc", STARVE, "disc", "velocity = 0 0", 0.05)
    l1 = int(diagnostics(disc)["particles_l1"].max())
    check(l1 == 0, f"starvation, a disc of gas in empty space: {l1} particles on level 1 over "
          f"the run (want 0: neither its edge nor the empty space is starved)")
    # A restart between regrids of the combined run (t = 0.3 of 0.6) ends bit for bit as the
    # run straight through: the flags come from the checkpoint's particles alone.
    case = os.path.join(mt.outdir("refine_starvation_restart_case"), "case.ini")
    with open(case, "w") as f:
        f.write(EXPANSION.format(t_end=0.6, interval=0.3, geometry="all", velocity=EXPAND_V,
                                 refine=comp))
    ids, worst, _ = mt.restart_difference(case, [], 0.6, "refine_starvation_restart", "fluid")
    check(ids and worst == 0.0, f"compression, starvation restarted at t = 0.3: the same "
          f"particles, fields {worst:.1e} from the run straight through (bit for bit: 0)")
    for label in ("starvation", "compression, starvation", "none"):
        out = runs[label][0]
        d = diagnostics(out)
        scale = np.sqrt(2 * d["mass"][0] * d["kinetic"][0])  # >= sum m |v|: the start is at rest
        dp = max(abs(d["px"]).max(), abs(d["py"]).max()) / scale  # on the whole
        dm = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
        de = abs(d["total"] - d["total"][0]).max() / d["total"][0]
        regrids = len(set(d["particles"].astype(int)))
        if label == "none":
            print(f"info unrefined: drifts of mass {dm:.1e}, momentum {dp:.1e}, energy {de:.1e}")
            continue
        # Mass and momentum to roundoff; energy to bs32's own error, which the scene's time.rtol
        # of 1e-8 keeps near 1e-10 (the run without refinement drifts 5e-11; 2e-9 at the
        # default 1e-6, where a regrid that lost energy would hide)
        check(dm <= 1e-12 and dp <= 1e-12 and de <= 2e-9 and regrids > 2,
              f"{label}: drifts of mass {dm:.1e}, momentum {dp:.1e} (of sqrt(2 M K)), energy "
              f"{de:.1e} (bounds 1e-12, 1e-12, 2e-9) over {regrids} particle counts")


# The expansion scene with a static level-1 box over its centre and the gas's expansion settings
# (refill at every step, light merges, merges and splits by count every 5 steps, the
# neighbourhood step), which the levels carry (fluid/fluid_regularise.c, fluid/fluid_stable.c).
REFILL_BOX = "[refine]\nlevels = 2\n\n[refine.box]\nlevel = 1\nlo = 0.6 0.6\nhi = 1.4 1.4\n"
REFILL_V = EXPAND_V.replace("(x-1)*", "3*(x-1)*").replace("(y-1)*", "3*(y-1)*")  # 3x faster
REFILL_GAS = ("[fluid]\nrefill_every = 1\nmerge_light = 0.125\nregularise_every = 5\n"
              "stable_step = neighbourhood\npressure = grid\n")


def span_counts(p):
    """Level-1 particles in each level-1 span (cell 0.025 wide from the origin) of the centre's
    [0.8, 1.2]^2, well inside the box: every one of them is a cell of level 1 alone."""
    h = 0.025
    on = p["level"].ravel() == 1
    k = np.floor((p["x"][on] - 0.8) / h).astype(int)
    inside = ((k >= 0) & (k < 16)).all(axis=1)
    c = np.zeros((16, 16), int)
    np.add.at(c, (k[inside, 1], k[inside, 0]), 1)
    return c


def part_refill():
    def scene(refill, extra=""):
        text = EXPANSION.format(t_end=0.6, interval=0.15, geometry="all", velocity=REFILL_V,
                                refine=REFILL_BOX)
        return text + (REFILL_GAS if refill else "[fluid]\npressure = grid\n") + extra
    fewest = {}
    for label, refill in (("refilled", True), ("not refilled", False)):
        out, _ = run(f"refine_refill_{label.replace(' ', '_')}", scene(refill))
        fewest[label] = min(int(span_counts(mt.particles(f, "fluid")).min())
                            for _, f in mt.snapshots(out))
        if refill:
            main = out
    # Able to fail: without the refill the centre's level-1 spans empty (measured below).
    check(fewest["not refilled"] == 0, f"not refilled: the centre's level-1 spans fall to "
          f"{fewest['not refilled']} particles (want 0: the expansion empties them)")
    check(fewest["refilled"] >= 1, f"refilled on level 1: the centre's level-1 spans keep at "
          f"least {fewest['refilled']} particle at every snapshot (want >= 1: no empty cell)")
    d = diagnostics(main)
    scale = np.sqrt(2 * d["mass"][0] * d["kinetic"][0])
    dp = max(abs(d["px"]).max(), abs(d["py"]).max()) / scale
    dm = abs(d["mass"] - d["mass"][0]).max() / d["mass"][0]
    de = abs(d["total"] - d["total"][0]).max() / d["total"][0]
    # Refills halve a particle, merges sum two: mass and momentum to roundoff, and total energy
    # to bs32's own error at rtol 1e-8, as in the starvation part.
    check(dm <= 1e-12 and dp <= 1e-12 and de <= 2e-9, f"refilled: drifts of mass {dm:.1e}, "
          f"momentum {dp:.1e} (of sqrt(2 M K)), energy {de:.1e} (bounds 1e-12, 1e-12, 2e-9)")
    # 2 ranks against 1 at fixed steps (level 0 split at x = 1, through the box): the donors
    # and children are chosen from the counts alone, so the same particles, ids included.
    fix = "[time]\nadaptive = false\ncfl = 0.4\n"
    text = scene(True).replace("[time]\n", fix).replace("t_end = 0.6", "t_end = 0.45")
    a, b = (mt.particles(mt.snapshots(run(f"refine_refill_np{n}", text, n)[0])[-1][1], "fluid")
            for n in (1, 2))
    same = a["id"].shape == b["id"].shape and np.array_equal(a["id"], b["id"])
    worst = max(float(np.abs(a[k] - b[k]).max() / np.abs(a[k]).max())
                for k in ("x", "v", "m", "e")) if same else float("inf")
    check(same and worst <= 1e-12, f"refilled on 2 ranks against 1 (fixed steps, to t = 0.45): "
          f"the same {len(a['id'])} particle ids: {same}, fields within {worst:.1e} (relative; "
          f"bound 1e-12, the sums' order)")


PERIODIC = ("[refine]\nlevels = 3\n\n[refine.band]\nlevel = 1\nlo = 0.3 0\nhi = 0.9 0.6\n\n"
            "[refine.across]\nlevel = 1\nlo = -0.15 0.2\nhi = 0.1 0.4\n\n"
            "[refine.inner]\nlevel = 2\nlo = 0.5 0\nhi = 0.7 0.6\n")


def near_faces(p, level, length, height, h):
    """Particles of `level` within h of the y faces, and within h of the x faces."""
    on = p["level"].ravel() == level
    x, y = p["x"][on, 0], p["x"][on, 1]
    return (int(np.sum((y < h) | (y > height - h))), int(np.sum((x < h) | (x > length - h))))


def part_periodic():
    u0, v0 = 0.5 * C0, 0.3 * C0
    gas = f"density = 1\npressure = 1\nvelocity = {u0!r} {v0!r}"
    runs = {"refined": run("refine_periodic", case_text(1.2, 0.6, gas, PERIODIC, extra=FLUID,
                                                         y="periodic"))}
    report_cost(runs)
    out = runs["refined"][0]
    p = final(out)
    got = max(np.abs(p["rho"] - 1).max(), np.abs(p["p"] - 1).max(),
              np.abs(p["v"][:, 0] - u0).max() / u0, np.abs(p["v"][:, 1] - v0).max() / u0)
    # Roundoff (the static box test measures 3e-15); a wrong fold or copy of the images, or a
    # mask that does not wrap, disturbs the gas at the faces by O(1e-2) within a few steps.
    check(got <= 1e-10, f"uniform gas moving diagonally across the periodic faces and the "
          f"levels: largest deviation {got:.2e} <= 1e-10 at t = {p['time']:g}")
    counts = [near_faces(p, l, 1.2, 0.6, 0.025) for l in (1, 2)]
    check(counts[0][0] > 0 and counts[1][0] > 0 and counts[0][1] > 0,
          f"particles within half a cell of the y faces on levels 1 and 2 ({counts[0][0]}, "
          f"{counts[1][0]}) and of the x faces on level 1 ({counts[0][1]}): the levels wrap")
    conservation(runs, 1e-12, 1e-12, 1e-10)  # as the uniform stream (energy measured ~1e-14)


def part_wrap():
    text = case_text(3, 1.2, PULSE_5.replace("x-0.6", "x-2.6"),
                     DYNAMIC.replace("levels = 2", "levels = 3"), y="periodic", height=0.15)
    text = text.replace("interval = 0.6", "interval = 0.1").replace(
        "t_end = 1.2", "t_end = 1.2\nadaptive = false")
    runs = {"refined": run("refine_wrap", text)}
    report_cost(runs)
    out = runs["refined"][0]
    across, spans, rows = 0, True, set()
    for t, f in mt.snapshots(out):
        p = mt.particles(f, "fluid")
        for level in (1, 2):
            on = p["level"].ravel() == level
            x, y = p["x"][on, 0], p["x"][on, 1]
            if not on.any():
                continue
            # Every particle row of the level's lattice (2 per cell of 0.05 / 2^level) is there:
            # a region that lost the half span below y = 0 (its image at the top) misses rows.
            got = len(np.unique(np.round(y * 2 ** (level + 1) / 0.05 - 0.5)))
            spans &= got == 3 * 2 ** (level + 1)
            rows.add(got)
        x = p["x"][p["level"].ravel() >= 1, 0]
        across += bool(np.any(x < 0.05) and np.any(x > 2.95))
    check(spans and across >= 2, f"levels 1 and 2 hold every particle row of the period along y "
          f"at every snapshot ({spans}; rows seen {sorted(rows)}) and the refined region crosses "
          f"the x faces at {across} of the snapshots (want >= 2)")
    d = diagnostics(out)
    check(len(set(d["particles"].astype(int))) > 2, "the particle count changes (regrids, splits "
          "and merges)")
    # Splits and merges conserve exactly; the regrid moves no particle. Energy: bs32's own error
    # at a fixed step on a steepening pulse (the dynamic part measures 6e-11 adaptive).
    conservation(runs, 1e-12, 1e-12, 1e-8)
    # A restart at t = 0.25, the region across the x faces (the pulse crosses at t = 0.34).
    case = os.path.join(mt.outdir("refine_wrap_restart_case"), "case.ini")
    with open(case, "w") as f:
        f.write(text)
    ids, worst, _ = mt.restart_difference(case, [], 0.5, "refine_wrap_restart", "fluid")
    check(ids and worst == 0.0, f"regridded across the periodic faces, restarted at t = 0.25: "
          f"the same particles, fields {worst:.1e} from the run straight through (bit for bit: 0)")


def part_restart():
    # A restart at t = 0.2 (step ~85, between regrids) of the run to 0.4.
    case = os.path.join(mt.outdir("refine_dynamic_restart_case"), "case.ini")
    with open(case, "w") as f:
        f.write(case_text(3, 0.4, PULSE_5, DYNAMIC))
    ids, worst, _ = mt.restart_difference(case, [], 0.4, "refine_dynamic_restart", "fluid")
    check(ids and worst == 0.0, f"dynamic refinement restarted at t = 0.2: the same particles, "
          f"fields {worst:.1e} from the run straight through (bit for bit: 0)")
    # Regrids every step: the one forced before the checkpoint then mostly keeps the regions it
    # found a step before, while the restart's builds them afresh; the particles must follow
    # the levels alike on both sides (coupler/mpm_sim.c).
    ids, worst, _ = mt.restart_difference(case, ["refine.every=1"], 0.4,
                                          "refine_dynamic_restart_every1", "fluid")
    check(ids and worst == 0.0, f"dynamic refinement regridded every step, restarted at t = 0.2: "
          f"the same particles, fields {worst:.1e} from the run straight through (bit for bit: 0)")


def part_ranks():
    text = case_text(3, 0.5, PULSE_5, "", extra="[fluid]\npressure = grid\n").replace(
        "t_end = 0.5", "t_end = 0.5\nadaptive = false\ncfl = 0.8")
    finals = [final(run(f"refine_gridp_np{n}", text, ranks=n)[0]) for n in (1, 2)]
    worst = 0.0
    ia, ib = (np.argsort(f["id"].ravel()) for f in finals)
    same = np.array_equal(finals[0]["id"][ia], finals[1]["id"][ib])
    for k in ("x", "v", "rho", "p"):
        va, vb = finals[0][k][ia], finals[1][k][ib]
        worst = max(worst, float(np.abs(va - vb).max() / max(np.abs(va).max(), 1e-300)))
    # Roundoff: the halo sums change the order of additions (measured 2.4e-15); fixed steps, as
    # the adaptive controller's norm, summed in another order, moves its steps (1e-9 then).
    check(same and worst <= 1e-12, f"grid pressure on 2 ranks against 1: the same particles, "
          f"fields within {worst:.1e} (relative; bound 1e-12)")


def part_input():
    gas = "density = 1\npressure = 1"
    box = BOX.format(x0=0.8, x1=1.2)
    refined = case_text(2, 0.1, gas, box)
    # (name, case text, key, the start of the line that sets it, words of the message)
    cases = [
        ("box with levels = 1", case_text(2, 0.1, gas, box.replace("levels = 2", "levels = 1")),
         "refine.box.level", "level = 1", "refine.levels = 1"),
        # A box may touch a slip or no-slip wall of the gas (test_refine_walls.py), not a
        # closed face (none), nor cross a wall.
        ("box near a closed face", case_text(2, 0.1, gas, box.replace(
            "lo = 0.8 0.15", "lo = 0.8 0.1"), y="none"), "refine.box.lo", "lo = 0.8 0.1",
         "act on level 0 only"),
        ("box past a wall", case_text(2, 0.1, gas, box.replace("lo = 0.8 0.15", "lo = 0.8 -0.1")),
         "refine.box.lo", "lo = 0.8 -0.1", "not crossed"),
        # Along a periodic axis a box may cross the faces (the levels wrap), by up to a period.
        ("box more than a period beyond a periodic face", case_text(
            2, 0.1, gas, box.replace("hi = 1.2 0.45", "hi = 4.5 0.45")),
         "refine.box.lo", "lo = 0.8 0.15", "more than a period"),
        ("box of level 2 outside level 1", case_text(2, 0.1, gas, box.replace(
            "levels = 2", "levels = 3") + "\n[refine.inner]\nlevel = 2\nlo = 0.5 0.2\n"
            "hi = 0.7 0.3\n"), "refine.inner.lo", "lo = 0.5 0.2", "not inside"),
        ("linear shape", refined.replace("dx = 0.05", "dx = 0.05\nshape = linear"), "grid.shape",
         "shape = linear", "quadratic"),
        ("odd ppc", case_text(2, 0.1, gas, box, extra="[fluid]\nppc = 3\n"), "fluid.ppc",
         "ppc = 3", "even"),
    ]
    for key, value in [("fluid.volume_rate", "domain"), ("fluid.av_form", "riemann"),
                       ("fluid.shift", "0.375")]:
        sec, k = key.split(".")
        if sec == "time":
            text = refined.replace("t_end = 0.1", f"t_end = 0.1\n{k} = {value}")
        else:
            text = case_text(2, 0.1, gas, box, extra=f"[fluid]\n{k} = {value}\n")
        cases.append((f"{key} = {value}", text, key, f"{k} = {value}", "not carried"))
    # Obstacles act on every level (test_refine_obstacles); the least-squares wall does not.
    obstacle = "[obstacle.post]\nshape = circle\ncenter = 0.3 0.3\nradius = 0.05\n"
    lsq = case_text(2, 0.1, gas, box, extra="[fluid]\nwall_treatment = least_squares\n\n" +
                    obstacle).replace("t_end = 0.1", "t_end = 0.1\nmethod = usl")
    cases.append(("least-squares wall", lsq, "fluid.wall_treatment",
                  "wall_treatment = least_squares", "not carried"))
    # Open faces are carried on level 0 (test_refine_open.py); a box keeps its three cells from
    # them, and the gauge exterior (the particle pressure's) is refused with the grid pressure.
    openface = refined.replace("y_lo = slip\ny_hi = slip", "y_lo = slip\ny_hi = outflow")
    openface = openface.replace("[gas.air]", "[freestream]\ndensity = 1\npressure = 1\n"
                                "exterior = gauge\n\n[gas.air]")
    cases.append(("open face with the gauge exterior", openface, "freestream.exterior",
                  "exterior = gauge", "gauge"))
    cases.append(("box near an open face", openface.replace("exterior = gauge\n", "").replace(
        "hi = 1.2 0.45", "hi = 1.2 0.5"), "refine.box.hi", "hi = 1.2 0.5", "act on level 0 only"))
    solid = ("[geometry.plate]\ntype = box\nlo = 0.2 0.2\nhi = 0.3 0.3\n\n[solid.plate]\n"
             "geometry = plate\nmaterial = linear_elastic\ndensity = 1000\nE = 1e6\nnu = 0.3\n")
    solid += "\n[geometry.air]\ntype = difference\nof = strip plate\n"
    with_solid = refined.replace("geometry = strip", "geometry = air")
    # Beside a solid a box must span the periodic axes (test_refine_fsi.py carries the rest).
    cases.append(("solid module, box not across x", with_solid.replace("[refine]", solid +
                                                                       "\n[refine]"),
                  "refine.box.lo", "lo = 0.8 0.15", "periodic axis x"))
    # fluid.pressure = grid's own refusals (fluid/fluid_gridp.c), on the strip without [refine].
    grid = "[fluid]\npressure = grid\n"
    plain = case_text(2, 0.1, gas, "", extra=grid)
    for key, value, words in [("fluid.strain_rate", "lagged", "current strain rate"),
                              ("grid.shape", "linear", "quadratic"),
                              ("fluid.shift", "0.375", "shifting"),
                              ("fluid.volume_rate", "domain", "volume rate")]:
        sec, k = key.split(".")
        if sec == "fluid":
            text = plain.replace("pressure = grid", f"pressure = grid\n{k} = {value}")
        elif sec == "time":
            text = plain.replace("t_end = 0.1", f"t_end = 0.1\n{k} = {value}")
        else:
            text = plain.replace("dx = 0.05", f"dx = 0.05\n{k} = {value}")
        cases.append((f"grid pressure with {key} = {value}", text, key, f"{k} = {value}", words))
    cases.append(("grid pressure with the gauge exterior", openface.replace(
        "[refine]", grid + "\n[refine]").replace("levels = 2", "levels = 1").split(
        "\n[refine.box]")[0], "freestream.exterior", "exterior = gauge", "gauge"))
    cases.append(("particle pressure with refinement", case_text(
        2, 0.1, gas, box, extra="[fluid]\npressure = particle\n"), "fluid.pressure",
        "pressure = particle", "corners"))
    # The grid pressure beside a solid runs (monolithic, not contact); its refusals are
    # test_refine_body_input's.
    for name, text, key, start, words in cases:
        mt.expect_input_error(check, name, text, key, mt.line_starting(text, start), words)
    # Dynamic refinement's own refusals.
    dyn = case_text(2, 0.1, gas, DYNAMIC)
    cases_dyn = [
        ("criterion without a threshold", dyn.replace("threshold = 0.004\n", ""),
         "refine.criterion", "criterion = density", "threshold"),
        ("dilate too small for the buffer", dyn.replace("every = 10", "every = 10\nbuffer = 4\n"
                                                        "dilate = 1"), "refine.dilate",
         "dilate = 1", "refine.dilate >= 2"),
        ("criterion with a static box", case_text(2, 0.1, gas, box.replace(
            "levels = 2", "levels = 2\ncriterion = density\nthreshold = 0.01")),
         "refine.box.level", "level = 1", "static box"),
        # Lists of criteria (compression, starvation; docs/refinement.md).
        ("unknown criterion", dyn.replace("criterion = density", "criterion = density, shock"),
         "refine.criterion", "criterion = density, shock", "'shock' is not a criterion"),
        ("criterion listed twice", dyn.replace("criterion = density",
                                               "criterion = density,density"),
         "refine.criterion", "criterion = density,density", "density twice"),
        ("none with another criterion", dyn.replace("criterion = density",
                                                    "criterion = none, density"),
         "refine.criterion", "criterion = none, density", "none alone"),
        ("starvation without min_particles", dyn.replace("criterion = density",
                                                         "criterion = density starvation"),
         "refine.criterion", "criterion = density starvation", "refine.min_particles > 0"),
        ("two criteria, one threshold", dyn.replace(
            "criterion = density", "criterion = density, compression"), "refine.threshold",
         "threshold = 0.004", "1 value for the 2 criteria"),
        ("a threshold no criterion reads", dyn.replace(
            "criterion = density", "criterion = starvation\nmin_particles = 2"),
         "refine.threshold", "threshold = 0.004", "lists none of its readers"),
        ("a threshold of 0", dyn.replace("criterion = density", "criterion = vorticity, "
                                         "density").replace("0.004", "0.05 0"),
         "refine.threshold", "threshold = 0.05 0", "is 0 for density"),
        ("min_particles = 0", dyn.replace("criterion = density", "criterion = starvation\n"
                                          "min_particles = 0").replace("threshold = 0.004\n",
                                                                        ""),
         "refine.min_particles", "min_particles = 0", "starvation needs a threshold"),
        ("min_particles without starvation", dyn.replace("threshold = 0.004",
                                                         "threshold = 0.004\nmin_particles = 2"),
         "refine.min_particles", "min_particles = 2", "does not list starvation"),
        ("proximity without an obstacle", dyn.replace("criterion = density",
                                                      "criterion = density, proximity"),
         "refine.criterion", "criterion = density, proximity", "the case has none"),
        ("distance without proximity", dyn.replace("threshold = 0.004",
                                                   "threshold = 0.004\ndistance = 0.1"),
         "refine.distance", "distance = 0.1", "does not list proximity"),
        ("a negative distance", dyn.replace("threshold = 0.004",
                                            "threshold = 0.004\ndistance = -0.1"),
         "refine.distance", "distance = -0.1", ""),
        # With criterion = none nothing regrids: the regrids' keys are refused, not ignored.
        ("a threshold without a criterion", case_text(2, 0.1, gas, box.replace(
            "levels = 2", "levels = 2\nthreshold = 0.01")), "refine.threshold",
         "threshold = 0.01", "refine.criterion is none"),
        ("distance without a criterion", case_text(2, 0.1, gas, box.replace(
            "levels = 2", "levels = 2\ndistance = 0.1")), "refine.distance", "distance = 0.1",
         "refine.criterion is none"),
        ("every without a criterion", case_text(2, 0.1, gas, box.replace(
            "levels = 2", "levels = 2\nevery = 5")), "refine.every", "every = 5",
         "refine.criterion is none"),
    ]
    for name, text, key, start, words in cases_dyn:
        mt.expect_input_error(check, name, text, key, mt.line_starting(text, start), words)
    # Regrids beside a solid need the grid pressure (the particles' pressure keeps to bands
    # across a periodic axis): one line naming refine.criterion, exit 2. (A solid on several
    # ranks runs: test_refine_ranks_solid.)
    fsi = rs.fsi_case(0.1, "[refine]\nlevels = 2\ncriterion = density\nthreshold = 0.001\n")
    mt.expect_input_error(check, "regrids beside a solid, particle pressure", fsi,
                          "refine.criterion", mt.line_starting(fsi, "criterion = density"),
                          "fluid.pressure = grid")


def part_identity():
    gas = "density = 1\npressure_field = 1 + 0.1*exp(-(x-1)^2/0.02)"
    plain = case_text(2, 0.2, gas, "")
    off = case_text(2, 0.2, gas, "[refine]\nlevels = 1\n")
    a, b = final(run("refine_off_plain", plain)[0]), final(run("refine_off_levels1", off)[0])
    same = np.array_equal(a["id"], b["id"]) and all(
        np.array_equal(a[k], b[k], equal_nan=True) for k in a if k != "time")
    check(same, f"refine.levels = 1 and no [refine] section: final snapshots identical, bit for "
          f"bit ({len(a['id'])} particles, fields {', '.join(k for k in a if k != 'time')})")
    # A refined run restarted from its checkpoint at T/2 ends as the run straight through.
    out = mt.outdir("refine_restart_case")
    path = os.path.join(out, "case.ini")
    with open(path, "w") as f:
        f.write(case_text(2, 0.2, gas, BOX.format(x0=0.8, x1=1.2)))
    ids, worst, _ = mt.restart_difference(path, [], 0.2, "refine_restart", "fluid")
    check(ids and worst == 0.0, f"refined run restarted at t = 0.1: the same particles, fields "
          f"{worst:.1e} from the run straight through (bit for bit: 0)")


# ---- output --------------------------------------------------------------------------------

H0 = 0.05  # level 0's spacing in case_text
LEVELS3 = ("[refine]\nlevels = 3\n\n[refine.box]\nlevel = 1\nlo = 0.8 0.15\nhi = 1.4 0.45\n\n"
           "[refine.inner]\nlevel = 2\nlo = 1.0 0.25\nhi = 1.2 0.35\n")
BOXES = [(1, (0.8, 0.15), (1.4, 0.45)), (2, (1.0, 0.25), (1.2, 0.35))]
DIAG_COLS = ["t", "step", "dt", "particles", "mass", "px", "py", "pz", "kinetic", "internal",
             "total", "rhs_evals"]


def level_origin(level):
    """o_l of mpm_hier.h: o_0 = the domain's lo (0, 0), o_{l+1} = o_l - h_{l+1} / 2."""
    o = np.zeros(2)
    for m in range(1, level + 1):
        o -= H0 / 2 ** m / 2
    return o


def regions():
    """Each box's region as [lo, hi] per axis: the level l - 1 spans (dual cells of its nodes,
    [o + (i - 1/2) h, o + (i + 1/2) h]) that meet the open box, as mpm_hier.h defines them."""
    out = []
    for level, lo, hi in BOXES:
        o, h = level_origin(level - 1), H0 / 2 ** (level - 1)
        a = np.floor((np.array(lo) - o) / h - 0.5 + 1e-9) + 1
        z = np.ceil((np.array(hi) - o) / h + 0.5 - 1e-9) - 1
        out.append((level, o + (a - 0.5) * h, o + (z + 0.5) * h))
    return out


def expected_levels(x):
    """The finest level whose region holds each position (the regions nest); and the least
    distance of a particle to a region's face (a particle on a face could go either way)."""
    level, margin = np.zeros(len(x), dtype=int), np.inf
    for lv, lo, hi in regions():
        inside = np.all((x > lo) & (x < hi), axis=1)
        level = np.where(inside, np.maximum(level, lv), level)
        margin = min(margin, np.abs(np.concatenate([x - lo, x - hi])).min())
    return level, margin


def check_level_group(f, snap, level, problems):
    """/levels/<level> of one snapshot: shapes, spacing, origin on the level's lattice."""
    g = f[f"levels/{level}"]
    h, o = H0 / 2 ** level, level_origin(level)
    shape = (f["grid/fluid/m"] if level == 0 else g["fluid/m"]).shape
    origin = np.asarray(g.attrs["origin"])
    steps = (origin - o) / h
    if g.attrs["level"] != level or abs(g.attrs["spacing"] - h) > 1e-15:
        problems.append(f"{snap} level {level}: attributes {dict(g.attrs)}")
    if np.abs(steps - np.round(steps)).max() > 1e-9:
        problems.append(f"{snap} level {level}: origin {origin} is not a node of o_l + i h_l")
    if level == 0 and (not np.allclose(origin, f["grid"].attrs["origin"]) or "fluid" in g):
        problems.append(f"{snap} level 0: origin {origin} or a grid phase beside /grid's")
    if level > 0 and g["fluid/v"].shape != shape + (2,):
        problems.append(f"{snap} level {level}: v {g['fluid/v'].shape} for m {shape}")
    for mask in ("active", "own"):
        if g[mask].shape != shape or g[mask].dtype != np.uint8:
            problems.append(f"{snap} level {level}: {mask} {g[mask].shape} {g[mask].dtype}")
    return g, origin, h


def own_of(groups, level, x):
    """The own mask of the span holding each position on its level (span i is node i's dual
    cell: the nearest node). Level 0's lattice has its pad layers and, along the periodic x,
    writes the nodes 0 .. ncells - 1 only (the rest are their images): wrap onto them."""
    g, origin, h = groups[level]
    j = np.round((x - origin) / h).astype(int)
    if level == 0:
        pad, ncells = int(round(-origin[0] / h)), int(round(2 / h))  # case_text(2, ...)
        j[:, 0] = (j[:, 0] - pad) % ncells + pad
    own = g["own"][()]
    ok = (j >= 0).all(axis=1) & (j[:, 0] < own.shape[1]) & (j[:, 1] < own.shape[0])
    out = np.zeros(len(x), dtype=int)
    out[ok] = own[j[ok, 1], j[ok, 0]]
    return out


def check_own(groups, level, snap, problems):
    """The mask own of a level is 1 exactly at the nodes whose span (centred on the node) has
    that level by the boxes (level 0: the periodic x's written nodes 0 .. ncells - 1 only)."""
    g, origin, h = groups[level]
    own = g["own"][()]
    jy, jx = np.meshgrid(np.arange(own.shape[0]), np.arange(own.shape[1]), indexing="ij")
    x = np.stack([origin[0] + jx.ravel() * h, origin[1] + jy.ravel() * h], axis=1)
    want = (expected_levels(x)[0] == level).reshape(own.shape)
    if level == 0:
        pad, ncells = int(round(-origin[0] / h)), int(round(2 / h))
        own, want = own[:, pad:pad + ncells], want[:, pad:pad + ncells]
    if not np.array_equal(own.astype(bool), want):
        problems.append(f"{snap} level {level}: own differs from the boxes' regions at "
                        f"{np.count_nonzero(own.astype(bool) != want)} nodes")


def check_grid_sums(f, groups, snap, problems):
    """The composite grid holds the particles' mass and momentum on the active nodes of all
    levels, and nothing on the inactive ones (mpm_hier.h). Mass: a sum of ~3000 terms, 1e-12
    relative. Momentum: the stream is uniform, so the deposit the grid keeps (from the last
    right-hand side, at a stage's positions) has the particles' momentum to roundoff too."""
    mass = f["fluid/m"][()].sum()
    mom = (f["fluid/m"][()] * f["fluid/v"][()]).sum(axis=0)
    gm, gp, stray = 0.0, np.zeros(2), 0.0
    for lv in range(3):
        g = groups[lv][0]
        m = (f["grid/fluid/m"] if lv == 0 else g["fluid/m"])[()]
        v = (f["grid/fluid/v"] if lv == 0 else g["fluid/v"])[()]
        act = g["active"][()].astype(bool)
        gm += m[act].sum()
        gp += (m[act][:, None] * v[act]).sum(axis=0)
        stray = max(stray, np.abs(m[~act]).max() if (~act).any() else 0.0)
    dm, dp = abs(gm - mass) / mass, np.abs(gp - mom).max() / np.abs(mom).max()
    if dm > 1e-12 or dp > 1e-12 or stray != 0.0:
        problems.append(f"{snap}: grid mass {gm!r} against the particles' {mass!r} ({dm:.1e}), "
                        f"momentum {dp:.1e}, inactive nodes up to {stray:.1e}")


def check_snapshot(path, diag, problems):
    """Levels, particle levels and counts of one snapshot; returns (particles, margin)."""
    with h5py.File(path, "r") as f:
        snap, step = os.path.basename(path), int(f.attrs["step"])
        groups = {lv: check_level_group(f, snap, lv, problems) for lv in range(3)}
        x, level = f["fluid/x"][()], f["fluid/level"][()]
        if level.shape != (len(x), 1):
            problems.append(f"{snap}: level {level.shape} for {len(x)} particles")
        level = level[:, 0].astype(int)
        want, margin = expected_levels(x)
        if not np.array_equal(level, want):
            problems.append(f"{snap}: {np.count_nonzero(level != want)} particles' level differs "
                            f"from their position's")
        for lv in range(3):
            check_own(groups, lv, snap, problems)
            mine = level == lv
            if not own_of(groups, lv, x[mine]).all():
                problems.append(f"{snap}: particles of level {lv} outside its own mask")
        if step > 0:  # the grid holds the last deposit (none before the first step)
            check_grid_sums(f, groups, snap, problems)
        row = diag[diag["step"] == step][-1]
        counts = [int(row[f"particles_l{lv}"]) for lv in range(3)]
        if counts != np.bincount(level, minlength=3).tolist():
            problems.append(f"{snap}: diagnostics.csv counts {counts} at step {step}, the level "
                            f"field {np.bincount(level, minlength=3).tolist()}")
        return len(x), margin


def check_index(out, problems):
    """grid.xmf: per snapshot the blocks fluid_grid, fluid_grid_l1, _l2, every HDF item a
    dataset of that shape; series.xmf lists the particle level."""
    import xml.etree.ElementTree as ET
    root = ET.parse(os.path.join(out, "grid.xmf")).getroot()
    snaps = root.find("Domain/Grid").findall("Grid")
    for snap in snaps:
        names = [b.get("Name") for b in snap.findall("Grid")]
        if names != ["fluid_grid", "fluid_grid_l1", "fluid_grid_l2"]:
            problems.append(f"grid.xmf {snap.get('Name')}: blocks {names}")
        for block in snap.findall("Grid/Grid"):
            attrs = [a.get("Name") for a in block.findall("Attribute")]
            if attrs != ["m", "v", "active", "own"]:
                problems.append(f"grid.xmf {block.get('Name')}: attributes {attrs}")
    for item in root.iter("DataItem"):
        if item.get("Format") != "HDF":
            continue
        fname, _, dset = item.text.strip().partition(":")
        dims = tuple(int(d) for d in item.get("Dimensions").split() if d != "1")
        with h5py.File(os.path.join(out, fname), "r") as f:
            shape = tuple(d for d in f[dset].shape if d != 1) if dset in f else None
        if shape != dims:
            problems.append(f"grid.xmf: {fname}:{dset} {shape} for Dimensions {dims}")
    series = ET.parse(os.path.join(out, "series.xmf")).getroot()
    levels = [a for a in series.iter("Attribute") if a.get("Name") == "level"]
    if len(levels) != len(snaps):
        problems.append(f"series.xmf: {len(levels)} level attributes for {len(snaps)} snapshots")
    return len(snaps)


def check_paraview(out):
    """ParaView's three readers on grid.xmf: three blocks each, of the levels' node counts, with
    m, v, active, own, and the mask own read as stored."""
    with h5py.File(mt.snapshots(out)[-1][1], "r") as f:
        want = [(f["grid/fluid/m"].size, int(f["levels/0/own"][()].sum()))]
        want += [(f[f"levels/{lv}/fluid/m"].size, int(f[f"levels/{lv}/own"][()].sum()))
                 for lv in (1, 2)]
    p = subprocess.run(["pvpython", os.path.abspath(__file__), "--in-paraview",
                        os.path.join(out, "grid.xmf")], capture_output=True, text=True, timeout=120)
    seen = {r: [] for r in READERS}
    for line in p.stdout.splitlines():
        f = line.split()
        if len(f) == 5 and f[0] == "PV":
            seen[f[1]].append((int(f[2]), f[3], int(f[4])))
    for r in READERS:
        got = sorted((n, own) for n, arrays, own in seen[r] if arrays == "active,m,own,v")
        check(p.returncode == 0 and got == sorted(want) and len(seen[r]) == 3,
              f"ParaView {r} opens grid.xmf: blocks (points, own nodes) {seen[r]} "
              f"(want {sorted(want)} with m, v, active, own)")


def part_output():
    gas = "density = 1\npressure = 1\nvelocity = 0.6 0"
    extra = "[fluid]\nppc = 2\npressure = grid\n"
    text = case_text(2, 0.3, gas, LEVELS3, extra=extra).replace(
        "interval = 0.15", "interval = 0.15\ngrid_fields = true")
    out, wall = run("refine_output", text)
    print(f"info refined run: {wall:.2f} s wall")
    diag = diagnostics(out)
    cols = list(diag.dtype.names)
    check(cols == DIAG_COLS + ["particles_l0", "particles_l1", "particles_l2"],
          f"diagnostics.csv: the unrefined columns, then particles_l0 .. l2 ({', '.join(cols)})")
    total = sum(diag[f"particles_l{lv}"] for lv in range(3))
    check(np.array_equal(total, diag["particles"]) and (diag["particles_l2"] > 0).all(),
          f"diagnostics.csv: the per-level counts sum to the particles in all {len(diag)} rows "
          f"(last row {[int(diag[f'particles_l{lv}'][-1]) for lv in range(3)]})")
    problems, n, margin = [], 0, np.inf
    snaps = mt.snapshots(out)
    for _, path in snaps:
        k, m = check_snapshot(path, diag, problems)
        n, margin = n + k, min(margin, m)
    check(not problems and len(snaps) == 3,
          f"{len(snaps)} snapshots: /levels/0..2 with the level's spacing, an origin on its node "
          f"lattice, masks and m, v of matching shapes, own where the boxes put the level, the "
          f"particles' mass and momentum on the active nodes of all levels (1e-12); the particle "
          f"level of all {n} rows equal to the level of the position computed from the boxes "
          f"(nearest particle {margin:.1e} from a region face) and inside its level's own "
          f"mask; the counts "
          f"diagnostics.csv gives at the snapshot's step equal to the level field's"
          + "".join("\n     " + q for q in problems[:10]))
    problems = []
    nsnap = check_index(out, problems)
    check(not problems, f"grid.xmf: {nsnap} snapshots with blocks fluid_grid, fluid_grid_l1, "
          f"fluid_grid_l2 (m, v, active, own), every item the shape of its dataset; series.xmf "
          f"lists the particle level" + "".join("\n     " + q for q in problems[:10]))
    tool = subprocess.run([sys.executable, os.path.join(mt.SOURCE, "tools", "check_snapshot.py"),
                           out], capture_output=True, text=True)
    check(tool.returncode == 0, f"tools/check_snapshot.py accepts the refined folder "
          f"(exit {tool.returncode}){tool.stdout[-300:] if tool.returncode else ''}")
    timers = dict(np.genfromtxt(os.path.join(out, "timers.csv"), delimiter=",", names=True,
                                dtype=None, encoding=None)[["phase", "mean_s"]].tolist())
    check(timers.get("restrict", 0) > 0 and timers.get("prolong", 0) > 0,
          f"timers.csv: restrict {timers.get('restrict')} s, prolong {timers.get('prolong')} s")
    if shutil.which("pvpython"):
        check_paraview(out)
    else:
        print("info pvpython is not on the PATH: ParaView's readers not tried")
    # The unrefined strip: the columns and the layout as before, no level anywhere.
    plain, _ = run("refine_output_plain", case_text(2, 0.1, gas, "", extra=extra).replace(
        "interval = 0.05", "interval = 0.05\ngrid_fields = true"))
    with h5py.File(mt.snapshots(plain)[-1][1], "r") as f:
        top, fields = sorted(f.keys()), sorted(f["fluid"].keys())
    with open(os.path.join(plain, "grid.xmf")) as f:
        xmf = f.read()
    cols = list(diagnostics(plain).dtype.names)
    check(cols == DIAG_COLS and top == ["fluid", "grid", "xdmf"] and "level" not in fields
          and "levels" not in xmf and "_l1" not in xmf,
          f"unrefined: diagnostics.csv columns {len(cols)} as before, snapshot groups {top}, no "
          f"particle level, grid.xmf without levels")


if PART == "uniform":
    runs, dev = part_uniform()
    got = dev["refined"]
    # Roundoff: every particle keeps rho, p, v to a few ulps (1e-14 measured); 1e-10 leaves room
    # for the ~600 steps' accumulation and fails on any disturbance the box raises (the particle
    # pressure's quadrature gave 0.15, docs/refinement.md).
    check(got <= 1e-10, f"uniform gas across the box: deviation {got:.2e} at roundoff (<= 1e-10)"
          f" like the coarse twin's {dev['coarse']:.1e}")
    # The particles follow the levels: the count changed during the run (splits and merges) and
    # at every snapshot (t = 0, 0.7, 1.4) every particle has its level's size, but for the lag
    # at the faces the stream crosses, which split and merge cannot avoid (docs/refinement.md,
    # "Particles follow the levels"): both keep the centre of mass, so a parent or group whose
    # particles straddle a face leaves some on the wrong side. Children of a parent that has
    # just entered wait outside within s / 4 of the face; a fine particle that has just left
    # waits in its coarser slot for its partners (in this stream within H / 2 of the face), H =
    # level 0's particle spacing 0.05 / ppc. So: none beyond H of the region's boundary (merges
    # switched off leave whole fine columns downstream; at ppc 4, t = 1.4, one column of 56
    # waits 1.3e-4 past the right face). Level 1's region is the box snapped outwards to level-0
    # spans (centred on the nodes).
    out = runs["refined"][0]
    counts = set(diagnostics(out)["particles"].astype(int))
    H = 0.05 / PPC
    for t, path in mt.snapshots(out):
        p = mt.particles(path, "fluid")
        size = np.rint(np.log2((0.05 / PPC) ** 2 * p["rho"].ravel() / p["m"].ravel()) / 2)
        x, y = p["x"][:, 0], p["x"][:, 1]
        inside = (x > 0.775) & (x < 1.225) & (y > 0.125) & (y < 0.475)
        out_dist = np.hypot(np.maximum(np.maximum(0.775 - x, x - 1.225), 0),
                            np.maximum(np.maximum(0.125 - y, y - 0.475), 0))
        in_dist = np.minimum(np.minimum(x - 0.775, 1.225 - x), np.minimum(y - 0.125, 0.475 - y))
        dist = np.where(inside, in_dist, out_dist)
        wrong = size != inside
        far = int(np.sum(wrong & (dist > H)))
        lag = dist[wrong].max() / H if wrong.any() else 0.0
        check(len(counts) > 1 and far == 0, f"particles follow the levels: {len(counts)} "
              f"distinct particle counts in the run; at t = {p['time']:g}, {int(wrong.sum())} of "
              f"{len(size)} particles with another level's size, {far} of them beyond one "
              f"particle spacing H of a face (want 0; farthest {lag:.3f} H)")
    # Mass: the sum of ~1e4 particle masses of two sizes in another order after sorting:
    # n eps ~ 1e-12. Momentum: of the order of the twins' roundoff. Energy: measured 7e-15 (the
    # stream is steady); 1e-10 fails on a work-energy mismatch of the grid pressure, which grows
    # with the disturbance it creates (+0.2 % by t = 0.75 in the one met while building it).
    conservation(runs, 1e-12, 1e-12, 1e-10)
elif PART == "pulse":
    runs, frac = part_pulse()
    got = frac["refined"]
    check(got <= 1e-2, f"pulse: reflected energy fraction {got:.2e} <= 1e-2 (the issue's bar; "
          f"coarse twin {frac['coarse']:.1e}, fine {frac['fine']:.1e})")
    # Energy: measured 8.5e-14 (ppc 2) and 3.3e-13 (ppc 4); bs32's error on this smooth,
    # small pulse is far below its rtol (1e-6). 1e-10, as for the stream.
    conservation(runs, 1e-12, 1e-12, 1e-10)
elif PART == "uniform3d":
    part_uniform3d()
elif PART == "dynamic":
    part_dynamic()
elif PART == "restart":
    part_restart()
elif PART == "compression":
    part_compression()
elif PART == "vorticity":
    part_vorticity()
elif PART == "starvation":
    part_starvation()
elif PART == "ranks":
    part_ranks()
elif PART == "input":
    part_input()
elif PART == "periodic":
    part_periodic()
elif PART == "wrap":
    part_wrap()
elif PART == "identity":
    part_identity()
elif PART == "output":
    part_output()
elif PART == "refill":
    part_refill()
else:
    raise SystemExit(f"unknown part {PART}")
sys.exit(check.finish())
