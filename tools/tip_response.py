"""Tip response of the Turek-Hron bar (CSM3 and friends) from a run's snapshots: the mean
displacement of the particles within 3 mm of the free end and 4 mm of the mid-line, its
extrema located by a parabola through the three samples around each, and from them the
frequency, the uy amplitude and the mean. Used by tests/verification/test_csm3.py and
bench/bench_csm3.py. Run with Debian's /usr/bin/python3 (h5py)."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "tools"))
import mpmtest as mt  # noqa: E402


def tip_uy(out):
    """(t, uy in mm) of the tip particles' mean over the snapshots of run folder out."""
    snaps = mt.snapshots(out)
    X = mt.particles(snaps[0][1])["x"]
    tip = (X[:, 0] > X[:, 0].max() - 0.003) & (np.abs(X[:, 1] - 0.2) < 0.004)
    t = np.array([s[0] for s in snaps])
    uy = np.array([1e3 * (mt.particles(p)["x"] - X)[tip, 1].mean() for _, p in snaps])
    return t, uy


def extrema(t, u, sign):
    """(time, value) of the local minima (sign=1) or maxima (sign=-1) of u(t)."""
    found = []
    for i in range(1, len(t) - 1):
        a, b, c = sign * u[i - 1], sign * u[i], sign * u[i + 1]
        if b < a and b <= c:
            off = 0.5 * (a - c) / (a - 2 * b + c)
            found.append((t[i] + off * (t[i] - t[i - 1]), sign * (b - 0.25 * (a - c) * off)))
    return found


def response(out):
    """dict: freq (Hz, from the minima), amp and mean (mm), lows and highs [(t, uy)]."""
    t, uy = tip_uy(out)
    lows, highs = extrema(t, uy, 1), extrema(t, uy, -1)
    freq = (len(lows) - 1) / (lows[-1][0] - lows[0][0]) if len(lows) > 1 else float("nan")
    hi = np.mean([h[1] for h in highs]) if highs else float("nan")
    lo = np.mean([m[1] for m in lows]) if lows else float("nan")
    return {"freq": freq, "amp": 0.5 * (hi - lo), "mean": 0.5 * (hi + lo), "lows": lows,
            "highs": highs}
