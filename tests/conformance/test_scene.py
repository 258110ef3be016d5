"""Scene errors: bodies that share space, and coupling keys in a scene with one phase.

1. A solid overlapping the gas or another solid is refused by `check` and `run` (exit 2, one
   error line at the first body's geometry key naming both sections and the second's line, and
   no output folder), on 1 and 2 ranks with the same line. Bodies that only touch (faces on a
   grid line, a face through a row of particles, the gas cut around the solid) are accepted.
2. Any [coupling] key given in a scene with only solids or only gas is refused naming the key,
   also at its default value and from the command line.

Small generated cases (dx = 0.05): the whole driver runs in a few seconds.
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_scene")

HEAD = """[domain]
dim = 2
lo = 0 0
hi = 1 0.5

[grid]
dx = 0.05

[time]
t_end = 1e-4
"""


def box(name, lo, hi):
    return f"\n[geometry.{name}]\ntype = box\nlo = {lo}\nhi = {hi}\n"


def solid(name, geom):
    return (f"\n[solid.{name}]\ngeometry = {geom}\nmaterial = linear_elastic\ndensity = 1000\n"
            "E = 1e6\nnu = 0.3\n")


def gas(name, geom):
    return f"\n[gas.{name}]\ngeometry = {geom}\ndensity = 1\npressure = 1e5\nvelocity = 0 0\n"


def line_of(text, needle):
    return [k for k, l in enumerate(text.splitlines(), 1) if l.strip() == needle][0]


def errors(p):
    return [l for l in p.stderr.splitlines() if l.startswith("error:")]


def run(cmd, text, args=(), ranks=1):
    """mpmfsi CMD on the case text; (process, whether an output folder appeared)."""
    with tempfile.TemporaryDirectory(dir=".") as tmp:
        path = os.path.join(tmp, "case.ini")
        with open(path, "w") as f:
            f.write(text)
        out = os.path.join(tmp, "out")
        p = mt.run([cmd, path, f"output.dir={out}", "run.progress=false"] + list(args),
                   ranks=ranks, check=False)
        return p, os.path.exists(out)


def refused(name, text, key, line, words, args=()):
    """check and run on 1 rank, run on 2: exit 2, one error line at case.ini:LINE with key and
    words, no output folder, the same line everywhere."""
    lines = []
    for cmd, ranks, extra in (("check", 1, []), ("run", 1, []), ("run", 2, ["grid.ranks=2 1"])):
        p, made = run(cmd, text, list(args) + extra, ranks)
        e = errors(p)
        ok = (p.returncode == 2 and len(e) == 1 and f"case.ini:{line}: {key}" in e[0]
              and all(w in e[0] for w in words) and not made)
        check(ok, f"{name}, {cmd} on {ranks} rank(s): exit {p.returncode}: "
                  f"{e[0] if e else p.stderr.strip()[-300:]}")
        lines.append(re.sub(r"\S*case\.ini", "case.ini", e[0]) if e else None)
    check(len(set(lines)) == 1, f"{name}: the same line from check, run and 2 ranks")


def accepted(name, text, args=(), ranks=1):
    p, _ = run("check", text, args, ranks)
    check(p.returncode == 0,
          f"{name}: check exit {p.returncode} {p.stderr.strip()[-300:] if p.returncode else ''}")


# 1. Overlaps.
text = HEAD + box("all", "0 0", "1 0.5") + box("block", "0.4 0.1", "0.6 0.3") + \
    gas("air", "all") + solid("block", "block")
refused("a solid inside the gas", text, "solid.block.geometry",
        line_of(text, "geometry = block"),
        ["[solid.block] overlaps [gas.air]", f"case.ini:{line_of(text, 'geometry = all')})",
         "of = all block"])

text = HEAD + box("a", "0.1 0.1", "0.5 0.3") + box("b", "0.45 0.2", "0.8 0.4") + \
    solid("a", "a") + solid("b", "b")
refused("two solids overlapping", text, "solid.a.geometry", line_of(text, "geometry = a"),
        ["[solid.a] overlaps [solid.b]", f"case.ini:{line_of(text, 'geometry = b')})"])

# A thin overlap: only the gas's finer lattice has points in it (gas ppc 4, solid ppc 1).
text = HEAD + "\n[fluid]\nppc = 4\n" + box("left", "0 0", "0.41 0.5") + \
    box("block", "0.4 0.1", "0.6 0.3") + gas("air", "left") + solid("block", "block") + "ppc = 1\n"
refused("a thin overlap seen by the gas's particles", text, "solid.block.geometry",
        line_of(text, "geometry = block"), ["[solid.block] overlaps [gas.air]"])

# The second gas region overlaps the solid where the first does not reach.
text = HEAD + box("left", "0 0", "0.5 0.5") + box("all", "0 0", "1 0.5") + \
    box("block", "0.6 0.1", "0.7 0.3") + gas("left", "left") + gas("rest", "all") + \
    solid("block", "block")
refused("a background gas region over the solid", text, "solid.block.geometry",
        line_of(text, "geometry = block"), ["[solid.block] overlaps [gas.rest]"])

text = HEAD.replace("dim = 2\nlo = 0 0\nhi = 1 0.5", "dim = 3\nlo = 0 0 0\nhi = 0.5 0.5 0.5") + \
    box("all", "0 0 0", "0.5 0.5 0.5") + "\n[geometry.ball]\ntype = sphere\ncenter = 0.25 " \
    "0.25 0.25\nradius = 0.1\n" + gas("air", "all").replace("0 0\n", "0 0 0\n") + \
    solid("ball", "ball")
refused("a sphere inside the gas (3-D)", text, "solid.ball.geometry",
        line_of(text, "geometry = ball"), ["[solid.ball] overlaps [gas.air]", ", "])

# 2. Touching is allowed.
text = HEAD + box("a", "0.1 0.1", "0.4 0.3") + box("b", "0.4 0.1", "0.7 0.3") + \
    box("gas", "0.7 0", "1 0.5") + solid("a", "a") + solid("b", "b") + gas("air", "gas")
accepted("solids and gas touching on grid lines", text)
# A face through a row of particles (x = 0.4125 with spacing 0.025): both seed it.
text = HEAD + box("a", "0.1 0.1", "0.4125 0.3") + box("b", "0.4125 0.1", "0.7 0.3") + \
    solid("a", "a") + solid("b", "b")
accepted("solids touching through a row of particles", text)
text = HEAD + box("all", "0 0", "1 0.5") + box("block", "0.4 0.1", "0.6 0.3") + \
    "\n[geometry.gas]\ntype = difference\nof = all block\n" + gas("air", "gas") + \
    solid("block", "block")
accepted("gas cut around the solid", text)
accepted("gas cut around the solid, 2 ranks", text, ["grid.ranks=2 1"], 2)

# 3. Coupling keys in a scene with one phase, at their default values.
SOLID_ONLY = HEAD + box("block", "0.4 0.1", "0.6 0.3") + solid("block", "block")
GAS_ONLY = HEAD + box("all", "0 0", "1 0.5") + gas("air", "all")
for name, base, body, key, phase in (
        ("coupling.scheme at its default, solids only", SOLID_ONLY, "scheme = velocity",
         "coupling.scheme", "no gas"),
        ("coupling.time at its default, gas only", GAS_ONLY, "time = monolithic", "coupling.time",
         "no solid"),
        ("coupling.friction at its default, gas only", GAS_ONLY, "friction = 0",
         "coupling.friction", "no solid"),
        ("coupling.substeps, solids only", SOLID_ONLY, "substeps = 4", "coupling.substeps",
         "no gas")):
    text = base + "\n[coupling]\n" + body + "\n"
    refused(name, text, key, line_of(text, body), [f"{key} has no effect", phase, "remove it"])
p, _ = run("check", SOLID_ONLY, ["coupling.scheme=velocity"])
e = errors(p)
check(p.returncode == 2 and len(e) == 1 and "command line" in e[0] and "coupling.scheme" in e[0],
      f"coupling.scheme on the command line, solids only: exit {p.returncode}: {e}")
accepted("a solid-only scene without [coupling]", SOLID_ONLY)
accepted("a gas-only scene without [coupling]", GAS_ONLY)

sys.exit(check.finish())
