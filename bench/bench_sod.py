#!/usr/bin/python3
"""Work-precision of the gas time methods on the Sod shock tube (cases/sod.ini, t = 0.2): the
L1 density error against wall time and particle-steps over 100 ... 1600 cells and the time
methods usl, musl (classic updates at the case's CFL) and the adaptive pairs bs32,
zonneveld43, dp54 (at the case's atol), with the ratio to the second-order finite-volume
Godunov figure of issue 4 (L1 = 1.3e-3 at 400 cells) at equal error.

The error is the one test_sod checks: tests/tools/shocktube.py (particle densities joined by
linear interpolation, averaged per cell, against the exact solution of tests/tools/riemann.py
averaged per cell; L1 over [0, 1]).

Usage: /usr/bin/python3 bench/bench_sod.py [--cells 100,200,...] [--methods usl,bs32,...]
[--repeat R] [--report] (from the repository root after building; --report only rewrites the
table, the page and the plot from the stored rows). Results accumulate in
bench/results/sod_work_precision.json (a run replaces the rows it repeats; with --repeat the
fastest of R runs is kept, the error being the same); the CSV, the page
sod_work_precision.md and the plot sod_work_precision.png are rewritten from all rows (the
page keeps whatever follows its NOTES line: the hand-written discussion). Wall times on a
shared 2-core machine are noisy: compare within one invocation.
"""
import csv
import json
import math
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
os.environ.setdefault("MPMFSI_SOURCE_DIR", ROOT)
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
import shocktube  # noqa: E402
from riemann import Riemann  # noqa: E402

RESULTS = os.path.join(ROOT, "bench", "results")
BASE = os.path.join(RESULTS, "sod_work_precision")
LEFT, RIGHT, T = (1.0, 0.0, 1.0), (0.125, 0.0, 0.1), 0.2  # as test_sod
EXACT = Riemann(LEFT, RIGHT, gamma=1.4, x0=0.5)
FV_L1, FV_N = 1.3e-3, 400  # second-order finite-volume Godunov at 400 cells (issue 4)
CELLS = [100, 200, 400, 800, 1600]
NOTES = "<!-- notes: written by hand, kept when bench_sod.py rewrites the tables above -->"
METHODS = ["usl", "musl", "bs32", "zonneveld43", "dp54", "ssprk2"]


def arg(name, default, conv=str):
    if name not in sys.argv:
        return default
    return [conv(v) for v in sys.argv[sys.argv.index(name) + 1].split(",")]


def run(N, method):
    """One run at N cells; the output folder goes away after the measurement."""
    with tempfile.TemporaryDirectory() as tmp:
        cwd = os.getcwd()
        os.chdir(tmp)  # shocktube.run makes its output folder in the working directory
        try:
            out = shocktube.run("sod.ini", N, method, T, 1, ["output.interval=0.2"])
            l1, xs, P = shocktube.measure(out, N, EXACT, T)
            s = json.load(open(os.path.join(out, "summary.json")))
        finally:
            os.chdir(cwd)
    return {"cells": N, "method": method, "particles": len(P["id"]), "l1": l1,
            "shock_offset_cells": (xs - EXACT.shock_position(T)) * N, "wall_s": s["wall_s"],
            "steps": s["steps"], "rhs_evals": s["rhs_evals"],
            "particle_steps": s["particle_steps"]}


def loglog_slope(a, b, key):
    """Slope of log(key) against log(cells) between rows a and b."""
    return math.log(b[key] / a[key]) / math.log(b["cells"] / a["cells"])


def orders(rows):
    """Observed order per doubling (by the rows' cell counts, ascending) and overall."""
    per = [-loglog_slope(a, b, "l1") for a, b in zip(rows, rows[1:])]
    overall = -loglog_slope(rows[0], rows[-1], "l1") if len(rows) > 1 else float("nan")
    return per, overall


def equal_error(rows):
    """Resolution and wall time at which the method reaches the finite-volume error FV_L1.
    Measured (log-log interpolation between the two bracketing runs) when some run reaches
    it; otherwise extrapolated from the finest run with the observed order and the wall-time
    growth of the last doubling (marked as extrapolated). None if the error does not fall."""
    for a, b in zip(rows, rows[1:]):
        if a["l1"] > FV_L1 >= b["l1"]:
            f = math.log(FV_L1 / a["l1"]) / math.log(b["l1"] / a["l1"])
            n = a["cells"] * (b["cells"] / a["cells"]) ** f
            w = a["wall_s"] * (b["wall_s"] / a["wall_s"]) ** f
            return {"cells": n, "wall_s": w, "how": "interpolated between measured runs"}
    if rows[0]["l1"] <= FV_L1:
        return {"cells": rows[0]["cells"], "wall_s": rows[0]["wall_s"], "how": "measured"}
    if len(rows) < 2:
        return None
    a, b = rows[-2], rows[-1]
    p = -loglog_slope(a, b, "l1")
    if not p > 0:
        return None
    n = b["cells"] * (b["l1"] / FV_L1) ** (1 / p)
    w = b["wall_s"] * (n / b["cells"]) ** loglog_slope(a, b, "wall_s")
    return {"cells": n, "wall_s": w, "how": f"extrapolated (order {p:.2f} of the last doubling)"}


