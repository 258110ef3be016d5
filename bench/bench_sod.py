#!/usr/bin/python3
"""Work-precision of the gas time methods on the shock tubes: the L1 density error against
wall time and particle-steps over 100 ... 1600 cells and the time methods usl, musl, ssprk2
(at time.cfl 0.4, tests/tools/shocktube.py) and the pairs bs32, zonneveld43, dp54 at the
case's time settings (the shock-tube cases: a fixed step at time.cfl 0.8; `--set
time.adaptive=true,time.cfl=0.4,time.atol=1e-4` for the adaptive pairs), with, measured in the same run, the reference finite-volume solver (MUSCL-Hancock +
HLLC, bench/fv_strip.py) on the same problem in the same strip at 400, 800 and 1600 cells,
and each method's cost at equal error as a ratio to it.

Problems (--problem, default sod; bench/fv_strip.py defines them): sod (cases/sod.ini, the
page sod_work_precision), toro3 (Toro's test 3, cases/strong_shock.ini, the page
strong_shock_work_precision) and toro3_moving (Toro's test 5: test 3 moving across the grid,
the page strong_shock_moving_work_precision, which also holds the Galilean-invariance table:
moving against at rest, from the toro3 rows).

The error is the one test_sod checks: tests/tools/shocktube.py (particle densities joined by
linear interpolation, averaged per cell, against the exact solution of tests/tools/riemann.py
averaged per cell; L1 over [0, 1]); the finite-volume solver's cell values are compared with
the same exact cell averages.

Usage: /usr/bin/python3 bench/bench_sod.py [--problem sod|toro3|toro3_moving]
[--cells 100,200,...] [--methods usl,bs32,...] [--fv-cells 400,800,1600] [--repeat R]
[--set key=value,...] [--results DIR] [--report] (from the repository root after building; --report only rewrites the table, the
page and the plot from the stored rows; --fv-cells none skips the finite-volume runs;
--set adds case keys to every mpmfsi run and labels its rows "method [key=value, ...]", for
probes written elsewhere with --results).
Results accumulate in bench/results/<page>.json (or DIR/<page>.json) (a run replaces the rows it repeats; with
--repeat the fastest of R runs is kept, the error being the same); the CSV, the page
<page>.md and the plot <page>.png are rewritten from all rows (the page keeps whatever
follows its NOTES line: the hand-written discussion). Every row records the invocation that
measured it; the ratio table marks ratios between rows of different invocations. Wall times
on a shared 2-core machine are noisy: compare within one invocation.
"""
import csv
import datetime
import json
import math
import os
import resource
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CWD = os.getcwd()  # before mpmtest moves out of the checkout's tracked folders
os.environ.setdefault("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
os.environ.setdefault("MPMFSI_SOURCE_DIR", ROOT)
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import shocktube  # noqa: E402
import mpmtest as mt  # noqa: E402
import fv_strip  # noqa: E402


def arg(name, default, conv=str):
    if name not in sys.argv:
        return default
    i = sys.argv.index(name) + 1
    if i >= len(sys.argv) or sys.argv[i] == "none":
        return []
    return [conv(v) for v in sys.argv[i].split(",")]


RESULTS = os.path.join(CWD, (arg("--results", []) or [os.path.join(ROOT, "bench", "results")])[0])
PAGES = {  # problem: (page, title, what the strip holds)
    "sod": ("sod_work_precision", "Sod work-precision",
            "Sod shock tube (`cases/sod.ini`: γ = 1.4, (1, 0, 1) | (0.125, 0, 0.1), x0 = 0.5, "
            "t = 0.2, a strip N × 3 cells periodic in y)"),
    "toro3": ("strong_shock_work_precision", "Strong shock (Toro 3) work-precision",
              "Strong shock tube, Toro's test 3 (`cases/strong_shock.ini`: γ = 1.4, "
              "(1, 0, 1000) | (1, 0, 0.01), x0 = 0.5, t = 0.012, a strip N × 3 cells periodic "
              "in y, slip walls at the ends)"),
    "toro3_moving": ("strong_shock_moving_work_precision",
                     "Moving strong shock (Toro 5) work-precision",
                     "Toro's test 5, his test 3 in a frame moving at u = −19.59745 "
                     "(`cases/strong_shock.ini` with both gases at that velocity, x0 = 0.8, "
                     "an outflow face at x = 0 and a supersonic inflow face of the cold state "
                     "at x = 1; t = 0.012; the contact at rest, the gas crossing the grid at "
                     "19.6; a strip N × 3 cells periodic in y)"),
}
PROBLEM = (arg("--problem", ["sod"]) or ["sod"])[0]
if PROBLEM not in PAGES:
    sys.exit(f"bench_sod.py: unknown --problem '{PROBLEM}'; give one of {', '.join(PAGES)}")
PR = fv_strip.PROBLEMS[PROBLEM]
T, EXACT = PR.t, PR.exact
BASE = os.path.join(RESULTS, PAGES[PROBLEM][0])
FV_L1, FV_N = 1.3e-3, 400  # second-order finite-volume Godunov at 400 cells (issue 4), Sod
CELLS = [100, 200, 400, 800, 1600]
FV_CELLS = [400, 800, 1600]
MAX_EXTRAPOLATION = 4  # beyond two doublings past the finest run, give only lower bounds
NOTES = "<!-- notes: written by hand, kept when bench_sod.py rewrites the tables above -->"
METHODS = ["usl", "musl", "bs32", "zonneveld43", "dp54", "ssprk2"]
SETS = arg("--set", [])  # extra case keys for every mpmfsi run; they label the method
INVOCATION = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def run(N, method):
    """One run at N cells; the output folder goes away after the measurement."""
    with tempfile.TemporaryDirectory() as tmp:
        cwd = os.getcwd()
        os.chdir(tmp)  # shocktube.run makes its output folder in the working directory
        try:
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            out = shocktube.run(PR.case, N, method, T, 1,
                                [f"output.interval={T}"] + PR.mpm_overrides() + SETS,
                                x0=PR.x0)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            P = mt.particles(mt.snapshots(out)[-1][1], "fluid")
            l1, off, plat = fv_strip.mpm_measure(PR, P, N)
            s = json.load(open(os.path.join(out, "summary.json")))
        finally:
            os.chdir(cwd)
    label = method + (f" [{', '.join(SETS)}]" if SETS else "")
    return {"cells": N, "method": label, "particles": len(P["id"]), "l1": l1,
            "shock_offset_cells": off, "plateau_err": plat[0], "plateau_l_err": plat[1],
            "wall_s": s["wall_s"],
            "cpu_s": r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime,
            "steps": s["steps"], "rhs_evals": s["rhs_evals"],
            "particle_steps": s["particle_steps"], "invocation": INVOCATION}


def loglog_slope(a, b, key):
    """Slope of log(key) against log(cells) between rows a and b."""
    return math.log(b[key] / a[key]) / math.log(b["cells"] / a["cells"])


def orders(rows):
    """Observed order per doubling (by the rows' cell counts, ascending) and overall."""
    per = [-loglog_slope(a, b, "l1") for a, b in zip(rows, rows[1:])]
    overall = -loglog_slope(rows[0], rows[-1], "l1") if len(rows) > 1 else float("nan")
    return per, overall


def equal_error(rows, target=FV_L1):
    """Resolution, wall time and particle-steps at which the method reaches the L1 `target`.
    Measured (log-log interpolation between the two bracketing runs) when some run reaches
    it; otherwise extrapolated from the finest run with the observed order and the wall-time
    (and particle-step) growth of the last doubling (marked as extrapolated). None if the
    error does not fall. The row it came from is returned as 'rows' (for the invocations)."""
    rows = [dict(r, particle_rhs=r["rhs_evals"] * r["particles"]) for r in rows]
    keys = ("wall_s", "particle_steps", "particle_rhs") + \
        (("cpu_s",) if all("cpu_s" in r for r in rows) else ())
    for a, b in zip(rows, rows[1:]):
        if a["l1"] > target >= b["l1"]:
            f = math.log(target / a["l1"]) / math.log(b["l1"] / a["l1"])
            out = {k: a[k] * (b[k] / a[k]) ** f for k in keys}
            out.update(cells=a["cells"] * (b["cells"] / a["cells"]) ** f, rows=(a, b),
                       how="interpolated between measured runs")
            return out
    if rows[0]["l1"] <= target:
        out = {k: rows[0][k] for k in keys}
        out.update(cells=rows[0]["cells"], rows=(rows[0],),
                   how="the coarsest run reaches it: an upper bound")
        return out
    if len(rows) < 2:
        return None
    a, b = rows[-2], rows[-1]
    p = -loglog_slope(a, b, "l1")
    if not p > 0:
        return None
    n = b["cells"] * (b["l1"] / target) ** (1 / p)
    out = {k: b[k] * (n / b["cells"]) ** loglog_slope(a, b, k) for k in keys}
    out.update(cells=n, rows=(a, b),
               how=f"extrapolated ×{n / b['cells']:.2f} in cells (order {p:.2f} of the last "
               "doubling)")
    return out


def by_method(rows):
    """mpmfsi's rows per method (the finite-volume rows, method 'fv', apart)."""
    out = {}
    for m in METHODS + sorted({r["method"] for r in rows} - set(METHODS) - {"fv"}):
        mr = sorted((r for r in rows if r["method"] == m), key=lambda r: r["cells"])
        if mr:
            out[m] = mr
    return out


def fv_rows(rows):
    return sorted((r for r in rows if r["method"] == "fv"), key=lambda r: r["cells"])


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.8))
    groups = dict(by_method(rows))
    if fv_rows(rows):
        groups["finite volume (MUSCL–Hancock + HLLC)"] = fv_rows(rows)
    for m, mr in groups.items():
        style = "s--" if m.startswith("finite") else "o-"
        line, = ax.loglog([r["wall_s"] for r in mr], [r["l1"] for r in mr], style, label=m)
        for r in mr:
            ax.annotate(str(r["cells"]), (r["wall_s"], r["l1"]), fontsize=7,
                        color=line.get_color(), xytext=(3, 3), textcoords="offset points")
    if PROBLEM == "sod":
        ax.axhline(FV_L1, color="k", ls=":", lw=0.8, label="finite-volume Godunov, 400 cells")
    ax.set_xlabel("wall time, s (1 core, shared machine)")
    ax.set_ylabel(f"L1 density error at t = {T:g}")
    ax.set_title(f"{PAGES[PROBLEM][1]} (labels: cells)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(BASE + ".png", dpi=120)


def sci(x):
    return f"{x:.2e}"


def pct(x):
    return "" if x is None or x != x else f"{100 * x:+.2f} %"


def page(rows):
    """The results page: the table, the orders, the equal-error comparisons."""
    groups = by_method(rows)
    name = PAGES[PROBLEM][0]
    L = [f"# {PAGES[PROBLEM][1]} (bench/bench_sod.py --problem {PROBLEM})", "",
         f"{PAGES[PROBLEM][2]}, quadratic B-splines, 2 particles per cell "
         "per direction. usl, musl (FLIP) and ssprk2 at time.cfl 0.4; bs32, zonneveld43 and dp54 "
         "at the case's time settings when the row was measured (each row's invocation and "
         "commit are in the JSON; since 2026-12-02 the shock-tube cases take a fixed step at "
         "time.cfl 0.8, before that adaptive at atol 1e-4). Error: L1 of the cell-averaged density "
         "against the exact solution, as `test_sod` measures it (`tests/tools/shocktube.py`, "
         "`tests/tools/riemann.py`). One rank. Raw rows: "
         f"[csv]({name}.csv), [json]({name}.json).", "",
         f"![L1 density error against wall time]({name}.png)", "",
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
    for m, mr in list(groups.items()) + ([("fv", fv_rows(rows))] if fv_rows(rows) else []):
        per, overall = orders(mr)
        span = f"{mr[0]['cells']}→{mr[-1]['cells']}"
        L.append(f"| {m} | " + ", ".join(f"{p:.2f}" for p in per) + f" | {overall:.2f} ({span}) |")
    if PROBLEM == "sod":
        L += quoted_fv_section(groups)
    L += ratio_section(rows, groups)
    if PROBLEM == "toro3_moving":
        L += galilean_section(rows)
    return "\n".join(L) + "\n"


def quoted_fv_section(groups):
    L = ["", f"## Against the finite-volume Godunov figure ({FV_L1:g} at {FV_N} cells)", "",
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
    return L


def ratio_section(rows, groups):
    """Each method's cost at the finite-volume solver's error, over the solver's cost."""
    fv = fv_rows(rows)
    L = ["", "## Cost at equal error against the finite-volume reference in the same strip", ""]
    if not fv:
        return L + ["No finite-volume rows (run without `--fv-cells none`)."]
    L += ["Reference: `bench/fv_strip.py`, the MUSCL–Hancock / HLLC solver of "
          "`bench/euler_reference.py` (van Leer limiter, CFL 0.8 on the 2-D rate) on the same "
          "N × 3 strip and problem, its cell densities measured against the same exact cell "
          "averages. What each wall time counts: mpmfsi's is `summary.json`'s `wall_s` (the "
          "whole run: set-up, steps, one snapshot), the reference's only its numpy step loop "
          "(no set-up, no output; one core); the CPU times (user + system: mpmfsi's process from "
          "the harness's rusage, the reference's loop by process_time) are the steadier measure "
          "on a loaded machine. Cost units: mpmfsi's particle-steps (particles × "
          "steps; each step of bs32 is 3 RHS evaluations, one P2G/grid/G2P each) against the "
          "reference's cell-steps (cells × steps; one flux evaluation per cell face each), and "
          "mpmfsi's particle-RHS (particles × RHS evaluations: bs32 pays three a step) against "
          "the same. The reference is numpy: about 0.3–1 M cell-steps/s on this machine, where "
          "a compiled finite-volume code does some 100 times more, so the wall ratio flatters "
          "mpmfsi against a compiled anchor; the work ratios do not depend on that.", "",
          "| FV cells | FV L1 | FV shock offset (cells) | FV wall s | FV steps | "
          "M cell-steps |", "|---|---|---|---|---|---|"]
    for r in fv:
        L.append(f"| {r['cells']} | {sci(r['l1'])} | {r['shock_offset_cells']:+.2f} | "
                 f"{r['wall_s']:.3f} | {r['steps']} | {r['particle_steps'] / 1e6:.2f} |")
    L += ["", "Per method, at each reference run's L1: the cells and wall time mpmfsi needs for "
          "it (as in the table above: log-log interpolation between the two runs that bracket "
          "it, or extrapolation from the finest run), and the ratios of its wall time and of "
          "its particle-steps to the reference's wall time and cell-steps at that run. "
          f"Where reaching it would take more than {MAX_EXTRAPOLATION}× the finest run's cells, "
          "only lower bounds (the finest run's cost) are given; "
          "† marks a ratio between rows of different invocations.", "",
          "| method | FV cells | target L1 | mpmfsi cells | mpmfsi wall s | **wall ratio** | "
          "CPU ratio | particle-steps / cell-steps | particle-RHS / cell-steps | how |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for m, mr in groups.items():
        for f in fv:
            eq = equal_error(mr, f["l1"])
            if eq is None:
                best = min(mr, key=lambda r: r["l1"])
                L.append(f"| {m} | {f['cells']} | {sci(f['l1'])} | not reached | | | | | | "
                         f"the error does not fall (best L1 {sci(best['l1'])} at "
                         f"{best['cells']} cells) |")
                continue
            mixed = any(r.get("invocation") != f.get("invocation") for r in eq["rows"])
            fine = mr[-1]
            if eq["cells"] > MAX_EXTRAPOLATION * fine["cells"]:
                # too far to trust the extrapolation: the finest run's cost is a lower bound
                L.append(f"| {m} | {f['cells']} | {sci(f['l1'])} | > {fine['cells']} | "
                         f"> {fine['wall_s']:.3g} | **> {fine['wall_s'] / f['wall_s']:.3g}**"
                         f"{' †' if mixed else ''} | {cpu_ratio(fine, f, '> ')} | "
                         f"> {fine['particle_steps'] / f['particle_steps']:.3g} | "
                         f"> {fine['rhs_evals'] * fine['particles'] / f['particle_steps']:.3g}"
                         " | not reached "
                         f"(L1 {sci(fine['l1'])} at {fine['cells']} cells; the order of the "
                         f"last doubling would need ×{eq['cells'] / fine['cells']:.3g} in "
                         "cells): lower bounds from the finest run |")
                continue
            L.append(f"| {m} | {f['cells']} | {sci(f['l1'])} | {eq['cells']:.0f} | "
                     f"{eq['wall_s']:.3g} | **{eq['wall_s'] / f['wall_s']:.3g}**"
                     f"{' †' if mixed else ''} | {cpu_ratio(eq, f, '')} | "
                     f"{eq['particle_steps'] / f['particle_steps']:.3g} | "
                     f"{eq['particle_rhs'] / f['particle_steps']:.3g} | {eq['how']} |")
    return L


def cpu_ratio(a, f, prefix):
    """CPU time of a (a row or an equal-error estimate) over the reference run f's."""
    if "cpu_s" not in a or "cpu_s" not in f:
        return ""
    return f"{prefix}{a['cpu_s'] / f['cpu_s']:.3g}"


def galilean_section(rows):
    """The moving problem against the same problem at rest (the toro3 page's rows)."""
    rest_path = os.path.join(RESULTS, PAGES["toro3"][0] + ".json")
    L = ["", "## Galilean invariance: moving (Toro 5) against at rest (Toro 3)", ""]
    if not os.path.exists(rest_path):
        return L + ["No rows at rest: run `bench/bench_sod.py --problem toro3` first."]
    rest = {(r["cells"], r["method"]): r for r in json.load(open(rest_path))}
    L += ["The same Riemann problem, its exact solution shifted by u t: L1 of the moving run "
          "over L1 at rest (1 for a Galilean-invariant method), and the star plateaux' "
          "density errors (the mean over the middle half of the exact plateau: left, between "
          "the fan's tail and the contact, relative to ρ*_L = 0.575; right, between the "
          "contact and the shock, relative to ρ*_R = 5.99). The finite-volume rows are the control: an Eulerian "
          "scheme is not Galilean invariant either (at rest its contact moves at 19.6 and "
          "smears; moving, the contact stands still).", "",
          "| cells | method | L1 at rest | L1 moving | moving / rest | left plateau at rest | "
          "left plateau moving | right plateau at rest | right plateau moving |",
          "|---|---|---|---|---|---|---|---|---|"]
    for m in METHODS + sorted({r["method"] for r in rows} - set(METHODS) - {"fv"}) + ["fv"]:
        for r in sorted((r for r in rows if r["method"] == m), key=lambda r: r["cells"]):
            a = rest.get((r["cells"], m))
            if a is None:
                continue
            L.append(f"| {r['cells']} | {m} | {sci(a['l1'])} | {sci(r['l1'])} | "
                     f"{r['l1'] / a['l1']:.2f} | {pct(a.get('plateau_l_err'))} | "
                     f"{pct(r.get('plateau_l_err'))} | {pct(a.get('plateau_err'))} | "
                     f"{pct(r.get('plateau_err'))} |")
    return L


def measure_fv(N, repeat):
    runs = [fv_strip.solve(PROBLEM, N) for _ in range(repeat)]
    r = min(runs, key=lambda x: x["wall_s"])
    r["invocation"] = INVOCATION
    for k in ("first_order_steps", "transverse_spread"):
        r.pop(k)
    print(f"N {N:5d} {'fv':<12} L1 {r['l1']:.3e} shock {r['shock_offset_cells']:+.2f}"
          f" cells  wall {r['wall_s']:7.3f} s  steps {r['steps']:6d}", flush=True)
    return r


def main():
    os.makedirs(RESULTS, exist_ok=True)
    rows = json.load(open(BASE + ".json")) if os.path.exists(BASE + ".json") else []
    repeat = int(arg("--repeat", ["1"])[0])
    report = "--report" in sys.argv

    def keep(r):
        nonlocal rows
        rows = [x for x in rows if (x["cells"], x["method"]) != (r["cells"], r["method"])] + [r]
        json.dump(rows, open(BASE + ".json", "w"), indent=1)
    for N in [] if report else arg("--fv-cells", FV_CELLS, int):
        keep(measure_fv(N, repeat))
    for N in [] if report else arg("--cells", CELLS, int):
        for method in arg("--methods", METHODS):
            runs = [run(N, method) for _ in range(repeat)]
            r = min(runs, key=lambda x: x["wall_s"])
            print(f"N {N:5d} {method:<12} L1 {r['l1']:.3e} shock {r['shock_offset_cells']:+.2f}"
                  f" cells  wall {r['wall_s']:7.2f} s  steps {r['steps']:6d}  rhs "
                  f"{r['rhs_evals']:6d}", flush=True)
            keep(r)
    if not rows:
        sys.exit(f"bench_sod.py: no rows in {BASE}.json; run without --report first")
    rows.sort(key=lambda x: (METHODS.index(x["method"]) if x["method"] in METHODS else
                             (100 if x["method"] == "fv" else 99), x["cells"]))
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    with open(BASE + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
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
