"""Surface tractions ([traction.NAME] geometry, value): each particle of a deformable body
inside the region at seeding carries the force t h^(dim-1), h = dx / ppc.

(i) Quasi-static bar, cases/traction_bar.ini: L = 25, E = 100, rho = 1, nu = 0, no-slip wall
    at x = 0, t = 0.01 Pa on the last particle column (X = 24.75), damping critical for the
    first mode, classic update to t = 25 s (about 16 first-mode time constants). Static
    solution u = t X / E, sigma_xx = t (the small-strain model's O(strain) term is 1e-4).
    - Tip column displacement against t X_tip / E within 1 % (the traction acts at the
      particles, h/2 inside the end, and the last cell carries a boundary layer of the
      point-like load; measured +0.38 %), and against t L / E within 1.5 % (the column sits
      at L - h/2, 1 % short of L; measured -0.62 %).
    - sigma_xx = E (F_xx - 1) = t within 0.5 % for every particle more than two cells from
      the wall and six from the loaded end (measured 0.054 %). The load acts at the particle
      centres, h/2 inside the end, and leaves a boundary layer in which every other column
      (X = k + 1/4) is off, decaying about threefold per cell: 33 %, 11 %, 3.6 %, 1.2 %,
      0.41 % at 0.75, 1.75, ..., 4.75 from the end (printed, not checked); the resultant and
      so the tip displacement are right.
    - Settled: the tip displacement changes by less than 1e-4 relative from t = 20 to 25.
    bs32 is not used here: with it the particles of the last cells keep a slow oscillation
    (about 1 % of the tip displacement, period about 16 s) that the mass-proportional damping
    does not remove.
(ii) The total applied force is t times the loaded area to roundoff (1e-14 relative): summed
    over the particles' fext at t = 0, in 2-D (bar end, area 2 per unit depth), on 1 and 2
    ranks, and in 3-D (a free block's top face, 1 x 0.5, traction (1, 2, 3)). For free blocks
    in 2-D and 3-D (no walls, no gravity) the momentum of diagnostics.csv grows at exactly the
    total force: |p(t) - F t| <= 1e-12 |F t| (P2G's weights sum to one and the internal
    forces to zero; only roundoff remains); the 3-D block with bs32, the 2-D one with the
    classic update.
A restart at t = 2 continued to 4 ends bitwise where a straight run does.
(iii) Bad input, one error line naming file:line and the key, exit 2: a traction region that
    holds no particle; one two particle layers deep; one on a rigid body only; a value with
    the wrong number of components.
"""
import csv
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_traction")
T, E, L = 0.01, 100.0, 25.0


def quasi_static():
    out = mt.outdir("traction_bar")
    mt.run(["run", mt.case("traction_bar.ini"), f"output.dir={out}", "run.progress=false"])
    snaps = mt.snapshots(out)
    p0 = mt.particles(snaps[0][1])
    X = p0["x"]
    tip = X[:, 0] == X[:, 0].max()
    u = {t: (mt.particles(path)["x"] - X)[tip, 0].mean() for t, path in snaps}
    final = mt.particles(snaps[-1][1])
    utip = u[snaps[-1][0]]
    rel_x = utip / (T * X[tip, 0][0] / E) - 1
    rel_l = utip / (T * L / E) - 1
    check(abs(rel_x) < 0.01, f"tip column (X = {X[tip, 0][0]}) u = {utip:.6e}, t X / E = "
          f"{T * X[tip, 0][0] / E:.6e}: {100 * rel_x:+.3f} % (tolerance 1 %)")
    check(abs(rel_l) < 0.015, f"tip u against t L / E = {T * L / E:.6e}: {100 * rel_l:+.3f} % "
          "(tolerance 1.5 %)")
    sig = E * (final["F"][:, 0] - 1.0)
    inner = (X[:, 0] > 2.0) & (X[:, 0] < L - 6.0)
    err = float(np.abs(sig[inner] / T - 1).max())
    check(err < 5e-3, f"sigma_xx = t within {100 * err:.3f} % over {inner.sum()} interior "
          "particles (tolerance 0.5 %)")
    cols = np.unique(X[:, 0])[-10::2]
    print("info sigma_xx / t - 1 near the loaded end: " + ", ".join(
        f"X = {x}: {100 * (sig[X[:, 0] == x].mean() / T - 1):+.2f} %" for x in cols))
    change = abs(u[snaps[-1][0]] / u[20.0] - 1)
    check(change < 1e-4, f"settled: tip u changed by {change:.1e} from t = 20 to 25 "
          "(tolerance 1e-4)")


def total_force(out, expect, label):
    p = mt.particles(mt.snapshots(out)[0][1])
    f = p["fext"].sum(axis=0)
    n = int((np.abs(p["fext"]).sum(axis=1) > 0).sum())
    err = float(np.abs(f - expect).max() / np.abs(expect).max())
    check(err <= 1e-14, f"{label}: sum of fext over {n} particles {np.array2string(f)} = t A "
          f"{np.array2string(np.array(expect))} to {err:.1e} (tolerance 1e-14)")


