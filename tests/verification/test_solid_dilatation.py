"""The projected dilatation, solid.NAME.dilatation = projected (solid/solid_dilatation.c): each
particle's tr L replaced by its volume-weighted projection onto the grid's nodes, interpolated
back; the deviatoric part of L stays the particle's own.

Checks:
1. Exact where tr L is uniform: a free block expanding homogeneously (v = a (x - x_c), a = 0.01
   /s, E so small that its stress does not move it in 10 steps): the particles at least 8 cells
   inside the block end with the same F as without the projection, to 1e-12 relative to
   |F - I| (measured 0: the projection is a ratio of two sums of O(30) terms whose roundoff
   stays far below the bound), under usl and bs32. Why 8: P2G of a linear field is not linear at the nodes within 1.5 cells of the
   edge, so tr L is not uniform within 3 cells of it, and the projection reaches 3 cells further
   (node and particle supports); measured, the difference is 1.5e-3, 4e-8, 7e-10 and 9e-13 of
   |F - I| beyond 3, 5, 6 and 7 cells, and 0 beyond 8 (the tail falls by 1e3 a cell). The block's
   edge, where MPM's P2G of a linear field is not linear, must differ (> 1e-6 of |F - I|): the
   projection acted.
   A twin block beside it that does not project ends bit for bit as without the key (the
   projecting body's particles are a list of its own).
2. At rest: the pre-stressed slab between gas columns at its pressure (cases/fsi_prestress.ini,
   the test_prestress scene) stays at rest with the projection, under usl and bs32: every
   particle's speed below 1e-10 c_g over 1,000 steps (the bound and its reason as in
   test_prestress: roundoff of node-by-node cancelling forces).
3. 2 ranks against 1: the axial bar (cases/axial_bar.ini, nu = 0.3 so that the projection
   changes the motion) across the rank boundary, every field by particle id to 1e-12.
4. Bad input, one line naming file, line and key, exit 2: a value not in the list; a rigid body
   (nothing deforms); a refinement hierarchy (the projection deposits on level 0's nodes).

What it buys and costs is measured elsewhere: the soft slab's ringing
(test_fsi_reflection long, the `fbar` variants) and the bending of a 3-D cantilever (docs/solid.md).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_solid_dilatation")
TOL_F, TOL_REST, TOL_RANKS = 1e-12, 1e-10, 1e-12

SCENE = """[run]
name = expanding_block
[domain]
dim = 2
lo = -1 -1
hi = 6.2 3.4
[grid]
dx = 0.1
shape = quadratic
[time]
t_end = 0.1
dt_max = 0.01
method = {method}
[output]
interval = 0.1
"""
# A block 24 cells square expanding about its centre xc (E so small that nothing else moves it).
BODY = """[geometry.{name}]
type = box
lo = {lo} 0
hi = {hi} 2.4
[solid.{name}]
geometry = {name}
material = linear_elastic
density = 1
E = 1e-12
nu = 0.3
velocity_field = 0.01*(x - {xc}); 0.01*(y - 1.2)
ppc = 2
"""
BLOCK = (SCENE + BODY.format(name="block", lo=0, hi=2.4, xc=1.2) + "{extra}\n"
         + BODY.format(name="twin", lo=2.8, hi=5.2, xc=4.0))


def final_F(method, extra):
    out = mt.run_text(f"block_{method}", BLOCK.format(method=method, extra=extra))
    p = mt.particles(mt.snapshots(out)[-1][1])
    return p["x"], p["F"], p["body"].reshape(-1)


for method in ("usl", "bs32"):
    x, F0, body = final_F(method, "")
    _, F1, _ = final_F(method, "dilatation = projected")
    I = np.eye(2).reshape(-1)
    scale = float(np.abs(F0 - I).max())
    block = body == 0
    inner = block & np.all((x > 0.8) & (x < 1.6), axis=1)
    d_in = float(np.abs(F1[inner] - F0[inner]).max()) / scale
    d_edge = float(np.abs(F1[block] - F0[block]).max()) / scale
    check(d_in <= TOL_F and d_edge > 1e-6,
          f"{method}: uniform dilatation: F of the {int(inner.sum())} particles 8 cells inside "
          f"the block the same with the projection to {d_in:.1e} of |F - I| = {scale:.2e} "
          f"(<= {TOL_F:g}); at the edge it differs by {d_edge:.1e} (> 1e-6: the projection acted)")
    same = np.array_equal(F1[~block], F0[~block])
    check(same, f"{method}: the twin block, which does not project, ends with the same F bit for "
          f"bit ({int((~block).sum())} particles)")

C_GAS = 1.4 ** 0.5
PRESTRESS = mt.case("fsi_prestress.ini")
for method in ("usl", "bs32"):
    out = mt.outdir(f"prestress_{method}")
    mt.run(["run", PRESTRESS, f"output.dir={out}", "run.progress=false",
            f"time.method={method}", "solid.slab.dilatation=projected"])
    d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
    snaps = mt.snapshots(out)
    m_min = min(mt.particles(snaps[0][1])["m"].min(),
                mt.particles(snaps[0][1], "fluid")["m"].min())
    speed = float(np.sqrt(2 * d["kinetic"].max() / m_min)) / C_GAS
    check(speed <= TOL_REST, f"{method}: pre-stressed slab at rest with the projection over "
          f"{int(d['step'][-1])} steps: speed <= {speed:.1e} c_g (<= {TOL_REST:g})")

mt.check_ranks_agree(check, mt.case("axial_bar.ini"),
                     ["time.t_end=2.5", "time.method=usl", "solid.bar.nu=0.3",
                      "solid.bar.dilatation=projected"], "axial_projected", tol=TOL_RANKS)

BAR = open(mt.case("axial_bar.ini")).read()
bad = BAR + "dilatation = smoothed\n"
mt.expect_input_error(check, "a value not in the list", bad, "solid.bar.dilatation",
                      mt.line_starting(bad, "dilatation"))
RIGID = (BAR.split("[solid.bar]")[0] + "[solid.bar]\ngeometry = bar\nmaterial = rigid\n"
         "density = 1\ndilatation = projected\n")
mt.expect_input_error(check, "a rigid body", RIGID, "solid.bar.dilatation",
                      mt.line_starting(RIGID, "dilatation"), "rigid")
REFINED = (BAR + "dilatation = projected\n[refine]\nlevels = 2\n[refine.box]\nlevel = 1\n"
           "lo = 5 0\nhi = 15 2\n")
mt.expect_input_error(check, "a refinement hierarchy", REFINED, "solid.bar.dilatation",
                      mt.line_starting(REFINED, "dilatation"), "refine")

sys.exit(check.finish())
