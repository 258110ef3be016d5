#!/usr/bin/env python3
"""Two builds of mpmfsi against each other on one case: wall time per run, in alternating pairs.

Runs CASE with binary A, then with binary B, PAIRS times (A B A B ...), on RANKS ranks, each to
the same end time, and takes each run's wall time from its summary.json (the step loop's own
clock, set-up excluded). Prints every pair and the median ratio A/B, checks that the two builds
took the same number of steps and wrote the same diagnostics.csv byte for byte (a change meant
to be bit-identical must), and writes the rows to OUT.json and OUT.csv. Each run's user CPU time
(of mpiexec and the ranks it waited for) is recorded too: unlike the wall time, another job on
the machine barely changes it. Pairing keeps the ratio meaningful when the shared machine's speed
drifts; compare ratios, not absolute times, across sessions.

  /usr/bin/python3 bench/bench_build_ab.py --a build/app/mpmfsi --b /path/to/old/mpmfsi \\
      --case cases/supersonic_bar.ini --t-end 4e-4 --pairs 5 --out bench/results/speed_ab
"""
import argparse
import csv
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def run(binary, case, ranks, t_end, extra):
    out = tempfile.mkdtemp(prefix="ab_")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_btl_vader_single_copy_mechanism="none",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    cmd = ["mpiexec", "-n", str(ranks), binary, "run", case, f"time.t_end={t_end}",
           f"output.dir={out}", "output.overwrite=true", "output.interval=1",
           "run.progress=false"] + extra
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    user_s = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before
    if p.returncode != 0:
        sys.exit(f"{binary} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "diagnostics.csv"), "rb") as f:
        diag = f.read()
    return {"wall_s": s["wall_s"], "user_s": user_s, "steps": s["steps"],
            "particle_steps": s["particle_steps"], "diag": diag}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--a", required=True, help="binary A (the new build)")
    ap.add_argument("--b", required=True, help="binary B (the baseline)")
    ap.add_argument("--case", default=os.path.join(HERE, "..", "cases", "supersonic_bar.ini"))
    ap.add_argument("--t-end", type=float, default=4e-4)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "speed_ab"))
    ap.add_argument("extra", nargs="*", help="key=value overrides for both builds")
    a = ap.parse_args()
    rows = []
    for k in range(a.pairs):
        ra = run(a.a, a.case, a.ranks, a.t_end, a.extra)
        rb = run(a.b, a.case, a.ranks, a.t_end, a.extra)
        rows.append({"pair": k, "a_wall_s": ra["wall_s"], "b_wall_s": rb["wall_s"],
                     "a_user_s": ra["user_s"], "b_user_s": rb["user_s"],
                     "a_steps": ra["steps"], "b_steps": rb["steps"],
                     "a_particle_steps": ra["particle_steps"],
                     "b_particle_steps": rb["particle_steps"],
                     "same_diagnostics": ra["diag"] == rb["diag"],
                     "ratio": ra["wall_s"] / rb["wall_s"], "user_ratio": ra["user_s"] / rb["user_s"]})
        print(f"pair {k}: A {ra['wall_s']:.2f} s ({ra['user_s']:.2f} s user), B "
              f"{rb['wall_s']:.2f} s ({rb['user_s']:.2f} s user), A/B {rows[-1]['ratio']:.3f} "
              f"(user {rows[-1]['user_ratio']:.3f}; {ra['steps']} / {rb['steps']} steps, "
              f"{ra['particle_steps']} / {rb['particle_steps']} particle-steps, diagnostics "
              f"{'identical' if rows[-1]['same_diagnostics'] else 'DIFFER'})", flush=True)
    ratios = [r["ratio"] for r in rows]
    user = [r["user_ratio"] for r in rows]
    summary = {"case": os.path.relpath(a.case, os.path.join(HERE, "..")), "t_end": a.t_end,
               "ranks": a.ranks, "extra": a.extra, "pairs": rows,
               "median_ratio": statistics.median(ratios), "min_ratio": min(ratios),
               "max_ratio": max(ratios), "median_user_ratio": statistics.median(user),
               "same_steps": all(r["a_steps"] == r["b_steps"] for r in rows),
               "same_diagnostics": all(r["same_diagnostics"] for r in rows)}
    print(f"A/B wall: median {summary['median_ratio']:.3f} (range {min(ratios):.3f}-"
          f"{max(ratios):.3f}); user CPU: median {summary['median_user_ratio']:.3f}; same step "
          f"counts: {summary['same_steps']}; same diagnostics: {summary['same_diagnostics']}")
    with open(a.out + ".json", "w") as f:
        json.dump(summary, f, indent=1)
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    return 0 if summary["same_steps"] and summary["same_diagnostics"] else 1


if __name__ == "__main__":
    sys.exit(main())