def momentum_growth(out, force, label):
    with open(os.path.join(out, "diagnostics.csv")) as fh:
        rows = list(csv.DictReader(fh))
    worst = 0.0
    for r in rows[1:]:
        t = float(r["t"])
        p = np.array([float(r[k]) for k in ("px", "py", "pz")[:len(force)]])
        worst = max(worst, float(np.abs(p - np.array(force) * t).max()
                                 / (np.abs(force).max() * t)))
    check(worst <= 1e-12, f"{label}: momentum = F t over {len(rows) - 1} steps to {worst:.1e} "
          "relative (tolerance 1e-12)")


BLOCK3 = """[domain]
dim = 3
lo = 0 0 0
hi = 2 2 2
[grid]
dx = 0.25
[time]
t_end = 0.02
method = bs32
[output]
interval = 0.02
[geometry.block]
type = box
lo = 0.5 0.5 0.5
hi = 1.5 1.0 1.5
[geometry.top]
type = box
lo = 0.4 0.4 1.4
hi = 1.6 1.1 1.5
[solid.block]
geometry = block
material = neo_hookean
density = 100
E = 1e5
nu = 0.3
[traction.top]
geometry = top
value = 1 2 3
"""

BLOCK2 = """[domain]
dim = 2
lo = 0 0
hi = 2 2
[grid]
dx = 0.25
[time]
t_end = 0.02
method = usl
[output]
interval = 0.02
[geometry.block]
type = box
lo = 0.5 0.5
hi = 1.5 1.0
[geometry.right]
type = box
lo = 1.4 0.4
hi = 1.6 1.1
[solid.block]
geometry = block
material = stvk
density = 100
E = 1e5
nu = 0.3
ppc = 3
[traction.right]
geometry = right
value = -3 1
"""


def run_text(text, name, ranks=1, extra=()):
    tmp = tempfile.mkdtemp(prefix=name + "_", dir=".")
    path = os.path.join(tmp, "case.ini")
    with open(path, "w") as f:
        f.write(text)
    out = os.path.join(tmp, "out")
    mt.run(["run", path, f"output.dir={out}", "run.progress=false"] + list(extra), ranks)
    return out


def forces():
    for ranks in (1, 2):
        out = mt.outdir(f"traction_force_np{ranks}")
        mt.run(["run", mt.case("traction_bar.ini"), f"output.dir={out}", "time.t_end=0.5",
                "run.progress=false"], ranks)
        total_force(out, [T * 2.0, 0.0], f"2-D bar end, {ranks} rank{'s' if ranks > 1 else ''}")
    # 3-D: top face 1 x 0.5; 2-D: right face, height 0.5 per unit depth (ppc 3)
    out = run_text(BLOCK3, "traction3d")
    total_force(out, [1.0 * 0.5, 2.0 * 0.5, 3.0 * 0.5], "3-D block top face")
    momentum_growth(out, [0.5, 1.0, 1.5], "3-D free block")
    out = run_text(BLOCK2, "traction2d")
    total_force(out, [-3.0 * 0.5, 1.0 * 0.5], "2-D block right face, ppc 3")
    momentum_growth(out, [-1.5, 0.5], "2-D free block")


def bad_input():
    base = open(mt.case("traction_bar.ini")).read()
    region = "[geometry.end]\ntype = box\nlo = 24.6 0\nhi = 25 2\n"
    assert region in base
    push = open(mt.case("rigid_push.ini")).read()
    cases = [
        ("region holding no particle",
         base.replace(region, "[geometry.end]\ntype = box\nlo = 25.5 0\nhi = 26 2\n"),
         "traction.end.geometry", "geometry = end", "no particle"),
        ("region two particle layers deep",
         base.replace(region, "[geometry.end]\ntype = box\nlo = 24.1 0\nhi = 25 2\n"),
         "traction.end.geometry", "geometry = end", "not on its body's surface"),
        ("value with 3 components in 2-D", base.replace("value = 0.01 0", "value = 1 0 0"),
         "traction.end.value", "value = 1 0 0", "needs 2 values"),
        ("region on a rigid body only", push + "\n[traction.p]\ngeometry = piston\nvalue = 1 0\n",
         "traction.p.geometry", "geometry = piston", "no particle of a deformable"),
    ]
    for name, text, key, prefix, words in cases:
        mt.expect_input_error(check, name, text, key, mt.line_starting(text, prefix), words)


def restart():
    same, worst, fields = mt.restart_difference(mt.case("traction_bar.ini"), [], 4.0,
                                                "traction_restart")
    check(same and worst == 0.0, f"restart at t = 2 and continue to 4 vs a straight run: "
          f"{', '.join(fields)} differ by {worst:.1e} (bitwise: fext comes back from the "
          "checkpoint)")


quasi_static()
forces()
restart()
bad_input()
sys.exit(check.finish())
