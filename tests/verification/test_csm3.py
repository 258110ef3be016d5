"""Turek & Hron CSM3 (validation/turek_hron_csm3_dynamic.csv; cases/csm3.ini).

Tip A displacement over the first five periods: frequency within 2 % of 1.0995 Hz and uy
amplitude within 5 % of 65.160 mm (tolerances from the issue). The tip response is measured
by tools/tip_response.py (mean of the particles at the free end's mid-line; extrema by a
parabola through three snapshots, taken every 0.02 s).
The full test (label long) runs musl at dx = 2.5 mm (8 cells through the thickness), which
meets both (measured -0.76 % and -2.90 %, about 10 minutes on one loaded core). usl is
dissipative here: its amplitude loses about 10 % (the maxima sink period by period), while
musl's and bs32's agree to 1e-4; the frequency error is spatial, first order in dx through
the clamp's node-based edge (see bench/results/csm3_work_precision.md). Arguments: the cell size, then extra key=value overrides (e.g. time.method=musl).

`fast` instead runs the first period at dx = 5 mm (4 cells through the thickness) with musl
(about 20 s) and checks the first minimum of uy against the reference's, mean - amplitude =
-128.77 mm at half a period, 0.4548 s: a regression guard for the default selection. Its
tolerances come from this grid's measured spatial error (-130.10 mm, +1.03 %, at 0.4618 s,
+1.53 %) with margin: 3 % in value and in time.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

sys.path.insert(0, os.path.join(mt.SOURCE, "tools"))
import tip_response  # noqa: E402

check = mt.Checks("test_csm3")
if len(sys.argv) > 1 and sys.argv[1] == "fast":
    out = mt.outdir("csm3_fast")
    mt.run(["run", mt.case("csm3.ini"), f"output.dir={out}", "grid.dx=0.005", "time.method=musl",
            "time.t_end=0.7", "run.progress=false"])
    t, uy = tip_response.tip_uy(out)
    lows = tip_response.extrema(t, uy, 1)
    check(len(lows) == 1, f"one minimum in the first 0.7 s (found {len(lows)})")
    tmin, umin = lows[0]
    check(abs(umin + 128.77) / 128.77 < 0.03,
          f"first minimum {umin:.2f} mm vs -128.77 ({100 * (umin + 128.77) / -128.77:+.2f} %, "
          "tolerance 3 %)")
    check(abs(tmin - 0.4548) / 0.4548 < 0.03,
          f"at t = {tmin:.4f} s vs 0.4548 ({100 * (tmin - 0.4548) / 0.4548:+.2f} %, tolerance 3 %)")
    sys.exit(check.finish())
dx = sys.argv[1] if len(sys.argv) > 1 else "0.005"
out = mt.outdir(f"csm3_dx{dx}")
mt.run(["run", mt.case("csm3.ini"), f"output.dir={out}", f"grid.dx={dx}", "run.progress=false"]
       + sys.argv[2:])

r = tip_response.response(out)
freq, amp, mean, lows, highs = r["freq"], r["amp"], r["mean"], r["lows"], r["highs"]
print(f"info dx = {dx}: uy minima {[f'{v:.1f}' for _, v in lows]}, maxima "
      f"{[f'{v:.1f}' for _, v in highs]} mm; mean {mean:.2f} mm (reference -63.607)")
check(abs(freq - 1.0995) / 1.0995 < 0.02,
      f"frequency {freq:.4f} Hz vs 1.0995 ({100 * (freq - 1.0995) / 1.0995:+.2f} %, tolerance 2 %)")
check(abs(amp - 65.160) / 65.160 < 0.05,
      f"uy amplitude {amp:.2f} mm vs 65.160 ({100 * (amp - 65.16) / 65.16:+.2f} %, tolerance 5 %)")
sys.exit(check.finish())
