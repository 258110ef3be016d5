"""Far-field faces under mixed flow: freestream.exterior = gauge, and freestream.sponge, against
copies.

1. cases/farfield_shear.ini: a sheared stream (u = 0.729 + 0.08 sin(2 pi y), rho = 1.4, p = 1,
   c = 1) through farfield faces, y periodic, to t = 16. The shear layers mix on the way, and
   the gas that reaches the outflow face is disordered at the particle scale. The face should
   hold the entering characteristic w- = p - Z u at the free stream's (-0.0206); the drift is
   the largest |mean w- - w-_inf| over the snapshots (every 1) of the gas within a chord (x >= 3)
   of the outflow face. Measured 2026-11-29: copies 0.119, gauge 0.050. Checked: gauge at most
   half of copies in the same run (0.42 measured; the copies' drift is the defect the gauge
   removes, and the mixing itself moves the mean state by about rho <u'^2> = 0.005, so the
   gauge's figure is the face's own error, not a floor).
   The sponge (freestream.sponge = 0.5, under copies: the incoming characteristic relaxed
   towards the free stream's within half a chord of the faces) is judged on the gas the drift
   reaches upstream, 0 <= x < 3 (outside the layer, which imposes w- by construction): measured
   2026-11-30, copies 0.071, sponge 0.024 (0.33 of it; gauge 0.019, which holds this channel
   better but blew up on RAE 2822). Checked: sponge at most half of copies there.
2. The clean far field under gauge: the same channel (0.4 high, dx = 0.1), uniform but at
   p = 1.0366, u = 0.7027 (w- = +0.0528: the state the RAE 2822 tunnel drifted to under
   copies), relaxes to the free stream's w- through the outflow face at the acoustic speed
   c - u; at t = 40 (1.5 crossings) the mean w- of the gas is within 1e-3 of -0.0206 (measured
   1e-4; a linear characteristic condition relaxes an acoustic offset in one crossing, what
   remains is the discrete face and the non-linear part of the offset).
3. 2 ranks vs 1 under gauge with the sponge (freestream.sponge = 0.5, so that both run): the
   sheared channel to t = 2 by id to 1e-10 relative (the halo sums run in another order;
   test_gas_boundaries holds copies to the same).
4. Bad input: freestream.exterior = bogus is refused with one line naming the key, and the
   sponge's keys out of range or without a farfield face likewise.

`ranks` (the argument; test_farfield_gauge_ranks, which the sanitizer pass runs): checks 3 and 4,
so that the gauge's and the sponge's code runs under the sanitizers in seconds; without it,
checks 1 and 2 (test_farfield_gauge, 141 s under the sanitizers, in the plain build only).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

RANKS = sys.argv[1:] == ["ranks"]
check = mt.Checks("test_farfield_gauge_ranks" if RANKS else "test_farfield_gauge")
CASE = mt.case("farfield_shear.ini")
Z, U = 1.4, 0.729
W_INF = 1.0 - Z * U


def run(name, args, ranks=1):
    out = mt.outdir(name)
    mt.run(["run", CASE, f"output.dir={out}", "run.progress=false"] + list(args), ranks)
    return out


def w_minus(path, select):
    P = mt.particles(path, "fluid")
    s = select(P["x"][:, 0])
    return float(P["p"][s, 0].mean() - Z * P["v"][s, 0].mean())


def mixed_flow_and_relaxation():
    # 1. Mixed flow at the outflow face.
    drift, upstream = {}, {}
    for exterior, args in (("copies", ["freestream.exterior=copies"]),
                           ("gauge", ["freestream.exterior=gauge"]),
                           ("sponge", ["freestream.exterior=copies", "freestream.sponge=0.5"])):
        out = run(f"shear_{exterior}", args)
        snaps = mt.snapshots(out)
        series = [w_minus(p, lambda x: x >= 3.0) - W_INF for _, p in snaps]
        inside = [w_minus(p, lambda x: (x >= 0.0) & (x < 3.0)) - W_INF for _, p in snaps]
        drift[exterior] = max(abs(d) for d in series)
        upstream[exterior] = max(abs(d) for d in inside)
        print(f"{exterior}: mean w- - w-_inf next to the outflow face, t = 0, 1, ..., 16: "
              + " ".join(f"{d:+.3f}" for d in series) + f"   ({mt.cost(out)})")
        print(f"{exterior}: the same over 0 <= x < 3: " + " ".join(f"{d:+.3f}" for d in inside))
    check(drift["gauge"] <= 0.5 * drift["copies"], f"sheared stream: the outflow face holds w- "
          f"within {drift['gauge']:.3f} of the free stream's under gauge, {drift['copies']:.3f} "
          f"under copies (gauge at most half)")
    check(upstream["sponge"] <= 0.5 * upstream["copies"], f"sheared stream, 0 <= x < 3: w- "
          f"within {upstream['sponge']:.3f} of the free stream's with the sponge, "
          f"{upstream['copies']:.3f} under copies alone (gauge {upstream['gauge']:.3f}; sponge at "
          f"most half of copies)")

    # 2. An off-free-stream state relaxes through the far field.
    off = ["domain.lo=-3 -0.2", "domain.hi=4 0.2", "geometry.air.lo=-3 -0.2",
           "geometry.air.hi=4 0.2", "grid.dx=0.1", "gas.air.velocity_field=0.7027; 0",
           "gas.air.pressure=1.0366", "gas.air.density=1.4364", "time.t_end=40",
           "output.interval=10"]
    out = run("relax_gauge", off)
    snaps = mt.snapshots(out)
    w0, w1 = (w_minus(snaps[k][1], lambda x: x > -10) - W_INF for k in (0, -1))
    check(abs(w1) <= 1e-3, f"off state under gauge: mean w- - w-_inf {w0:+.4f} at t = 0, "
          f"{w1:+.1e} at t = {snaps[-1][0]:g} (<= 1e-3)")


def ranks_and_input():
    # 3. Ranks.
    mt.check_ranks_agree(check, CASE, ["time.t_end=2", "output.interval=1",
                                       "freestream.sponge=0.5"], "shear_ranks", phase="fluid",
                         tol=1e-10)

    # 4. Bad input.
    text = open(CASE).read().replace("exterior = gauge", "exterior = bogus")
    mt.expect_input_error(check, "freestream.exterior = bogus", text, "freestream.exterior",
                          mt.line_starting(text, "exterior = bogus"))

    # The sponge's keys.
    text = open(CASE).read().replace("exterior = gauge", "exterior = copies\nsponge = -1")
    mt.expect_input_error(check, "freestream.sponge = -1", text, "freestream.sponge",
                          mt.line_starting(text, "sponge = -1"))
    text = open(CASE).read().replace("exterior = gauge", "sponge_rate = 4")
    mt.expect_input_error(check, "sponge_rate without sponge", text, "freestream.sponge_rate",
                          mt.line_starting(text, "sponge_rate = 4"), "freestream.sponge")
    text = (open(CASE).read().replace("exterior = gauge", "sponge = 0.5")
            .replace("x_lo = farfield", "x_lo = subsonic_inflow")
            .replace("x_hi = farfield", "x_hi = subsonic_outflow"))
    mt.expect_input_error(check, "a sponge without a farfield face", text, "freestream.sponge",
                          mt.line_starting(text, "sponge = 0.5"), "farfield")


if RANKS:
    ranks_and_input()
else:
    mixed_flow_and_relaxation()
sys.exit(check.finish())
