"""The main job's bar in its gas at rest: the gas's ambient pressure must not change the bar's
period with the grid's placement.

Scene (tests/tools/bar_scene.py): cases/supersonic_bar.ini's bar (6 x 30 mm, clamped on the
floor, neo-Hookean, E = 0.7 GPa, rho = 1000) in a domain cut to 132 x 48 mm with slip walls,
started in its first bending mode (5 m/s at the tip, a 0.8 mm swing), to 3.5 ms; in the
case's gas at rest (p = 1e5 Pa, rho = 1.2, the case's gas settings), and alone as the control.
Each runs on the case's node lattice, where the bar's faces (x = 0.100, 0.106; y = 0.030) lie on
node lines, and on the lattice shifted half a cell along x, where its side faces lie half-way
between node lines. The period is twice the mean spacing of the tip velocity's zero crossings.

Measured: the gas's effect on the period, T_gas / T_alone - 1 on the same lattice.

1. It must not depend on the lattice's placement: the shifted lattice's effect within
   0.5 % (of the period) of the case's lattice's. The continuum has no lattice; 0.5 % is the
   bar alone's own placement spread at 2 mm (1.1284 against 1.1230 ms, 0.48 %; 0.20 % at 1 mm),
   what three cells across the bar may keep.
2. It must lie in [0, +2 %]: the gas slows the bar and cannot stiffen it. Its added mass
   (the air a plate of the bar's height and its image in the floor carry, about 2 % of the
   bar's mass, less after the mode's weighting) and the pressure's effect on the bending (order
   p / E (L / h)^2, 0.4 %) bound it.

With physics.gauge_pressure at the ambient both hold under velocity and sharp, and so they do
under velocity with the hybrid pressure (fluid.pressure = hybrid, no gauge). Without either the
particles' quadrature of the ambient pressure over the gas's last columns at the bar's faces
acts as a spring whose stiffness depends on where the faces lie between nodes: the gauge takes
the uniform part out of the forces (fluid/fluid_gauge.c); the hybrid continues the gas's
pressure through the solid, so that its quadrature does not end at the face
(fluid/fluid_gridp_solid.c). The grid pressure alone does not (fluid.pressure = grid, one run
each: 1.0896 and 1.1379 ms, -3.44 % and +1.33 %). Measured 2026-12-07 (2 mm; in
brackets 1 mm, `long`), periods in ms, the effect in %:

  scheme    gauge  faces on node lines       shifted                   spread
  alone            1.1284 (1.1009)           1.1230 (1.0987)
  velocity  p0     1.1393, +0.96 (1.1104, +0.86)  1.1382, +1.35 (1.1056, +0.63)  0.39 (0.23)
  velocity  none   1.0929, -3.15 (1.0932, -0.70)  1.1368, +1.23 (1.1054, +0.60)  4.38 (1.30)
  velocity  hybrid 1.1455, +1.51 (1.1125, +1.06)  1.1383, +1.36 (1.1120, +1.21)  0.15 (0.15)
  sharp     p0     1.1364, +0.71             1.1338, +0.97             0.26
  sharp     none   1.1580, +2.62             1.1114, -1.03             3.65

The runs with neither the gauge nor the hybrid are expected failures (printed with the reason).
The main job cannot take the gauge: its open faces and its near-vacuum wake carry no uniform
stress (fluid_gauge.c refuses them; with the refusal lifted its drag fell 11.6 %). It can take
the hybrid, which leaves its tip as it was (period 1.023 against 1.021 ms at 2 mm, 0.15 mm RMS
apart): in its flow the spring does not set the tip. docs/coupling.md, "The gauge".

Arguments: [long] (long: 1 mm as well, `velocity` only). Default: twelve runs, about 65 s on
one core.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import bar_scene  # noqa: E402
import mpmtest as mt  # noqa: E402

check = mt.Checks("test_bar_in_gas")
LONG = sys.argv[1:2] == ["long"]
P0 = 1.0e5  # the case's ambient pressure
TOL_SPREAD, BAND = 0.005, (0.0, 0.02)
CASES = mt.outdir("bar_in_gas_cases")  # the scenes' case files, one folder for all
REASON = ("without the gauge the particles' quadrature of the ambient pressure at the bar's "
          "faces acts as a spring whose stiffness depends on where the faces lie between "
          "nodes; see the docstring")


def verdict(expected, cond, msg):
    """An ordinary check, or one known to fail (REASON)."""
    if expected:
        check(cond, msg)
    else:
        check.expect_fail(cond, msg, REASON)


def period(tag, dx, shift, gas, keys=()):
    case = os.path.join(CASES, f"{tag}.ini")
    bar_scene.write(case, gas=gas, shift=shift)
    out = mt.outdir(f"bar_in_gas_{tag}")
    mt.run(["run", case, f"output.dir={out}", f"grid.dx={dx!r}", "run.progress=false"]
           + list(keys))
    T, n = bar_scene.period(out)
    if n < 5:
        raise SystemExit(f"test_bar_in_gas: {tag}: {n} zero crossings of the tip's velocity")
    print(f"info {tag}: period {T * 1e3:.4f} ms ({n} crossings); cost {mt.cost(out)}")
    return T


def study(dx, runs):
    """runs: (label, keys, expected to pass)."""
    mm = f"{dx * 1e3:g}mm"
    shifts = (0.0, dx / 2)
    alone = [period(f"alone_{mm}_{k}", dx, s, False) for k, s in enumerate(shifts)]
    for label, keys, expected in runs:
        tag = label.replace(", ", "_").replace(" ", "_") + f"_{mm}"
        eff = [period(f"{tag}_{k}", dx, s, True, keys) / a - 1.0
               for k, (s, a) in enumerate(zip(shifts, alone))]
        what = f"{label}, dx {dx * 1e3:g} mm"
        effects = f"{100 * eff[0]:+.2f} % (faces on node lines), {100 * eff[1]:+.2f} % (shifted)"
        spread = abs(eff[1] - eff[0])
        verdict(expected, spread <= TOL_SPREAD,
                f"{what}: the gas's effect on the period {effects}: spread {100 * spread:.2f} % "
                f"(<= {100 * TOL_SPREAD:g} %)")
        verdict(expected, all(BAND[0] <= e <= BAND[1] for e in eff),
                f"{what}: the gas's effect {effects} in [{100 * BAND[0]:g}, {100 * BAND[1]:g}] %")


def run(scheme, gauge=False, pressure=None):
    """A study's run: its label, its keys, and whether it is expected to pass."""
    pg = P0 if gauge else 0.0
    keys = [f"coupling.scheme={scheme}", f"physics.gauge_pressure={pg!r}"]
    label = f"{scheme}, {'gauge at p0' if gauge else 'no gauge'}"
    if pressure:
        keys.append(f"fluid.pressure={pressure}")
        label += f", {pressure} pressure"
    return label, keys, gauge or pressure == "hybrid"


study(0.002, [run("velocity", gauge=True), run("velocity"), run("velocity", pressure="hybrid"),
              run("sharp", gauge=True), run("sharp")])
if LONG:
    study(0.001, [run("velocity", gauge=True), run("velocity"), run("velocity", pressure="hybrid")])
sys.exit(check.finish())
