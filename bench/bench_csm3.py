#!/usr/bin/python3
"""Work-precision of the time methods on Turek-Hron CSM3 (cases/csm3.ini, St. Venant-Kirchhoff,
first five periods): frequency and uy-amplitude errors against the reference (1.0995 Hz,
65.160 mm; validation/turek_hron_csm3_dynamic.csv) and the wall time, over three cell sizes
and each time method.

Usage: /usr/bin/python3 bench/bench_csm3.py [--dx 0.01,0.005,0.0025] [--methods usl,musl,bs32]
(from the repository root after building). Results accumulate in
bench/results/csm3_work_precision.json (a run replaces the rows it repeats), and the CSV
table and the plot csm3_work_precision.png are rewritten from all rows. Wall times on a
shared 2-core machine are noisy: compare within one invocation.
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import tip_response  # noqa: E402

BIN = os.path.join(ROOT, "build", "app", "mpmfsi")
RESULTS = os.path.join(ROOT, "bench", "results")
JSON = os.path.join(RESULTS, "csm3_work_precision.json")
F_REF, A_REF = 1.0995, 65.160


def arg(name, default):
    return sys.argv[sys.argv.index(name) + 1].split(",") if name in sys.argv else default


def run(dx, method):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([BIN, "run", os.path.join(ROOT, "cases", "csm3.ini"), f"output.dir={out}",
                        f"grid.dx={dx}", f"time.method={method}", "run.progress=false"],
                       check=True, capture_output=True)
        s = json.load(open(os.path.join(out, "summary.json")))
        r = tip_response.response(out)
    return {"dx": float(dx), "method": method, "wall_s": s["wall_s"], "steps": s["steps"],
            "rhs_evals": s["rhs_evals"], "freq_hz": r["freq"], "amp_mm": r["amp"],
            "mean_mm": r["mean"], "freq_err_pct": 100 * (r["freq"] - F_REF) / F_REF,
            "amp_err_pct": 100 * (r["amp"] - A_REF) / A_REF}


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, label in ((axes[0], "freq_err_pct", "|frequency error| %"),
                           (axes[1], "amp_err_pct", "|uy amplitude error| %")):
        for method in sorted({r["method"] for r in rows}):
            pts = sorted((r["wall_s"], abs(r[key]), r["dx"]) for r in rows if r["method"] == method)
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=method)
            for w, e, dx in pts:
                ax.annotate(f"{1e3 * dx:g} mm", (w, e), fontsize=7)
        ax.axhline(2 if key == "freq_err_pct" else 5, color="k", ls=":", lw=0.8)
        ax.set_xlabel("wall time, s (1 core)")
        ax.set_ylabel(label)
        ax.legend()
    fig.suptitle("CSM3 work-precision (dotted: acceptance tolerance)")
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "csm3_work_precision.png"), dpi=120)


def main():
    rows = json.load(open(JSON)) if os.path.exists(JSON) else []
    for dx in arg("--dx", ["0.01", "0.005", "0.0025"]):
        for method in arg("--methods", ["usl", "musl", "bs32"]):
            r = run(dx, method)
            rows = [x for x in rows if (x["dx"], x["method"]) != (r["dx"], r["method"])] + [r]
            print(f"dx {r['dx']:<7g} {method:<12} wall {r['wall_s']:8.1f} s  steps {r['steps']:7d}"
                  f"  freq {r['freq_hz']:.4f} Hz ({r['freq_err_pct']:+.2f} %)  amp "
                  f"{r['amp_mm']:.2f} mm ({r['amp_err_pct']:+.2f} %)", flush=True)
            json.dump(rows, open(JSON, "w"), indent=1)
    rows.sort(key=lambda x: (x["method"], -x["dx"]))
    with open(os.path.join(RESULTS, "csm3_work_precision.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot(rows)


if __name__ == "__main__":
    main()
