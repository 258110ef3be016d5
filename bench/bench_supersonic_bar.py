#!/usr/bin/python3
"""The main job under refinement, per spatial coupling scheme and time method: a
work-precision table for cases/supersonic_bar.ini (3 ms, 2 ranks).

For each run: whether it completed (or the message it stopped with), wall time, steps,
particle-steps, the bow shock's stand-off and the empty cells inside the gas at every snapshot
(tools/supersonic_bar.py), the tip displacement at 1.5 ms and its largest value, the interface
momentum imbalance and the energy the coupling created. Per scheme, the successive
differences of the stand-off (at 3 ms) and of the tip displacement (at 1.5 ms) over the
resolutions, and the error of each run against the finest `usl` run of the same scheme
(work-precision), plotted against wall time.

Usage (from the repository root, after building):
  /usr/bin/python3 bench/bench_supersonic_bar.py [--dx 0.004,0.003,0.002]
      [--schemes velocity,contact,traction] [--methods usl] [--cfl 0.8] [--ranks 2]
      [--timeout 1800] [--report]
Rows accumulate in bench/results/supersonic_bar_runs.json; a run whose row is there is not
repeated (an interrupted sweep resumes where it stopped; delete a row to redo it). Each run's
output stays in out/bench_supersonic_bar/<name>. The table (.md, .csv) and the plot (.png)
are rewritten from all rows; the page keeps whatever follows its NOTES line. Every run is
given its time.cfl on the command line (--cfl, default the case's); rows stored before the
step was recorded were run at 0.4, the case's value then, and are read as such. Wall times on a
shared 2-core machine are noisy: compare within one invocation.
"""
import argparse
import csv
import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np

from benchrun import ENV, ROOT  # noqa: E402

sys.path.insert(0, os.path.join(ROOT, "tools"))
sys.path.insert(0, os.path.join(ROOT, "tests", "tools"))
os.environ.setdefault("MPMFSI_BIN", os.path.join(ROOT, "build", "app", "mpmfsi"))
os.environ.setdefault("MPMFSI_SOURCE_DIR", ROOT)
import supersonic_bar as sb  # noqa: E402

RESULTS = os.path.join(ROOT, "bench", "results")
STORE = os.path.join(RESULTS, "supersonic_bar_runs.json")
PAGE = os.path.join(RESULTS, "supersonic_bar_work_precision")
OUT = os.path.join(ROOT, "out", "bench_supersonic_bar")
CASE = os.path.join(ROOT, "cases", "supersonic_bar.ini")
T_TIP = 0.0015
T_HIST = np.linspace(0.0, 0.003, 301)  # the tip history is kept on this grid (10 us)


CFL_BEFORE = 0.4  # time.cfl of the rows stored before each row recorded its own


def name_of(scheme, method, dx, cfl):
    return f"{scheme}_{method}_dx{dx * 1e3:g}mm_cfl{cfl:g}"


def measure(out):
    """The figures of a finished run folder."""
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.devnull, "w") as null:
        stdout, sys.stdout = sys.stdout, null
        try:
            sb.main(out)
        finally:
            sys.stdout = stdout
    with open(os.path.join(out, "standoff.csv")) as f:
        so = [(float(r["t"]), float(r["standoff_m"]), int(r["empty_cells_inside_gas"]))
              for r in csv.DictReader(f)]
    pr = np.genfromtxt(os.path.join(out, "probes.csv"), delimiter=",", names=True)
    return {"wall_s": s["wall_s"], "steps": s["steps"], "particle_steps": s["particle_steps"],
            "imbalance": s.get("coupling_imbalance"), "coupling_work": s.get("coupling_work"),
            "standoff": [[t, v] for t, v, _ in so], "empty": [[t, e] for t, _, e in so],
            "tip_ux_1p5ms": float(np.interp(T_TIP, pr["t"], pr["tip_ux"])),
            "tip_ux_max": float(np.nanmax(pr["tip_ux"])), "t_end": float(pr["t"][-1]),
            "tip_hist": np.interp(T_HIST, pr["t"], pr["tip_ux"]).tolist()}


def tip_hist(r):
    """A row's tip history on T_HIST; None for a row stored without one (measured before the
    history was kept) whose output folder is gone."""
    if "tip_hist" not in r:
        path = os.path.join(OUT, r["name"], "probes.csv")
        if not os.path.exists(path):
            return None
        pr = np.genfromtxt(path, delimiter=",", names=True)
        r["tip_hist"] = np.interp(T_HIST, pr["t"], pr["tip_ux"]).tolist()
    return np.array(r["tip_hist"])


