#!/usr/bin/python3
"""Coupled throughput: particle-steps per second of the gas and the solid together on one grid,
for each coupling scheme (velocity, contact, traction) against the same scene run with
`coupling.scheme = none` (both modules run, no interaction), usl, 2-D, on 1 rank and 2 ranks,
with the coupler's own share of the run time (the `coupling` phase of timers.csv over `total`).

The scene (bench/bench_coupling.ini): a periodic unit box, dx = 1/256, quadratic B-splines,
2 particles per cell per direction in both phases: an elastic neo-Hookean block
[0.25, 0.75]^2 (65 536 particles) in gas (the box minus the block, 196 608 particles) with a
gaussian pressure pulse beside it; 262 144 particles in all. The step is pinned with
time.dt_max = 1e-4 (below every scheme's stable step; with `none` the gas expands into the
block's space and its own stable step falls to about 2e-4), so that every run takes the same
200 steps to t = 0.02.

Usage: /usr/bin/python3 bench/bench_coupling.py [--quick] [--repeat N] [--ranks 1,2]
       [--schemes velocity,contact,traction] [--bin PATH] [--out NAME]
(run from the repository root after building). The runs use a copy of the binary taken at
the start (a rebuild during the measurement cannot mix builds). Each repeat runs every
(ranks, scheme) once,
`none` included, in an order that rotates from repeat to repeat, so that the load of a shared
machine falls on all of them alike; the best and the median throughput are reported, the
per-phase split is that of the median run, and the ratio to `none` is taken both between the
medians and run by run within a repeat (the median of those paired ratios). Writes
bench/results/NAME.csv, .json and .md (NAME = coupling_throughput; the .md keeps whatever
follows its notes line) and prints a table. --quick: dx = 1/128 (65 536 particles), 20 steps,
one repeat, results to NAME_quick.* in the temporary directory (a smoke test of the driver,
not a measurement).

Phases (timers.csv, wall seconds summed over the run, mean over the ranks): coupling is the
schemes' hooks and the interpenetration sum; it runs inside the grid phase, whose figure
includes it. What a scheme costs outside its hooks (the solid's mass-gradient deposit in P2G
and its reverse halo for contact and traction, the per-step coupling.csv row under io and
diagnostics) shows in the ratio to `none`, not in the coupling share.
"""
import csv
import hashlib
import json
import os
import resource
import shutil
import statistics
import sys
import tempfile
import time

from benchrun import ROOT, git, run_case  # noqa: E402

# Phases that do not nest (coupling runs inside grid, so it is left out of the sum for other).
PHASES = ["p2g", "stress", "grid", "g2p", "halo", "check", "stable", "boundary", "migrate",
          "post_step", "diagnostics", "io"]
TARGET_SHARE = 0.15  # the coupling's own share of a step


def option(name, default):
    if name in sys.argv:
        return sys.argv[sys.argv.index(name) + 1]
    return default


quick = "--quick" in sys.argv
REPEAT = int(option("--repeat", "1" if quick else "3"))
RANKS = [int(r) for r in option("--ranks", "1,2").split(",")]
SCHEMES = ["none"] + [s for s in option("--schemes", "velocity,contact,traction").split(",")
                      if s != "none"]
BIN = option("--bin", os.path.join(ROOT, "build", "app", "mpmfsi"))
OUTNAME = option("--out", "coupling_throughput") + ("_quick" if quick else "")
CASE = os.path.join(ROOT, "bench", "bench_coupling.ini")

CELLS = 128 if quick else 256  # per side of the unit box
DT = 1e-4                      # the pinned step
STEPS = 20 if quick else 200


