"""The RAE 2822 case (cases/rae2822.ini) and the obstacles' surface pressure output
(obstacle.NAME.surface_interval: fluid/fluid_surface.h).

Default (`surface`, fast):
a) Rest: the case's domain and aerofoil with the gas at rest (p = 1, closed slip faces) for 0.05 s
   under least_squares. The gas stays at rest, so every sample of surface_rae2822.csv must read
   p = 1 and Cp = 0 to 1e-12 (roundoff: the samples are mass-weighted means of the particles'
   pressure, all 1): a wrong weight, a missed node or a window that averages zeros would show.
   Every one of the 128 outline points (the file's 129 rows close the outline at the trailing
   edge) gets a value in every window (no NaN: gas reaches every vertex, the trailing edge's
   too); the windows end within a step of t = 0.01, 0.02, ...; the points are split 65 upper
   (trailing edge to leading edge) and 63 lower, with x/c from 0 to 1 and x/c = 0 at the last
   upper point.
b) Ranks: the case itself (M = 0.729 past the aerofoil, coarse dx = 0.1) to t = 0.2 on 2 ranks
   gives the same surface pressure as on 1, to 1e-12 relative (sums in another node order).

`long`: the case as shipped (dx = 0.04, to t = 24) on 2 ranks: it runs stably to the end with
no gas particle inside the aerofoil, every outline point has a Cp in every window, and the lift
is positive and the drag non-negative in the mean of the last 5 windows (a sign error or a lost
lift would show); the figures of tools/rae2822.py are printed.
`targets` (an expected failure, long): the same run against the issue's targets: Cp RMS to the
experiment <= 0.05 over the lower surface and <= 0.08 on the upper surface ahead of the shock
(x/c <= 0.5), the upper-surface shock within 0.08 chord of the experiment's (the same
definition: Cp rising through Cp*), and a steady state (Cl of the last two 5-window spans within
2 %, Cp within 0.03 RMS). Not met at this resolution (nor at 0.028 and 0.02:
bench/results/rae2822.md): the shock is within 0.08 c and Cl steady since 2026-11-30 (the case's
wall_blend and far-field sponge), but the nose (radius 0.008 c, a fifth of a cell here) is not
resolved, which alone keeps both RMS figures far above their targets (0.33 and 0.65; 0.11 and
0.11 behind x/c = 0.1), and the Cp of the last window moves by 0.057 RMS. Nor can any inviscid
run meet the RMS targets: the converged Euler solution on a body-fitted grid is itself 0.072 and
0.164 from the experiment (tools/euler_aerofoil.py, bench/results/rae2822_euler.md).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))

check = mt.Checks("test_rae2822")
CASE = mt.case("rae2822.ini")


def surface(out):
    return np.genfromtxt(os.path.join(out, "surface_rae2822.csv"), delimiter=",", names=True,
                         dtype=None, encoding=None)


def rest():
    out = mt.outdir("rae_rest")
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false", "output.snapshots=false",
            "domain.lo=-0.5 -0.5", "domain.hi=1.5 0.5", "geometry.air.lo=-0.5 -0.5",
            "geometry.air.hi=1.5 0.5", "gas.air.velocity=0 0", "freestream.velocity=0 0",
            "time.t_end=0.05", "obstacle.rae2822.surface_interval=0.01", "freestream.sponge=0"]
           + [f"boundary.{f}=slip" for f in ("x_lo", "x_hi", "y_lo", "y_hi")])
    s = surface(out)
    times = np.unique(s["t"])
    dp = np.max(np.abs(s["p"] - 1.0))
    check(dp <= 1e-12 and np.max(np.abs(s["cp"])) <= 1e-11,
          f"rest: every surface sample p = 1 (max |p - 1| = {dp:.2e}, tolerance 1e-12)")
    check(not np.any(np.isnan(s["p"])), "rest: every outline point has gas near it (no NaN)")
    dt = np.max(np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",",
                              names=True)["dt"])
    check(len(times) == 5 and np.all(np.abs(times - 0.01 * np.arange(1, 6)) <= dt),
          f"rest: 5 windows ending within a step ({dt:.3g}) of 0.01 .. 0.05 (got "
          f"{np.round(times, 4).tolist()})")
    one = s[s["t"] == times[-1]]
    up, lo = one[one["side"] == "upper"], one[one["side"] == "lower"]
    check(len(one) == 128 and len(up) == 65 and len(lo) == 63,
          f"rest: 128 points per window, 65 upper and 63 lower (got {len(one)}, {len(up)}, "
          f"{len(lo)})")
    xc = one["coordinate"]
    check(abs(xc.min()) < 1e-12 and abs(xc.max() - 1) < 1e-12 and abs(up["coordinate"][-1]) < 1e-12,
          f"rest: x/c spans [0, 1] ({xc.min():.3g}, {xc.max():.6f}) with the leading edge last "
          "on the upper side")


def ranks():
    args = ["domain.lo=-1 -1", "domain.hi=2 1", "geometry.air.lo=-1 -1", "geometry.air.hi=2 1",
            "grid.dx=0.1", "time.t_end=0.2", "obstacle.rae2822.surface_interval=0.05",
            "run.progress=false", "output.snapshots=false"]
    res = []
    for n in (1, 2):
        out = mt.outdir(f"rae_ranks{n}")
        mt.run(["run", CASE, f"output.dir={out}"] + args, n)
        res.append(surface(out))
    a, b = res
    same = len(a) == len(b) and np.all(a["point"] == b["point"])
    diff = np.max(np.abs(a["p"] - b["p"])) / np.max(np.abs(a["p"])) if same else np.inf
    check(same and diff <= 1e-12, f"ranks: 2 ranks as 1 ({diff:.2e} relative, tolerance 1e-12)")
    check(np.std(a["p"]) > 1e-3, f"ranks: the flow loads the surface unevenly (std p = "
          f"{np.std(a['p']):.3g}): the comparison is not between two uniform fields")


def full_run():
    import rae2822
    out = mt.outdir("rae_full")
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"], 2)
    res, _, _ = rae2822.analyse(out, 5)
    for k, v in res.items():
        print(f"  {k:20s} {v}")
    return out, res


def long_checks():
    out, res = full_run()
    snaps = mt.snapshots(out)
    last = mt.particles(snaps[-1][1], "fluid")
    import rae2822
    t_end = snaps[-1][0]
    check(abs(t_end - 24) < 1e-9, f"long: ran to t = 24 (last snapshot at {t_end})")
    inside = airfoil_inside(last["x"])
    check(inside == 0, f"long: no gas particle inside the aerofoil at the end ({inside})")
    s = surface(out)
    check(not np.any(np.isnan(s["cp"])), "long: every outline point has a Cp in every window")
    check(res["cl"] > 0 and res["cd"] >= 0,
          f"long: lift up and drag downstream in the mean (Cl {res['cl']:.3f}, Cd "
          f"{res['cd']:.4f}); {rae2822.__name__}: RMS lower {res['rms_lower']:.3f}, upper "
          f"{res['rms_upper_ahead']:.3f}, shock {res['shock_x']}")


def airfoil_inside(x):
    """Particles inside the outline (the case's file, turned by the angle of attack)."""
    from matplotlib.path import Path
    rows = [r.split(",") for r in open(mt.case("rae2822_coordinates.csv"))
            if r[0].isdigit() or r[0] in "-."]
    xy = np.array([[float(r[0]), float(r[1])] for r in rows])
    a = np.radians(2.31)
    body = np.column_stack([np.cos(a) * xy[:, 0] + np.sin(a) * xy[:, 1],
                            -np.sin(a) * xy[:, 0] + np.cos(a) * xy[:, 1]])
    return int(np.sum(Path(body).contains_points(x)))


def targets():
    _, res = full_run()
    exp = res["shock_x_experiment"]
    check(res["rms_lower"] <= 0.05, f"targets: Cp RMS lower {res['rms_lower']:.3f} (<= 0.05)")
    check(res["rms_upper_ahead"] <= 0.08,
          f"targets: Cp RMS upper ahead of the shock {res['rms_upper_ahead']:.3f} (<= 0.08)")
    check(res["shock_x"] is not None and abs(res["shock_x"] - exp) <= 0.08,
          f"targets: shock at {res['shock_x']} against the experiment's {exp:.3f} (within 0.08)")
    check(res["steady"], f"targets: steady (Cl change {100 * res['cl_change']:.1f} %, Cp drift "
          f"{res['cp_drift_rms']:.3f})")


def main():
    mode = sys.argv[1] if len(sys.argv) > 1 else "surface"
    if mode == "surface":
        rest()
        ranks()
    elif mode == "long":
        long_checks()
    elif mode == "targets":
        targets()
    else:
        raise SystemExit(f"unknown mode {mode}")
    return check.finish()


if __name__ == "__main__":
    sys.exit(main())