def rms(a, b):
    """1e3 times the RMS difference of two tip histories (mm); None if either is missing."""
    return None if a is None or b is None else 1e3 * float(np.sqrt(np.mean((a - b)**2)))


def stop_message(log, out, code):
    """Why a run stopped: its error line, or for a run stopped by a signal (exit code 3, e.g.
    after --timeout) where it was and the step it had fallen to (diagnostics.csv)."""
    err = [ln for ln in log.splitlines() if re.match(r"(\[\d+\] )?error:", ln)]
    if err:
        return err[0]
    try:
        d = np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)
        return (f"stopped (exit code {code}) at t = {d['t'][-1]:.4g} s after {int(d['step'][-1])} "
                f"steps, the step at {d['dt'][-1]:.2g} s (the first {d['dt'][1]:.2g} s)")
    except (OSError, ValueError, IndexError):
        return f"exit code {code}"


def run_one(scheme, method, dx, cfl, ranks, timeout):
    name = name_of(scheme, method, dx, cfl)
    out = os.path.join(OUT, name)
    cmd = [os.environ["MPMFSI_BIN"], "run", CASE, f"output.dir={out}", "output.overwrite=true",
           f"grid.dx={dx}", f"coupling.scheme={scheme}", f"time.method={method}",
           f"time.cfl={cfl}", "run.progress=false"]
    if method not in ("usl", "musl"):  # the case's PIC share is for the classic update only
        cmd.append("fluid.pic_fraction=0")
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    t0 = time.time()
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        stdout, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:  # SIGTERM: mpmfsi ends after its step, exit code 3
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate()
    p = subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr)
    row = {"name": name, "scheme": scheme, "method": method, "dx": dx, "cfl": cfl,
           "ranks": ranks, "ok": p.returncode == 0}
    if p.returncode != 0:
        row["message"] = stop_message(p.stdout + p.stderr, out, p.returncode)
        row["wall_s"] = time.time() - t0
    else:
        row.update(measure(out))
    return row


def load():
    """The stored rows; one stored before rows recorded their time.cfl gets CFL_BEFORE, and
    its name the suffix name_of gives."""
    if not os.path.exists(STORE):
        return []
    with open(STORE) as f:
        rows = json.load(f)
    for r in rows:
        if "cfl" not in r:
            r["cfl"] = CFL_BEFORE
            r["name"] = name_of(r["scheme"], r["method"], r["dx"], CFL_BEFORE)
    return rows


def at(series, t):
    """The value of a [[t, v], ...] series at time t (the nearest snapshot)."""
    s = np.array(series)
    return float(s[np.argmin(abs(s[:, 0] - t)), 1]) if len(s) else float("nan")


def standoff_mean(r):
    """The stand-off averaged over the snapshots from 1.5 to 3 ms (the bow shock moves with
    the bar's swing: one snapshot's value carries that motion)."""
    v = [x for t, x in r["standoff"] if t >= 0.0015 - 1e-9]
    return float(np.mean(v)) if v else float("nan")