def cpu_seconds():
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_once(scheme, ranks):
    cpu0 = cpu_seconds()
    summary, timers = run_case(
        BIN, CASE,
        [f"grid.dx={1.0 / CELLS}", f"coupling.scheme={scheme}", "time.method=usl",
         f"time.dt_max={DT}", f"time.t_end={STEPS * DT}"], ranks)
    cpu = cpu_seconds() - cpu0  # every process of the run (mpiexec and the ranks), start-up too
    steps = summary["steps"]
    n = summary["particle_steps"] / max(steps, 1)
    total = timers.get("total", summary["wall_s"])
    split = {k: timers.get(k, 0.0) for k in PHASES + ["coupling"]}
    split["other"] = total - sum(split[k] for k in PHASES)
    return {"scheme": scheme, "ranks": ranks, "particles": int(round(n)), "steps": steps,
            "rhs_evals": summary["rhs_evals"], "wall_s": summary["wall_s"],
            "particle_steps_per_s": summary["particle_steps_per_s"], "total_s": total,
            "cpu_s": cpu, "particle_steps_per_cpu_s": summary["particle_steps"] / cpu,
            "coupling_share": split["coupling"] / total,
            "coupling_imbalance": summary.get("coupling_imbalance", 0.0),
            **{f"t_{k}": v for k, v in split.items()}}


def snapshot(tmp):
    """Run a copy of the binary, so that a rebuild during the measurement cannot mix builds."""
    global BIN
    copy = os.path.join(tmp, "mpmfsi")
    shutil.copy2(BIN, copy)
    BIN = copy


def provenance():
    dirty = git("status", "--porcelain", "--", "common", "fluid", "solid", "coupler", "app",
                "CMakeLists.txt")
    return {"commit": git("rev-parse", "--short", "HEAD"),
            "sources_modified": bool(dirty and dirty != "unknown"),
            "binary": BIN,
            "binary_sha256": hashlib.sha256(open(BIN, "rb").read()).hexdigest()[:16],
            "binary_mtime": time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(os.path.getmtime(BIN))),
            "date": time.strftime("%Y-%m-%d %H:%M"), "loadavg_before": os.getloadavg()[0]}


def measure():
    """All runs, interleaved: {(ranks, scheme): [run per repeat]}."""
    configs = [(r, s) for r in RANKS for s in SCHEMES]
    runs = {c: [] for c in configs}
    for rep in range(REPEAT):
        k = rep % len(configs)
        for ranks, scheme in configs[k:] + configs[:k]:
            r = run_once(scheme, ranks)
            r["repeat"] = rep
            r["loadavg"] = os.getloadavg()[0]
            runs[(ranks, scheme)].append(r)
            print(f"  repeat {rep + 1}/{REPEAT} {ranks} rank(s) {scheme:>8}: "
                  f"{r['particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s, {r['steps']} steps, "
                  f"coupling {100 * r['coupling_share']:.2f} % of {r['total_s']:.2f} s, "
                  f"{r['particle_steps_per_cpu_s'] / 1e6:.2f} M per CPU-s, load {r['loadavg']:.1f}",
                  flush=True)
    return runs


def summarise(runs):
    rows = []
    for (ranks, scheme), rs in runs.items():
        rates = sorted(r["particle_steps_per_s"] for r in rs)
        med = statistics.median(rates)
        row = dict(min(rs, key=lambda r: abs(r["particle_steps_per_s"] - med)))  # median run
        shares = [r["coupling_share"] for r in rs]
        cpu_rates = [r["particle_steps_per_cpu_s"] for r in rs]
        row.update(repeats=len(rs), best_particle_steps_per_s=rates[-1],
                   median_particle_steps_per_s=med, all_particle_steps_per_s=rates,
                   median_coupling_share=statistics.median(shares), max_coupling_share=max(shares),
                   median_particle_steps_per_cpu_s=statistics.median(cpu_rates))
        row.pop("repeat", None)
        rows.append(row)
    for row in rows:
        base = next(b for b in rows if b["ranks"] == row["ranks"] and b["scheme"] == "none")
        pair = [c["particle_steps_per_s"] / n["particle_steps_per_s"]
                for c in runs[(row["ranks"], row["scheme"])]
                for n in runs[(row["ranks"], "none")] if c["repeat"] == n["repeat"]]
        row["ratio_to_none_best"] = row["best_particle_steps_per_s"] / base["best_particle_steps_per_s"]
        row["ratio_to_none_median"] = (row["median_particle_steps_per_s"] /
                                       base["median_particle_steps_per_s"])
        row["ratio_to_none_paired"] = statistics.median(pair)
        row["cpu_ratio_to_none"] = (row["median_particle_steps_per_cpu_s"] /
                                    base["median_particle_steps_per_cpu_s"])
        row["same_steps_as_none"] = row["steps"] == base["steps"]
    return rows