def by_method(rows):
    out = {}
    for m in METHODS + sorted({r["method"] for r in rows} - set(METHODS)):
        mr = sorted((r for r in rows if r["method"] == m), key=lambda r: r["cells"])
        if mr:
            out[m] = mr
    return out


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for m, mr in by_method(rows).items():
        line, = ax.loglog([r["wall_s"] for r in mr], [r["l1"] for r in mr], "o-", label=m)
        for r in mr:
            ax.annotate(str(r["cells"]), (r["wall_s"], r["l1"]), fontsize=7,
                        color=line.get_color(), xytext=(3, 3), textcoords="offset points")
    ax.axhline(FV_L1, color="k", ls=":", lw=0.8, label="finite-volume Godunov, 400 cells")
    ax.set_xlabel("wall time, s (1 core, shared machine)")
    ax.set_ylabel("L1 density error at t = 0.2")
    ax.set_title("Sod shock tube work-precision (labels: cells)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(BASE + ".png", dpi=120)


def sci(x):
    return f"{x:.2e}"


def page(rows):
    """The results page: the table, the orders, the equal-error comparison."""
    groups = by_method(rows)
    L = ["# Sod work-precision (bench/bench_sod.py)", "",
         "Sod shock tube (`cases/sod.ini`: γ = 1.4, (1, 0, 1) | (0.125, 0, 0.1), x0 = 0.5, "
         "t = 0.2, a strip N × 3 cells periodic in y), quadratic B-splines, 2 particles per cell "
         "per direction. usl and musl at the case's CFL 0.4 with FLIP; bs32, zonneveld43 and dp54 "
         "adaptive at the case's atol 1e-4 (default rtol). Error: L1 of the cell-averaged density "
         "against the exact solution, as `test_sod` measures it (`tests/tools/shocktube.py`, "
         "`tests/tools/riemann.py`). One rank. Raw rows: [csv](sod_work_precision.csv), "
         "[json](sod_work_precision.json).", "",
         "![L1 density error against wall time](sod_work_precision.png)", "",
         "| cells | method | L1 | shock offset (cells) | wall s | steps | RHS evals | "
         "M particle-steps | M particle-steps/s |", "|---|---|---|---|---|---|---|---|---|"]
    for m, mr in groups.items():
        for r in mr:
            L.append(f"| {r['cells']} | {m} | {sci(r['l1'])} | {r['shock_offset_cells']:+.2f} | "
                     f"{r['wall_s']:.2f} | {r['steps']} | {r['rhs_evals']} | "
                     f"{r['particle_steps'] / 1e6:.1f} | "
                     f"{r['particle_steps'] / r['wall_s'] / 1e6:.2f} |")
    L += ["", "## Observed orders (−log2 of the L1 ratio per doubling)", "",
          "| method | per doubling | first to last |", "|---|---|---|"]
    for m, mr in groups.items():
        per, overall = orders(mr)
        span = f"{mr[0]['cells']}→{mr[-1]['cells']}"
        L.append(f"| {m} | " + ", ".join(f"{p:.2f}" for p in per) + f" | {overall:.2f} ({span}) |")
    L += ["", f"## Against the finite-volume Godunov figure ({FV_L1:g} at {FV_N} cells)", "",
          f"Ratio: the method's L1 at {FV_N} cells divided by {FV_L1:g}. Equal error: the "
          f"resolution and wall time at which the method's L1 reaches {FV_L1:g} (log-log "
          "interpolation between the two runs that bracket it; extrapolation from the finest "
          "run with the order of the last doubling and its wall-time growth when no run "
          "reaches it).", "",
          f"| method | L1 at {FV_N} / {FV_L1:g} | cells for {FV_L1:g} | wall s for {FV_L1:g} | how |",
          "|---|---|---|---|---|"]
    for m, mr in groups.items():
        at = [r for r in mr if r["cells"] == FV_N]
        ratio = f"{at[0]['l1'] / FV_L1:.2f}" if at else "not run"
        eq = equal_error(mr)
        if eq is None:
            L.append(f"| {m} | {ratio} | not reached | | the error does not fall |")
        else:
            L.append(f"| {m} | {ratio} | {eq['cells']:.0f} | {eq['wall_s']:.1f} | {eq['how']} |")
    return "\n".join(L) + "\n"


def main():
    rows = json.load(open(BASE + ".json")) if os.path.exists(BASE + ".json") else []
    repeat = int(arg("--repeat", ["1"])[0])
    for N in [] if "--report" in sys.argv else arg("--cells", CELLS, int):
        for method in arg("--methods", METHODS):
            runs = [run(N, method) for _ in range(repeat)]
            r = min(runs, key=lambda x: x["wall_s"])
            rows = [x for x in rows if (x["cells"], x["method"]) != (N, method)] + [r]
            print(f"N {N:5d} {method:<12} L1 {r['l1']:.3e} shock {r['shock_offset_cells']:+.2f}"
                  f" cells  wall {r['wall_s']:7.2f} s  steps {r['steps']:6d}  rhs "
                  f"{r['rhs_evals']:6d}", flush=True)
            json.dump(rows, open(BASE + ".json", "w"), indent=1)
    rows.sort(key=lambda x: (METHODS.index(x["method"]) if x["method"] in METHODS else 99,
                             x["cells"]))
    with open(BASE + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    notes = ""
    if os.path.exists(BASE + ".md"):
        old = open(BASE + ".md").read()
        if NOTES in old:
            notes = old[old.index(NOTES) + len(NOTES):]
    with open(BASE + ".md", "w") as f:
        f.write(page(rows) + "\n" + NOTES + (notes or "\n"))
    plot(rows)
    print("wrote", BASE + ".{csv,json,md,png}")


if __name__ == "__main__":
    main()
