"""Every class of bad input gives one error line naming the file, the line and the key,
exits with status 2, and starts nothing (no output folder appears).

Each case edits the valid ballistic2d.ini in one place, writes it to a temporary file and
runs `mpmfsi run` on it. The expected key and line are derived from the edit, not typed in.
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

BASE = open(mt.case("ballistic2d.ini")).read()
check = mt.Checks("test_bad_input")


def line_of(text, needle):
    for k, line in enumerate(text.splitlines(), 1):
        if needle in line:
            return k
    raise AssertionError(f"{needle!r} not in the case")


# (name, old text, new text, key expected in the message, extra words expected)
CASES = [
    ("unknown key", "dx = 0.1", "dx = 0.1\nshpae = quadratic", "grid.shpae", "grid.shape"),
    ("wrong type", "dx = 0.1", "dx = abc", "grid.dx", None),
    ("integer expected", "dim = 2", "dim = 2.5", "domain.dim", None),
    ("negative modulus", "E = 1e6", "E = -5", "solid.block.E", None),
    ("zero density", "density = 1000", "density = 0", "solid.block.density", None),
    ("Poisson ratio 0.5", "nu = 0.3", "nu = 0.5", "solid.block.nu", None),
    ("unstable CFL", "method = bs32", "method = bs32\ncfl = 1.5", "time.cfl", None),
    ("unknown method", "method = bs32", "method = rk99", "time.method", "bs32"),
    ("unknown material", "material = linear_elastic", "material = unobtainium",
     "solid.block.material", "linear_elastic"),
    ("box outside the domain", "hi = 1.0 2.5", "hi = 1.0 5.5", "solid.block.geometry", "domain"),
    ("domain not whole cells", "dx = 0.1", "dx = 0.3", "grid.dx", "whole number"),
    ("wrong vector length", "lo = 0 0\n", "lo = 0 0 0\n", "domain.lo", None),
    ("malformed line", "[physics]", "[physics]\nthis line has no equals sign", None, "syntax"),
    ("missing required key", "density = 1000\n", "", "[solid.block]", "'density'"),
    ("duplicate key", "dx = 0.1", "dx = 0.1\ndx = 0.2", "grid.dx", None),
    ("periodic on one face only", "velocity = 3 2",
     "velocity = 3 2\n\n[boundary]\nx_lo = periodic", "boundary.x_lo",
     "set both x_lo and x_hi to periodic"),
]


def expect_error(name, text, key, words, line, args=()):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "case.ini")
        with open(path, "w") as f:
            f.write(text)
        out = os.path.join(tmp, "out")
        p = mt.run(["run", path, f"output.dir={out}", "run.progress=false"] + list(args),
                   check=False)
        errors = [l for l in p.stderr.splitlines() if l.startswith("error:")]
        ok = p.returncode == 2 and len(errors) == 1 and not os.path.exists(out)
        msg = errors[0] if errors else p.stderr.strip().replace("\n", " | ")[:300]
        if ok and line is not None:
            ok = f"case.ini:{line}:" in msg
        if ok and key:
            ok = key in msg
        if ok and words:
            ok = words in msg
        check(ok, f"{name}: exit {p.returncode}: {msg}")


for name, old, new, key, words in CASES:
    assert old in BASE, old
    text = BASE.replace(old, new, 1)
    line = line_of(text, new.splitlines()[-1]) if new else None
    if name == "missing required key":
        line = None  # reported at the section, not at a line
    if name == "duplicate key":
        line = line_of(text, "dx = 0.2")
    if name == "box outside the domain":
        line = line_of(text, "geometry = block")
    expect_error(name, text, key, words, line)

# A body's initial stress (solid.NAME.initial_stress / initial_pressure), on the same case: the
# key and its line named, exit 2. The block is linear_elastic with E = 1e6 in 2-D.
ELASTIC = "nu = 0.3\n"
RIGID = BASE.replace("material = linear_elastic", "material = rigid").replace(
    "E = 1e6\n", "").replace(ELASTIC, "")
PRESTRESS_CASES = [
    ("initial_stress of the wrong size", BASE, "initial_stress = -1 0 -1", "initial_stress",
     "needs 4 values in a 2-D case"),
    ("initial_stress not symmetric", BASE, "initial_stress = -1 2 3 -1", "initial_stress",
     "must be symmetric"),
    ("initial_stress and initial_pressure", BASE,
     "initial_stress = -1 0 0 -1\ninitial_pressure = 1", "initial_pressure", "not both"),
    ("initial_pressure on a rigid body", RIGID, "initial_pressure = 5", "initial_pressure",
     "carries no stress"),
    ("initial_stress beyond j2's yield surface",
     BASE.replace("material = linear_elastic", "material = j2\nsigma_y = 1e3"),
     "initial_stress = 1e4 0 0 -1e4", "initial_stress", "yield surface"),
    ("a tension neo_hookean cannot reach (its stress saturates near 5e5 Pa)",
     BASE.replace("material = linear_elastic", "material = neo_hookean"),
     "initial_pressure = -1e7", "initial_pressure", "no elastic stretch gives it"),
]
for name, base, body, key, words in PRESTRESS_CASES:
    assert ELASTIC in base or base is RIGID
    text = base.replace("velocity = 3 2", "velocity = 3 2\n" + body, 1)
    expect_error(name, text, "solid.block." + key, words, line_of(text, body.splitlines()[-1]))

# Gas keys, on the valid cases/sod.ini run with an ERK pair (bs32), so that the checks of the
# pairs' rules apply (same form: one error with file:line and key, exit 2).
SOD = open(mt.case("sod.ini")).read()
assert "method = usl\n" in SOD, "cases/sod.ini no longer sets time.method = usl"
GAS = SOD.replace("method = usl\n", "method = bs32\n", 1)
GAS_CASES = [
    ("gamma not above 1", "\ngamma = 1.4", "\ngamma = 1.0", "fluid.gamma", "> 1"),
    ("negative gas density", "density = 0.125", "density = -0.125", "gas.right.density", "> 0"),
    ("zero gas pressure", "pressure = 0.1", "pressure = 0", "gas.right.pressure", "> 0"),
    ("negative artificial viscosity", "\ngamma = 1.4", "\ngamma = 1.4\nav_linear = -0.5",
     "fluid.av_linear", ">= 0"),
    ("unknown fluid key", "\ngamma = 1.4", "\ngamma = 1.4\ngama = 1.3", "fluid.gama",
     "fluid.gamma"),
    ("unknown gas key", "pressure = 0.1", "pressure = 0.1\npresure = 0.2", "gas.right.presure",
     "gas.right.pressure"),
    ("density and density_field", "density = 0.125", "density = 0.125\ndensity_field = 0.125",
     "gas.right.density_field", "not both"),
    ("density field not positive", "density = 0.125", "density_field = x - 0.75",
     "gas.right.density_field", "must be positive"),
    ("gas region outside the domain", "lo = 0.5 0\nhi = 1 0.0075", "lo = 0.5 0\nhi = 1.5 0.0075",
     "gas.right.geometry",
     "outside the domain"),
    ("negative regularise_every", "\ngamma = 1.4", "\ngamma = 1.4\nregularise_every = -30",
     "fluid.regularise_every", ">= 0"),
    ("negative refill_every", "\ngamma = 1.4", "\ngamma = 1.4\nrefill_every = -1",
     "fluid.refill_every", ">= 0"),
    ("refill_every with refill off", "\ngamma = 1.4",
     "\ngamma = 1.4\nrefill = false\nrefill_every = 1", "fluid.refill_every", "remove one"),
    ("merge_light above its range", "\ngamma = 1.4",
     "\ngamma = 1.4\nregularise_every = 30\nmerge_light = 0.6", "fluid.merge_light", "[0, 0.5]"),
    ("merge_light without regularisation or refill", "\ngamma = 1.4",
     "\ngamma = 1.4\nrefill_holes = false\nmerge_light = 0.125", "fluid.merge_light",
     "regularise_every"),
    ("empty_node_mass above its range", "\ngamma = 1.4",
     "\ngamma = 1.4\nempty_node_mass = 0.5", "fluid.empty_node_mass", "[0, 0.01]"),
    ("light_node_mass above its range", "\ngamma = 1.4",
     "\ngamma = 1.4\nlight_node_mass = 0.8", "fluid.light_node_mass", "[0, 0.5]"),
    ("shift above its range", "\ngamma = 1.4", "\ngamma = 1.4\nshift = 0.8", "fluid.shift",
     "[0, 0.5]"),
    ("unknown strain_rate", "\ngamma = 1.4", "\ngamma = 1.4\nstrain_rate = now",
     "fluid.strain_rate", "current|lagged"),
    ("negative shift_expansion", "\ngamma = 1.4",
     "\ngamma = 1.4\nshift = 0.1\nshift_expansion = -1", "fluid.shift_expansion", ">= 0"),
    ("shift_every below 1", "\ngamma = 1.4", "\ngamma = 1.4\nshift = 0.1\nshift_every = 0",
     "fluid.shift_every", ">= 1"),
    ("regularise_min not below regularise_max", "\ngamma = 1.4",
     "\ngamma = 1.4\nregularise_min = 8\nregularise_max = 8", "fluid.regularise_max",
     "must be below"),
    ("regularise_min above the default max", "\ngamma = 1.4", "\ngamma = 1.4\nregularise_min = 20",
     "fluid.regularise_min", "regularise_max = 16"),
    ("open face without [freestream]", "x_hi = slip", "x_hi = outflow", "boundary.x_hi",
     "[freestream]"),
    ("APIC with an ERK pair", "pressure = 0.1", "pressure = 0.1\n\n[transfer]\nvelocity = apic",
     "transfer.velocity", "classic update"),
]
for name, old, new, key, words in GAS_CASES:
    assert old in GAS, old
    text = GAS.replace(old, new, 1) if old != "pressure = 0.1" or "[transfer]" not in new else \
        GAS.rstrip("\n").rsplit(old, 1)[0] + new + "\n"
    line = line_of(text, new.splitlines()[-1])
    if name == "gas region outside the domain":
        line = line_of(text, "geometry = right")
    expect_error(name, text, key, words, line)
# The strain rate of the viscosity is a choice of the ERK pairs only.
text = GAS.replace("method = bs32", "method = usl", 1).replace(
    "\ngamma = 1.4", "\ngamma = 1.4\nstrain_rate = lagged", 1)
expect_error("strain_rate with the classic update", text, "fluid.strain_rate", "ERK pairs only",
             line_of(text, "strain_rate = lagged"))
# An obstacle in a scene without gas (it would do nothing).
lone = BASE + "\n[obstacle.post]\nshape = box\nlo = 0.2 0.2\nhi = 0.4 0.4\n"
expect_error("obstacle without gas", lone, "obstacle.post.shape", "no [gas.NAME]",
             line_of(lone, "shape = box"))
# An inflow face through which the free stream leaves.
inflow = GAS.replace("x_hi = slip", "x_hi = inflow") + \
    "\n[freestream]\ndensity = 1\npressure = 1\nvelocity = 1 0\n"
expect_error("inflow face the free stream leaves", inflow, "boundary.x_hi", "does not enter",
             line_of(inflow, "x_hi = inflow"))
# A gas section without its density (reported within the section), and a scene with neither
# bodies nor gas (naming the sections to add).
expect_error("gas without density", GAS.replace("density = 0.125\n", ""), "gas.right.density",
             "density_field", None)
expect_error("empty scene", GAS[:GAS.index("[gas.left]")], None, "add a [solid.NAME] or a "
             "[gas.NAME] section", None)

# Overrides on the command line are named as such.
expect_error("bad override", BASE, "grid.dx", "command line", None, ["grid.dx=-1"])
expect_error("malformed override", BASE, None, "command line", None, ["grid.dx"])

# A polygon file that does not exist.
poly = BASE.replace("type = box\nlo = 0.5 2.0\nhi = 1.0 2.5",
                    "type = polygon\nfile = no_such_vertices.csv")
expect_error("missing polygon file", poly, "geometry.block.file", None,
             line_of(poly, "no_such_vertices"))

# A missing case file.
p = mt.run(["run", "/nonexistent/case.ini"], check=False)
errors = [l for l in p.stderr.splitlines() if l.startswith("error:")]
check(p.returncode == 2 and len(errors) == 1 and "/nonexistent/case.ini" in errors[0],
      f"missing case file: exit {p.returncode}: {errors[0] if errors else p.stderr.strip()}")

# `check` on a good case prints a resolved configuration that reads back identically.
with tempfile.TemporaryDirectory() as tmp:
    p = mt.run(["check", mt.case("ballistic2d.ini")])
    path = os.path.join(tmp, "resolved.ini")
    with open(path, "w") as f:
        f.write(p.stdout)
    q = mt.run(["check", path])
    strip = lambda s: re.sub(r"\s*#.*", "", s).strip()
    check(strip(p.stdout) == strip(q.stdout) and "t_end = 0.3" in p.stdout,
          "check: the resolved configuration reads back to itself")


# Obstacles: the same rules on cases/gas_obstacles.ini (their keys are read with the gas).
OBST = open(mt.case("gas_obstacles.ini")).read()
OBST_CASES = [
    ("unknown obstacle shape", "shape = circle", "shape = blob", "obstacle.cylinder.shape",
     "circle"),
    ("negative radius", "radius = 0.12", "radius = -0.12", "obstacle.cylinder.radius", None),
    ("polygon with 2 vertices", "shape = box\nlo = 0.8 0.15\nhi = 0.9 0.35",
     "shape = polygon\nvertices = 0.8 0.15 0.9 0.15", "obstacle.block.vertices", "3 vertices"),
    ("self-crossing polygon", "shape = box\nlo = 0.8 0.15\nhi = 0.9 0.35",
     "shape = polygon\nvertices = 0.8 0.15 0.9 0.35 0.9 0.15 0.8 0.35",
     "obstacle.block.vertices", "crosses itself"),
    ("missing aerofoil file", "shape = box\nlo = 0.8 0.15\nhi = 0.9 0.35",
     "shape = airfoil\nchord = 0.1\nleading_edge = 0.7 0.2\nfile = no_such_file.csv",
     "obstacle.block.file", None),
    ("obstacle outside the domain", "center = 0.55 0.5", "center = 1.55 0.5",
     "obstacle.cylinder.shape", "outside the domain"),
    ("reference area without speed", "reference_speed = 1\n", "", "obstacle.cylinder.reference_area",
     "reference_speed"),
    ("key the shape does not use", "radius = 0.12", "radius = 0.12\nlo = 0.01 0.01",
     "obstacle.cylinder.lo", "not used"),
]
for name, old, new, key, words in OBST_CASES:
    assert old in OBST, old
    text = OBST.replace(old, new, 1)
    needle = {"obstacle outside the domain": "shape = circle",
              "reference area without speed": "reference_area"}.get(name) or new.splitlines()[-1]
    expect_error(name, text, key, words, line_of(text, needle))

# The wall treatment's keys (fluid/fluid_wall_ls.c).
LS = "\n[fluid]\nwall_treatment = least_squares\n"
text = OBST.replace("method = usl", "method = bs32", 1) + LS
expect_error("least_squares with an ERK pair", text, "fluid.wall_treatment", "classic update",
             line_of(text, "wall_treatment"))
text = SOD + LS
expect_error("least_squares without an obstacle", text, "fluid.wall_treatment", "has neither",
             line_of(text, "wall_treatment"))
for name, key_line, key in (("wall band 0", "wall_band = 0", "fluid.wall_band"),
                            ("wall blend -1", "wall_blend = -1", "fluid.wall_blend"),
                            ("wall fit order 2", "wall_fit_order = 2", "fluid.wall_fit_order")):
    text = OBST + LS + key_line + "\n"
    expect_error(name, text, key, None, line_of(text, key_line))

# The surface pressure output (fluid/fluid_surface.h): vertices of a 2-D outline only; Cp needs
# the reference values.
POLY = ("\n[obstacle.tri]\nshape = polygon\nvertices = 0.2 0.7 0.3 0.7 0.25 0.8\n")
for name, text, needle, key, words in (
        ("surface output of a circle", OBST.replace("radius = 0.12", "radius = 0.12\n"
                                                     "surface_interval = 0.1", 1),
         "surface_interval", "obstacle.cylinder.surface_interval", "polygon, wedge or airfoil"),
        ("reference_pressure without surface output", OBST + POLY + "reference_pressure = 1\n",
         "reference_pressure", "obstacle.tri.reference_pressure", "set surface_interval"),
        ("Cp without a reference area", OBST + POLY + "surface_interval = 0.1\n"
                                                      "reference_pressure = 1\n",
         "reference_pressure", "obstacle.tri.reference_pressure", "reference_area"),
        ("a surface interval of 0", OBST + POLY + "surface_interval = 0\n", "surface_interval",
         "obstacle.tri.surface_interval", None)):
    expect_error(name, text, key, words, line_of(text, needle))

# Coupling, on gas_obstacles.ini with a solid block added, cut out of the gas (a solid overlapping
# the gas is an error of its own: test_scene).
SOLID = ("\n[geometry.plate]\ntype = box\nlo = {lo}\nhi = {hi}\n\n[solid.plate]\ngeometry = plate\n"
         "material = linear_elastic\ndensity = 10\nE = 100\nnu = 0.3\n")
FSI = OBST.replace("[gas.air]\ngeometry = all", "[geometry.around]\ntype = difference\n"
                   "of = all plate\n\n[gas.air]\ngeometry = around", 1) + \
    SOLID.format(lo="0.1 0.8", hi="0.2 0.9")
COUPLING_CASES = [
    ("unknown coupling scheme", FSI, "scheme = veloctiy", "coupling.scheme", "did you mean 'velocity'"),
    ("negative friction", FSI, "scheme = contact\nfriction = -0.1", "coupling.friction", ">= 0"),
    ("friction with another scheme", FSI, "scheme = velocity\nfriction = 0.2", "coupling.friction",
     "key of the contact scheme"),
    ("coupling keys in a gas-only scene", OBST, "scheme = traction", "coupling.scheme",
     "nothing to couple"),
    ("coupling keys in a solid-only scene", BASE, "scheme = contact", "coupling.scheme",
     "nothing to couple"),
    ("unknown time scheme", FSI, "time = stagered", "coupling.time", "did you mean 'staggered'"),
    ("staggered in a gas-only scene", OBST, "time = staggered", "coupling.time",
     "has no effect"),
    ("order of another time scheme", FSI, "order = gas_first", "coupling.order",
     "key of the staggered time scheme"),
    ("unknown staggered order", FSI, "time = staggered\norder = fluid_first", "coupling.order",
     "gas_first"),
    ("no substeps", FSI, "time = multirate\nsubsteps = 0", "coupling.substeps", ">= 1"),
    ("substeps with another time scheme", FSI, "time = staggered\nsubsteps = 4",
     "coupling.substeps", "key of the multirate time scheme"),
    ("iterations without a tolerance", FSI, "time = staggered\niterations = 5",
     "coupling.iterations", "give coupling.tolerance"),
    ("iterations of the parallel order", FSI, "time = staggered\norder = parallel\ntolerance = "
     "1e-6\niterations = 5", "coupling.iterations", "solid_first only"),
    ("a tolerance without iterations", FSI, "time = staggered\ntolerance = 1e-6",
     "coupling.tolerance", "coupling.iterations is 1"),
    ("a negative tolerance", FSI, "time = staggered\niterations = 5\ntolerance = -1",
     "coupling.tolerance", "must be in (0, 1]"),
    ("iterations with multirate", FSI, "time = multirate\niterations = 5",
     "coupling.iterations", "key of the staggered time scheme"),
    ("negative slow substeps", FSI, "time = multirate\nslow_substeps = -1",
     "coupling.slow_substeps", "must be in [0, 10000]"),
    ("slow substeps with another time scheme", FSI, "time = staggered\nslow_substeps = 0",
     "coupling.slow_substeps", "key of the multirate time scheme"),
]
# sharp: usl, musl or an ERK pair (whose RHS relaxes the phases' own velocities), monolithic or
# multirate (staggered is not measured).
COUPLING_CASES += [
    ("sharp with euler", FSI.replace("method = usl", "method = euler", 1), "scheme = sharp",
     "coupling.scheme", "get no relaxation"),
    ("sharp with staggered", FSI, "scheme = sharp\ntime = staggered", "coupling.time",
     "monolithic and multirate only"),
]
for name, base, body, key, words in COUPLING_CASES:
    text = base.rstrip("\n") + "\n\n[coupling]\n" + body + "\n"
    expect_error(name, text, key, words, line_of(text, body.splitlines()[-1]))
# A staggered scheme with an adaptive pair: the error names time.method, on its own line.
text = FSI.replace("method = usl", "method = bs32", 1) + "\n[coupling]\ntime = staggered\n"
expect_error("staggered with an adaptive pair", text, "time.method", "classic update",
             line_of(text, "method = bs32"))
# Multirate with an ERK pair is MRIStep, fixed steps only: an adaptive pair is an error naming
# time.adaptive; coupling.load is the classic form's, coupling.mri_table MRIStep's.
ERK = FSI.replace("method = usl", "method = bs32", 1)
text = ERK + "\n[coupling]\ntime = multirate\n"
expect_error("multirate with an adaptive pair", text, "time.adaptive", "fixed steps", None)
for name, base, body, key, words in (
        ("coupling.load with MRIStep", ERK.replace("method = bs32", "method = bs32\nadaptive = false"),
         "time = multirate\nload = interpolated", "coupling.load", "classic update only"),
        ("coupling.slow_substeps with MRIStep",
         ERK.replace("method = bs32", "method = bs32\nadaptive = false"),
         "time = multirate\nslow_substeps = 0", "coupling.slow_substeps", "classic update only"),
        ("coupling.mri_table with the classic update", FSI,
         "time = multirate\nmri_table = mis_kw3", "coupling.mri_table", "ERK pair only"),
        ("unknown MRI table", FSI, "time = multirate\nmri_table = erk33", "coupling.mri_table",
         "mri_gark_erk33a")):
    text = base.rstrip("\n") + "\n\n[coupling]\n" + body + "\n"
    expect_error(name, text, key, words, line_of(text, body.splitlines()[-1]))
# A solid inside a static obstacle of the gas (obstacle block spans 0.8-0.9 x 0.15-0.35).
text = OBST + SOLID.format(lo="0.82 0.2", hi="0.88 0.3")
expect_error("solid overlapping a static obstacle", text, "obstacle.block.shape",
             "must not overlap a static obstacle", line_of(text, "shape = box"))

# physics.gauge_pressure: walls and periodic faces only, the particles' pressure, a gas present.
GAUGE = "\n[physics]\ngauge_pressure = 1\n"
OPEN = SOD.replace("x_hi = slip", "x_hi = outflow", 1) + \
    "\n[freestream]\ndensity = 1\npressure = 1\nvelocity = 0 0\n"
for name, text, words, args in (
        ("gauge with an open face", OPEN + GAUGE, "open face (boundary.x_hi)", ()),
        ("gauge with static obstacles", OBST + GAUGE, "static obstacles", ()),
        ("gauge with the least-squares wall", SOD + GAUGE, "least_squares",
         ("fluid.wall_treatment=least_squares",)),
        ("gauge with refinement", SOD + GAUGE, "refinement levels", ("refine.levels=2",)),
        ("gauge with the hybrid pressure", GAS + GAUGE, "takes no gauge",
         ("fluid.pressure=hybrid",)),
        ("gauge without a gas", BASE.replace("gravity = 0 -9.81", "gravity = 0 -9.81\n"
                                             "gauge_pressure = 1", 1), "no gas", ()),
        ("negative gauge", SOD + GAUGE.replace("= 1", "= -1"), ">= 0", ())):
    expect_error(name, text, "physics.gauge_pressure", words,
                 line_of(text, "gauge_pressure ="), args)

sys.exit(check.finish())
