"""The main job's bar (cases/supersonic_bar.ini) started in its first bending mode, in a domain
cut to 132 x 48 mm around it with slip walls: alone (test_bar_clamp) or in the case's gas at
rest (test_bar_in_gas), and its period from the probes."""
import configparser
import math
import os

import numpy as np

import mpmtest as mt

# The first Euler-Bernoulli cantilever mode, beta L = 1.8751, sigma = 0.7341, L = 0.03 m;
# 2.5 times the shape, which is 2 at the tip: 5 m/s at the tip, a 0.8 mm swing (linear).
MODE = ("2.5*(cosh(62.503*y)-cos(62.503*y)-0.7341*(sinh(62.503*y)-sin(62.503*y))); 0")
GAS = ("freestream", "fluid", "coupling", "geometry.air", "gas.air")
T_END = 0.0035  # six zero crossings of the tip's velocity


def write(path, gas=False, shift=0.0, dx=None):
    """The scene as a case file at path: without the gas, or with the case's gas at rest (its
    free stream's state and gas settings, no open face). shift moves the domain, and with it
    the node lattice, by -shift along x (the bar stays where the case puts it). dx, if given,
    is the grid's spacing, and the domain grows to whole cells of it (the cut's 132 x 48 mm
    divides 2 mm, 1.5 mm and 1 mm, not every spacing)."""
    cfg = configparser.ConfigParser(inline_comment_prefixes=("#",))
    cfg.optionxform = str  # keys are case-sensitive (solid.bar.E)
    cfg.read(mt.case("supersonic_bar.ini"))
    if gas:
        cfg.remove_section("freestream")  # no open face reads it
        cfg["gas.air"]["velocity"] = "0 0"
    else:
        for s in GAS:
            cfg.remove_section(s)
    if shift:
        cfg["domain"]["lo"] = cfg["geometry.channel"]["lo"] = f"{-shift!r} 0"
    size = (0.132, 0.048)
    if dx is not None:
        cfg["grid"]["dx"] = repr(dx)
        size = tuple(math.ceil(s / dx - 1e-9) * dx for s in size)
    cfg["domain"]["hi"] = cfg["geometry.channel"]["hi"] = f"{size[0] - shift!r} {size[1]!r}"
    cfg["boundary"]["x_lo"] = cfg["boundary"]["x_hi"] = "slip"
    cfg["solid.bar"]["velocity_field"] = MODE
    cfg["time"]["t_end"] = repr(T_END)
    with open(path, "w") as f:
        cfg.write(f)


def period(out):
    """Twice the mean spacing of the tip velocity's zero crossings, and their count."""
    p = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
    t, v = p["t"], p["tip_vx"]
    k = np.nonzero(np.sign(v[1:]) * np.sign(v[:-1]) < 0)[0]
    tz = t[k] - v[k] * (t[k + 1] - t[k]) / (v[k + 1] - v[k])
    return 2.0 * (tz[-1] - tz[0]) / (len(tz) - 1), len(tz)