def ms_per_step(row, k):
    return 1e3 * row["t_" + k] / max(row["steps"], 1)


def page(rows, prov):
    L = ["# Coupled throughput (bench/bench_coupling.py)", "",
         "Gas and an elastic block on one grid (`bench/bench_coupling.ini`): periodic unit box, "
         f"dx = 1/{CELLS}, quadratic B-splines, 2 particles per cell per direction in both "
         "phases; neo-Hookean block [0.25, 0.75]² (ρ = 5, E = 50, ν = 0.3) in gas (the box minus "
         "the block, ρ = 1, p = 1 with a gaussian pulse of +0.5 centred at (0.125, 0.5)); "
         f"usl, the step pinned at {DT:g} (`time.dt_max`, below every scheme's stable step), "
         f"{STEPS} steps per run. `none` runs both modules on the same grid without interaction. "
         f"Measured on {prov['date']} with `/usr/bin/python3 bench/bench_coupling.py` "
         f"({REPEAT} repeats, interleaved) on commit {prov['commit']}"
         + (" with modified C sources" if prov["sources_modified"] else "")
         + f" (binary built {prov['binary_mtime']}, sha256 {prov['binary_sha256']}…); load average {prov['loadavg_before']:.2f} "
         f"before and {prov.get('loadavg_after', float('nan')):.2f} after. "
         f"Raw rows with the per-phase split of the median run: [csv]({OUTNAME}.csv), "
         f"[json]({OUTNAME}.json).", "",
         "Throughput in M particle-steps/s (both phases), best / median of the repeats. "
         "Coupling share: the `coupling` phase of timers.csv over `total`, median (max) over the "
         "repeats; target ≤ 15 %. Ratio to none: best / best, median / median, and the median "
         "of the run-by-run ratios within a repeat. Per CPU-s: particle-steps over the CPU "
         "seconds of every process of the run (median; less sensitive to other jobs than wall "
         "time, but on 2 ranks it counts MPI's busy waiting).", "",
         "| ranks | scheme | particles | steps | M particle-steps/s | coupling share | "
         "vs none: best | median | paired | M particle-steps per CPU-s (vs none) | target |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ok = "—" if r["scheme"] == "none" else (
            "met" if r["max_coupling_share"] <= TARGET_SHARE else "**not met**")
        L.append(f"| {r['ranks']} | {r['scheme']} | {r['particles']} | {r['steps']} | "
                 f"{r['best_particle_steps_per_s'] / 1e6:.2f} / "
                 f"{r['median_particle_steps_per_s'] / 1e6:.2f} | "
                 f"{100 * r['median_coupling_share']:.2f} % ({100 * r['max_coupling_share']:.2f} %) | "
                 f"{r['ratio_to_none_best']:.3f} | {r['ratio_to_none_median']:.3f} | "
                 f"{r['ratio_to_none_paired']:.3f} | "
                 f"{r['median_particle_steps_per_cpu_s'] / 1e6:.2f} ({r['cpu_ratio_to_none']:.3f}) | "
                 f"{ok} |")
    cols = ["p2g", "stress", "grid", "coupling", "g2p", "halo", "check", "stable", "boundary",
            "migrate", "post_step", "diagnostics", "io", "other"]
    L += ["", "Where the time goes (median run, ms per step; coupling is part of grid):", "",
          "| ranks | scheme | " + " | ".join(cols) + " | total |",
          "|---|---|" + "---|" * (len(cols) + 1)]
    for r in rows:
        L.append(f"| {r['ranks']} | {r['scheme']} | " +
                 " | ".join(f"{ms_per_step(r, k):.2f}" for k in cols) +
                 f" | {1e3 * r['total_s'] / max(r['steps'], 1):.1f} |")
    L += ["", "Rerun (from the repository root, after building `build/`, about "
          f"{'1' if quick else '8'} minutes; a quiet machine gives the figures that matter): "
          "`/usr/bin/python3 bench/bench_coupling.py` (`--repeat N`, `--ranks 1,2`, "
          "`--schemes velocity,contact,traction`, `--bin PATH`, `--quick` for a smoke test).", ""]
    return "\n".join(L)