def observed_order(h, d):
    """The p for which differences d[0], d[1] between runs at h[0], h[1], h[2] are those of an
    error C h^p: d0 / d1 = (h0^p - h1^p) / (h1^p - h2^p); None outside 0.05 < p < 8."""
    def f(p):
        return (h[0]**p - h[1]**p) / (h[1]**p - h[2]**p) - d[0] / d[1]
    lo, hi = 0.05, 8.0
    if d[1] <= 0 or f(lo) * f(hi) > 0:
        return None
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(lo) * f(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def successive(rows):
    """Per scheme, method and time.cfl, the differences between runs at successive dx (finest
    last), with the observed order of the tip history's differences over each three runs."""
    out = []
    for key in sorted({(r["scheme"], r["method"], r["cfl"]) for r in rows if r["ok"]}):
        runs = sorted((r for r in rows
                       if r["ok"] and (r["scheme"], r["method"], r["cfl"]) == key),
                      key=lambda r: -r["dx"])
        d = [rms(tip_hist(a), tip_hist(b)) for a, b in zip(runs, runs[1:])]
        for k, (a, b) in enumerate(zip(runs, runs[1:])):
            order = (observed_order([r["dx"] for r in runs[k - 1:k + 2]], d[k - 1:k + 1])
                     if k > 0 and None not in d[k - 1:k + 1] else None)
            out.append([key[0], key[1], key[2], f"{1e3 * a['dx']:g} - {1e3 * b['dx']:g}", d[k],
                        1e3 * abs(a["tip_ux_1p5ms"] - b["tip_ux_1p5ms"]),
                        1e3 * abs(at(a["standoff"], 0.003) - at(b["standoff"], 0.003)),
                        1e3 * abs(standoff_mean(a) - standoff_mean(b)), order])
    return out


def report(rows):
    ok = [r for r in rows if r["ok"]]
    ref = {}  # per scheme: the finest usl run (of those, the smallest step)
    for r in ok:
        f = ref.get(r["scheme"])
        if r["method"] == "usl" and (f is None or (r["dx"], r["cfl"]) < (f["dx"], f["cfl"])):
            ref[r["scheme"]] = r
    table = []
    for r in sorted(rows, key=lambda r: (r["scheme"], r["method"], -r["cfl"], -r["dx"])):
        e = {"name": r["name"], "scheme": r["scheme"], "method": r["method"],
             "dx_mm": 1e3 * r["dx"], "cfl": r["cfl"], "ok": r["ok"],
             "wall_s": round(r["wall_s"], 1)}
        if r["ok"]:
            f = ref.get(r["scheme"])
            so3, so15 = at(r["standoff"], 0.003), at(r["standoff"], 0.0015)
            e.update({"steps": r["steps"], "Mps_per_s": r["particle_steps"] / r["wall_s"] / 1e6,
                      "standoff_1p5ms_mm": 1e3 * so15, "standoff_3ms_mm": 1e3 * so3,
                      "standoff_mean_mm": 1e3 * standoff_mean(r),
                      "tip_ux_1p5ms_mm": 1e3 * r["tip_ux_1p5ms"],
                      "tip_ux_max_mm": 1e3 * r["tip_ux_max"],
                      "empty_cells_max": max(v for _, v in r["empty"]),
                      "imbalance": r["imbalance"], "coupling_work_J": r["coupling_work"]})
            if f is not None and f is not r:
                e["tip_err_mm"] = 1e3 * abs(r["tip_ux_1p5ms"] - f["tip_ux_1p5ms"])
                e["standoff_err_mm"] = 1e3 * abs(so3 - at(f["standoff"], 0.003))
                a, b = tip_hist(r), tip_hist(f)
                e["tip_hist_rms_err_mm"] = rms(a, b)
                if a is not None and b is not None:
                    e["tip_hist_max_err_mm"] = 1e3 * float(np.abs(a - b).max())
        else:
            e["message"] = r["message"]
        table.append(e)
    cols = ["scheme", "method", "dx_mm", "cfl", "ok", "wall_s", "steps", "Mps_per_s",
            "standoff_1p5ms_mm", "standoff_3ms_mm", "standoff_mean_mm", "tip_ux_1p5ms_mm", "tip_ux_max_mm",
            "empty_cells_max", "imbalance", "coupling_work_J", "tip_err_mm", "standoff_err_mm",
            "tip_hist_rms_err_mm", "tip_hist_max_err_mm", "message"]
    with open(PAGE + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(table)

    def fmt(v):
        if isinstance(v, float):
            return f"{v:.3g}"
        return "" if v is None else str(v)
    notes = ""
    if os.path.exists(PAGE + ".md"):
        text = open(PAGE + ".md").read()
        if "<!-- NOTES -->" in text:
            notes = text.split("<!-- NOTES -->", 1)[1]
    with open(PAGE + ".md", "w") as f:
        f.write("# supersonic_bar: refinement and work-precision (bench/bench_supersonic_bar.py)"
                "\n\nStand-off: bow shock to the bar's upstream face (tools/supersonic_bar.py); "
                "standoff_mean: over the snapshots from 1.5 to 3 ms; "
                "tip: probes.csv at 1.5 ms; cfl: time.cfl; errors against the finest usl run "
                "of the same scheme, at its smallest time.cfl (tip_hist: the RMS and the "
                "largest difference of the tip's ux(t) over "
                "0-3 ms); empty cells: the most, over the snapshots, of cells without gas whose "
                "four neighbours hold gas. Wall times on the shared 2-core machine, 2 ranks.\n\n")
        f.write("| " + " | ".join(cols) + " |\n|" + "---|" * len(cols) + "\n")
        for e in table:
            f.write("| " + " | ".join(fmt(e.get(c)) for c in cols) + " |\n")
        f.write("\nSuccessive differences (each run against the next finer one of the same "
                "scheme, method and time.cfl): tip history RMS over 0-3 ms, tip at 1.5 ms, "
                "stand-off at "
                "3 ms and its mean over 1.5-3 ms; and the observed order p of the tip history's differences over this "
                "and the coarser pair (the p for which they are those of an error C dx^p).\n\n"
                "| scheme | method | cfl | dx_mm | tip_hist_rms_diff_mm | tip_1p5ms_diff_mm | "
                "standoff_3ms_diff_mm | standoff_mean_diff_mm | order |\n"
                "|---|---|---|---|---|---|---|---|---|\n")
        for line in successive(rows):
            f.write("| " + " | ".join(fmt(v) for v in line) + " |\n")
        f.write("\n<!-- NOTES -->" + notes)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    keys = sorted({(e["scheme"], e["method"], e["cfl"]) for e in table})
    for (scheme, method, cfl), mark in zip(keys, "osd^v<>ph*x+"):
        pts = [e for e in table if (e["scheme"], e["method"], e["cfl"]) == (scheme, method, cfl)
               and "tip_err_mm" in e]
        if not pts:
            continue
        w = [e["wall_s"] for e in pts]
        axes[0].loglog(w, [max(e.get("tip_hist_rms_err_mm") or np.nan, 1e-3) for e in pts],
                       mark + "-", label=f"{scheme} {method} cfl {cfl:g}")
        axes[1].loglog(w, [max(e["standoff_err_mm"], 1e-2) for e in pts], mark + "-",
                       label=f"{scheme} {method} cfl {cfl:g}")
    axes[0].set_ylabel("tip ux(t) - finest, RMS over 0-3 ms, mm")
    axes[1].set_ylabel("|stand-off(3 ms) - finest|, mm")
    for ax in axes:
        ax.set_xlabel("wall time, s (2 ranks)"), ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(PAGE + ".png", dpi=100)
    plt.close(fig)
    print(f"wrote {PAGE}.md, .csv, .png")


def case_cfl():
    """time.cfl as the case file sets it (mpmfsi's default, 0.4, if it does not)."""
    import configparser
    c = configparser.ConfigParser(inline_comment_prefixes=("#", ";"))
    c.read(CASE)
    return c.getfloat("time", "cfl", fallback=0.4)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dx", default="0.004,0.003,0.002")
    ap.add_argument("--schemes", default="velocity,contact,traction")
    ap.add_argument("--methods", default="usl")
    ap.add_argument("--cfl", type=float, default=None,
                    help="time.cfl of every run (default: the case's)")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=1800,
                    help="wall seconds a run may take before it is stopped (recorded as such)")
    ap.add_argument("--report", action="store_true", help="only rewrite the table and plot")
    a = ap.parse_args()
    rows = load()
    cfl = a.cfl if a.cfl is not None else case_cfl()
    if not a.report:
        todo = [(s, m, float(d)) for s in a.schemes.split(",") for m in a.methods.split(",")
                for d in a.dx.split(",")]
        for k, (s, m, d) in enumerate(todo):
            if any(r["name"] == name_of(s, m, d, cfl) for r in rows):
                print(f"[{k + 1}/{len(todo)}] {name_of(s, m, d, cfl)}: done before, kept")
                continue
            print(f"[{k + 1}/{len(todo)}] {name_of(s, m, d, cfl)} ...", flush=True)
            row = run_one(s, m, d, cfl, a.ranks, a.timeout)
            rows = [r for r in load() if r["name"] != row["name"]] + [row]
            os.makedirs(RESULTS, exist_ok=True)
            with open(STORE + ".tmp", "w") as f:
                json.dump(rows, f, indent=1)
            os.replace(STORE + ".tmp", STORE)
            print(f"    {'ok' if row['ok'] else 'STOPPED: ' + row['message']}, "
                  f"{row['wall_s']:.0f} s", flush=True)
    report(rows)


if __name__ == "__main__":
    main()
