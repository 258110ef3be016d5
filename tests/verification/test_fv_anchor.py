"""The finite-volume anchor of the gas benchmarks (issue 50, item 6).

1. bench/fv_strip.py's reference solver (euler_reference.py's MUSCL-Hancock / HLLC in the
   N x 3 strip) gives Sod L1 within 1.2e-3 ... 1.4e-3 at 400 cells: the figure quoted for a
   second-order finite-volume Godunov code (Athena++-like PLM-HLLC) is 1.3e-3, given to two
   digits (measured here 1.283e-3); the band is that rounding plus the limiters' spread.
   The moving strong shock (Toro 5) is solved with its contact at rest: its shock lies within
   1 cell of the exact position at 200 cells.
2. bench_sod.py --problem toro3, then toro3_moving, at tiny sizes (usl at 50 and 100 cells,
   the reference at 50 and 100) into a folder of the build tree: each writes its JSON, CSV,
   page and plot; the rows hold positive finite errors and walls; the page holds the ratio
   table with a wall ratio (or its lower bound) for each reference run, and the moving page the Galilean table
   with a moving/rest ratio for usl and fv at both sizes. No wall time is asserted.
"""
import csv
import json
import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

SOURCE = os.path.abspath(mt.SOURCE)
sys.path.insert(0, os.path.join(SOURCE, "bench"))
import fv_strip  # noqa: E402

check = mt.Checks("test_fv_anchor")
r = fv_strip.solve("sod", 400)
check(1.2e-3 <= r["l1"] <= 1.4e-3, f"reference Sod L1 at 400 cells {r['l1']:.4e} (1.2e-3 ... "
      "1.4e-3)")
r = fv_strip.solve("toro3_moving", 200)
check(abs(r["shock_offset_cells"]) <= 1.0,
      f"reference Toro 5 at 200 cells: shock {r['shock_offset_cells']:+.2f} cells (within 1)")

work = os.path.abspath(mt.outdir("fv_anchor"))
env = dict(os.environ, MPMFSI_BIN=os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN)
for problem, page in (("toro3", "strong_shock_work_precision"),
                      ("toro3_moving", "strong_shock_moving_work_precision")):
    p = subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "bench_sod.py"),
                        "--problem", problem, "--results", work, "--cells", "50,100",
                        "--methods", "usl", "--fv-cells", "50,100"],
                       env=env, capture_output=True, text=True, timeout=600)
    check(p.returncode == 0, f"{problem}: bench_sod.py exit {p.returncode} {p.stderr[-300:]}")
    base = os.path.join(work, page)
    check(all(os.path.getsize(base + e) > 0 for e in (".json", ".csv", ".md", ".png")
              if os.path.exists(base + e)) and
          all(os.path.exists(base + e) for e in (".json", ".csv", ".md", ".png")),
          f"{problem}: {page}.json, .csv, .md and .png written")
    rows = list(csv.DictReader(open(base + ".csv")))
    got = sorted((r["method"], int(r["cells"])) for r in rows)
    check(got == [("fv", 50), ("fv", 100), ("usl", 50), ("usl", 100)],
          f"{problem}: CSV rows {got}")
    ok = all(math.isfinite(float(r[k])) and float(r[k]) > 0 for r in rows
             for k in ("l1", "wall_s", "steps", "particle_steps"))
    check(ok, f"{problem}: every row's l1, wall_s, steps, particle_steps finite and positive")
    md = open(base + ".md").read()
    # a ratio, or a lower bound ("> x") where reaching the error is beyond the finest run
    ratios = re.findall(r"^\| usl \| (50|100) \| [0-9.e+-]+ \| (?:> )?\d+ \| (?:> )?[0-9.e+-]+ "
                        r"\| \*\*(?:> )?([0-9.e+-]+)\*\*", md, re.M)
    check(sorted(c for c, _ in ratios) == ["100", "50"] and
          all(float(v) > 0 for _, v in ratios),
          f"{problem}: ratio table has usl's wall ratio at both reference runs: {ratios}")
    if problem == "toro3_moving":
        gal = re.findall(r"^\| (50|100) \| (usl|fv) \| [0-9.e+-]+ \| [0-9.e+-]+ \| "
                         r"([0-9.]+) \| [+-][0-9.]+ % \| [+-][0-9.]+ % \|", md, re.M)
        check(len(gal) == 4 and all(float(v) > 0 for *_, v in gal),
              f"Galilean table: moving/rest for usl and fv at 50 and 100 cells: {gal}")
    json.load(open(base + ".json"))

sys.exit(check.finish())