NOTES = "<!-- notes: written by hand, kept when bench_coupling.py rewrites the tables above -->"


def main():
    prov = provenance()
    tmp = tempfile.TemporaryDirectory()
    snapshot(tmp.name)
    print(f"coupled throughput: {CELLS}^2 cells, {STEPS} steps, schemes {', '.join(SCHEMES)}, "
          f"ranks {RANKS}, {REPEAT} repeat(s); commit {prov['commit']}", flush=True)
    rows = summarise(measure())
    prov["loadavg_after"] = os.getloadavg()[0]
    mtime = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(os.path.getmtime(prov["binary"])))
    if mtime != prov["binary_mtime"]:
        print(f"note: {prov['binary']} was rebuilt during the measurement ({prov['binary_mtime']} "
              f"-> {mtime}); the runs used a copy of the build from the start", flush=True)
        prov["binary_rebuilt_during_run"] = mtime
    for r in rows:
        r.update(commit=prov["commit"], date=prov["date"])
        share = " ".join(f"{k} {100 * r['t_' + k] / r['total_s']:.0f}%"
                         for k in PHASES + ["coupling", "other"]
                         if r["t_" + k] > 0.005 * r["total_s"])
        print(f"{r['ranks']} rank(s) {r['scheme']:>8} {r['particles']} particles {r['steps']} steps: "
              f"best {r['best_particle_steps_per_s'] / 1e6:6.2f}, median "
              f"{r['median_particle_steps_per_s'] / 1e6:6.2f} M particle-steps/s; coupling share "
              f"{100 * r['median_coupling_share']:.2f} % (max {100 * r['max_coupling_share']:.2f} %);"
              f" vs none {r['ratio_to_none_median']:.3f} (paired {r['ratio_to_none_paired']:.3f},"
              f" per CPU-s {r['cpu_ratio_to_none']:.3f});"
              f" {share}", flush=True)
        if not r["same_steps_as_none"]:
            print(f"  warning: {r['steps']} steps, not the same as none's", flush=True)

    outdir = tempfile.gettempdir() if quick else os.path.join(ROOT, "bench", "results")
    os.makedirs(outdir, exist_ok=True)
    base = os.path.join(outdir, OUTNAME)
    keys = sorted({k for r in rows for k in r if k != "all_particle_steps_per_s"},
                  key=lambda k: (k not in ("ranks", "scheme"), k.startswith("t_"), k))
    with open(base + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    json.dump({"provenance": prov, "rows": rows}, open(base + ".json", "w"), indent=1)
    notes = ""
    if os.path.exists(base + ".md"):
        old = open(base + ".md").read()
        if NOTES in old:
            notes = old[old.index(NOTES) + len(NOTES):]
    with open(base + ".md", "w") as f:
        f.write(page(rows, prov) + "\n" + NOTES + (notes or "\n"))
    print("wrote", base + ".csv", ".json and .md")


if __name__ == "__main__":
    main()
