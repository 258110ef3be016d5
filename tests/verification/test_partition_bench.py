"""The partition-quality benchmark of the refinement (issue 51, item 5), at a reduced size.

1. Known answers of its parts: a 12 x 10 level split in two at x = 6 gives each rank 3 x 10
   ghost cells (ghost width 3; exact count); the exact rectilinear split of a row load whose
   heavy rows need narrow slabs equals a brute-force search over all splits (16; the greedy
   sweep under a bisected cap it replaced gives 18, and on the main job's 3-level map at 1024
   ranks it left the heaviest rank 66 % above the exact split's and 13 % above the unmoved
   planes'); the Morton curve puts a coarse block before the finer ones at its corner.
2. bench/bench_partition.py --reduced (the main job at 6 mm to 0.5 ms on 2 ranks, a 16^3 sphere,
   16 and 64 ranks, 2 and 3 levels, blocks of 8) into the build tree: every hierarchy is 2:1
   balanced (leaf levels of adjacent level-0 cells differ by <= 1: the buffer's purpose;
   without it the reduced run's maps jump by 2); every
   partition puts all the weight on some rank; moving the planes never raises the heaviest
   rank (wbox <= box: the optimiser is exact per axis and starts from the uniform planes); the
   curve's heaviest rank is at most the mean plus the heaviest block (exact: a rank takes the
   blocks whose weight's midpoint falls in its share) and, on the main job at 16 ranks, below
   the unweighted box's.
The load comparisons allow 1e-12 relative (the same sums in another order); the rest is exact.
No wall time is asserted.
"""
import itertools
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tools"))
import mpmtest as mt  # noqa: E402

SOURCE = os.path.abspath(mt.SOURCE)
sys.path.insert(0, os.path.join(SOURCE, "bench"))
import partition_methods as pq  # noqa: E402

check = mt.Checks("test_partition_bench")

# 1. Known answers.
A = np.zeros((12, 10), np.int64)
A[6:] = 1
cell, need = pq.halo_pairs(A, 3)
counts = np.bincount(need, minlength=2)
check(list(counts) == [30, 30], f"ghost cells of a 12 x 10 level split at x = 6: {list(counts)} "
      "(30 each)")

# Heavy rows after light ones: stretching the first slab pushes the second's minimum width into
# the heavy rows (found by a random search against brute force).
M = np.array([[2.0], [1], [4], [2], [4], [1], [9], [9], [5], [2]])


def bottleneck(s):
    return max(M[s[k]:s[k + 1]].sum() for k in range(len(s) - 1))


best = min(bottleneck((0,) + c + (10,)) for c in itertools.combinations(range(1, 10), 2)
           if min(np.diff((0,) + c + (10,))) >= 2)
got = bottleneck(pq._bottleneck_splits(M, 3, 2))
check(got == best, f"rectilinear split of 10 rows over 3 slabs of >= 2 rows: bottleneck {got} "
      f"(brute force {best}; the greedy sweep gave 18)")

keys = pq.morton(np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 0]]))
check(list(keys) == [0, 1, 2, 3, 4], f"Morton keys of (0,0) (1,0) (0,1) (1,1) (2,0): {list(keys)}")

# 2. The driver at a reduced size.
work = os.path.abspath(mt.outdir("partition_bench"))
binary = os.path.abspath(mt.BIN) if os.path.sep in mt.BIN else mt.BIN
r = subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "bench_partition.py"),
                    "--reduced", "--binary", binary, "--out", work], capture_output=True,
                   text=True)
check(r.returncode == 0, f"bench_partition.py --reduced exits 0 ({r.returncode}: "
      f"{r.stderr.strip()[-300:]})")
rows = []
if r.returncode == 0:
    with open(os.path.join(work, "partition_quality.json")) as f:
        rows = json.load(f)["rows"]
check(len(rows) == 24, f"{len(rows)} rows (24: main job 2 levels x 2 rank counts x 4 methods, "
      "sphere 2 x 4)")
jump = max((x["max_leaf_jump"] for x in rows), default=9)
check(jump <= 1, f"largest leaf-level jump between adjacent level-0 cells {jump} (2:1: <= 1)")
done = [x for x in rows if "imbalance" in x]
check(all(x["load_mean"] > 0 and x["imbalance"] >= 1 for x in done),
      "every partition holds the whole weight (mean load > 0, max/mean >= 1)")
by = {(x["scene"], x["levels"], x["block"], x["ranks"], x["method"]): x for x in done}
for (s, L, B, P, m), x in sorted(by.items()):
    if m == "wbox" and (s, L, B, P, "box") in by:
        box = by[(s, L, B, P, "box")]["load_max"]
        check(x["load_max"] <= box * (1 + 1e-12),
              f"{s} L={L} B={B} P={P}: wbox's heaviest rank {x['load_max']:.0f} <= box's {box:.0f}")
    if m == "sfc":
        bound = x["load_mean"] + x["block_w_max"]
        check(x["load_max"] <= bound * (1 + 1e-12),
              f"{s} L={L} B={B} P={P}: sfc's heaviest rank {x['load_max']:.0f} <= mean + "
              f"heaviest block {bound:.0f}")
for L in (2, 3):
    sfc = by.get(("supersonic_bar", L, 8, 16, "sfc"), {}).get("imbalance", 9)
    box = by.get(("supersonic_bar", L, 8, 16, "box"), {}).get("imbalance", 0)
    check(sfc < box, f"main job, {L} levels, 16 ranks: sfc max/mean {sfc:.3f} below box's "
          f"{box:.3f}")
sys.exit(check.finish())
