"""Partition quality of the refinement (issue 51, item 5) on 64, 256 and 1024 ranks, computed
from real block maps and weights without running them.

1. Flow fields: the main job (cases/supersonic_bar.ini) and RAE 2822 (cases/rae2822.ini) are
   run once on 2 ranks (or --bar-run / --rae-run name finished output folders), and their last
   snapshot's gas is averaged onto the level-0 cells. Level 0 is the case's own grid.
2. Flags (bench/partition_maps.py): pressure jump, h|grad rho|/rho and compression
   h max(0, -div v)/c above the thresholds of THRESHOLDS (per case, why there),
   the solid and 2 level-0 cells around it, the aerofoil and 1 level-0 cell around it; all
   grown by 1 level-0 cell (the regrid's dilation). The flagged cells go to the finest level;
   every coarser level holds its finer level's parents and one block around them (2:1 balance
   follows and is checked). L = 2, 3, 4 levels; blocks of B^d cells at their level. The 3-D
   sphere of issue 52 is a geometric estimate (partition_maps.sphere_scene), 3 levels.
3. Weights: particles + r * nodes, r the main job's cost of a node-step over that of a
   particle-step from its own timers.csv (grid phase per node-step over the particle phases
   p2g, g2p, stress, check, boundary, migrate and post_step per particle-step), or --node-cost.
4. Partitions (bench/partition_methods.py): sfc (weighted Morton curve over all blocks: what
   p4est_partition does), box (today's Cartesian level 0, finer blocks to the owner beneath),
   wbox (the same with its planes moved to balance the weight), hybrid (box's level 0, the
   finer blocks on the weighted curve filling each rank to the mean); quality per P and method.
   --p4est cross-checks the 2-D maps with libp4est (bench/p4est_check.c, built with mpicc).

Writes the table page (--md, default bench/results/partition_quality.md) and the raw rows as
JSON and CSV (--out, default out/partition_quality/).
  /usr/bin/python3 bench/bench_partition.py [--binary build/app/mpmfsi] [--bar-run DIR]
      [--rae-run DIR] [--ranks 64,256,1024] [--levels 2,3,4] [--blocks 8,16] [--reduced]
"""
import argparse
import csv
import datetime
import glob
import json
import os
import subprocess
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchrun  # noqa: E402
import partition_maps as pm  # noqa: E402
import partition_methods as pq  # noqa: E402

GHOST = 3  # mpm_shape_ghost_width(quadratic): ghost layers of a box, and of a block
# Flag thresholds per case (a case file would name its own): on the main job's field at 3 ms they
# take the bow shock and its wall reflection, the wake's edge and the bar's foot, not the free
# stream; RAE 2822's transonic shock is smeared over about 6 cells at 25 cells per chord, where
# h|grad rho|/rho and the compression reach only 0.05-0.10 (free stream: 90 % of cells under
# 0.012 and 0.002), so its thresholds are lower (they also take the wake's slip line and a few
# noise patches near the tunnel's top wall).
THRESHOLDS = {"supersonic_bar": {"pressure_jump": 0.1, "density_gradient": 0.2,
                                 "compression": 0.1},
              "rae2822": {"pressure_jump": 0.1, "density_gradient": 0.04, "compression": 0.03}}
METHODS = ("sfc", "box", "wbox", "hybrid")
PARTICLE_PHASES = ("p2g", "g2p", "stress", "check", "boundary", "migrate", "post_step")


def parse():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=os.path.join(benchrun.ROOT, "build", "app", "mpmfsi"))
    ap.add_argument("--bar-run", help="finished output folder of cases/supersonic_bar.ini")
    ap.add_argument("--rae-run", help="finished output folder of cases/rae2822.ini")
    ap.add_argument("--skip-rae", action="store_true")
    ap.add_argument("--ranks", default="64,256,1024")
    ap.add_argument("--levels", default="2,3,4")
    ap.add_argument("--blocks", default="8,16")
    ap.add_argument("--sphere-n", type=int, default=40)
    ap.add_argument("--p4est", action="store_true",
                    help="cross-check the 2-D maps with libp4est (bench/p4est_check.c)")
    ap.add_argument("--node-cost", type=float, help="node-step cost in particle-steps")
    ap.add_argument("--reduced", action="store_true",
                    help="the test's size: the main job at 6 mm to 0.5 ms, no RAE 2822, "
                         "a 16^3 sphere, 16 and 64 ranks, 2 and 3 levels, blocks of 8")
    ap.add_argument("--out", default=os.path.join(benchrun.ROOT, "out", "partition_quality"))
    ap.add_argument("--md", default=os.path.join(benchrun.ROOT, "bench", "results",
                                                 "partition_quality.md"))
    a = ap.parse_args()
    if a.reduced:
        a.ranks, a.levels, a.blocks, a.sphere_n, a.skip_rae = "16,64", "2,3", "8", 16, True
    return a


def run_case(a, case, name, overrides):
    """Run a case on 2 ranks into out/<name>; returns the folder."""
    out = os.path.join(a.out, name)
    args = ["mpiexec", "-n", "2", a.binary, "run", os.path.join(benchrun.ROOT, "cases", case),
            f"output.dir={out}", "output.overwrite=true", "run.progress=false"] + overrides
    subprocess.run(args, check=True, env=benchrun.ENV, capture_output=True)
    return out


def last_snapshot(run):
    snaps = sorted(glob.glob(os.path.join(run, "snap_*.h5")))
    if not snaps:
        sys.exit(f"bench_partition: no snapshot in {run}; run the case there first")
    return snaps[-1]


def node_cost(run, N0):
    """Cost of a node-step over that of a particle-step, from a run's own timers (see the
    file comment); the box nodes counted with their pad layers."""
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(run, "timers.csv")) as f:
        t = {r["phase"]: float(r["mean_s"]) * s["ranks"] for r in csv.DictReader(f)}
    nodes = float(np.prod([n + 1 + 2 * GHOST for n in N0]))
    per_node = t["grid"] / (nodes * s["steps"])
    per_particle = sum(t[p] for p in PARTICLE_PHASES) / s["particle_steps"]
    return per_node / per_particle, {"grid_ns_per_node_step": per_node * 1e9,
                                     "ns_per_particle_step": per_particle * 1e9,
                                     "steps": s["steps"], "nodes": nodes,
                                     "particle_steps": s["particle_steps"]}


def field_scene(name, snap, obstacle_fn=None):
    with h5py.File(snap, "r") as h5:
        f = pm.cell_fields(h5)
        t = float(h5.attrs["time"])
    obstacle = obstacle_fn(f) if obstacle_fn else None
    flags, share = pm.flags_from_field(f, THRESHOLDS[name], solid_buffer=2, obstacle=obstacle)
    return {"name": name, "dim": f["dim"], "N0": f["N0"], "h0": f["h0"], "time": t,
            "snapshot": os.path.relpath(snap, benchrun.ROOT), "fine": flags,
            "n0": f["n_gas"] + f["n_solid"], "sensor_share": share,
            "flag_share": float(flags.mean())}


def rae_obstacle(f):
    return pm.aerofoil_mask(os.path.join(benchrun.ROOT, "cases", "rae2822_coordinates.csv"),
                            f["N0"], f["lo"], f["h0"], 1.0, (0.0, 0.0), 2.31, 1)


def evaluate(a, scene, L, B, ranks, r):
    need = scene["need"] if "need" in scene else {L - 1: scene["fine"]}
    H = pm.Hierarchy(scene["N0"], B, L, need, scene["n0"])
    w = pq.block_weights(H, r)
    w0 = pq.level0_cell_weights(H, r)
    summ = H.summary()
    rows = []
    chk = p4est_check(a, H, w, ranks) if a.p4est and H.dim == 2 else None
    for P in ranks:
        dims = pq.layout(H.N0, P, GHOST)
        parts = {"sfc": pq.part_sfc(H, w, P)}
        if dims is not None:
            parts["box"] = pq.part_box(H, pq.uniform_splits(H.N0, dims))
            W = pq.wbox_weights(H, w, r)
            parts["wbox"] = pq.part_box(H, pq.weighted_splits(W, dims, GHOST))
            parts["hybrid"] = pq.part_hybrid(H, w, w0, P, pq.uniform_splits(H.N0, dims))
        for m in METHODS:
            row = {"scene": scene["name"], "levels": L, "block": B, "ranks": P, "method": m,
                   "layout": "x".join(map(str, dims)) if dims else "none",
                   "blocks": sum(summ["blocks"]), "blocks_per_level": summ["blocks"],
                   "particles": sum(summ["particles"]), "nodes": sum(summ["nodes"]),
                   "max_leaf_jump": summ["max_leaf_jump"], "p4est": chk,
                   "block_w_max": float(max(x.max() for x in w))}
            if m in parts:
                row.update(pq.quality(H, parts[m], w, w0, P, GHOST))
            rows.append(row)
    return rows


def p4est_check(a, H, w, ranks):
    """bench/p4est_check.c on this 2-D map: leaves before and after p4est_balance (and how many
    of those it adds lie in the domain: the brick's whole trees reach past it), whether
    p4est's leaf order is the driver's Morton order, and the load imbalance of p4est's weighted
    cut over its leaves (an inner block's weight added to its first leaf, the leaves p4est adds
    to complete a family weighing nothing). None where p4est or mpicc is missing."""
    exe = os.path.join(a.out, "p4est_check")
    src = os.path.join(benchrun.ROOT, "bench", "p4est_check.c")
    if not os.path.exists(exe):
        try:
            subprocess.run(["mpicc", "-std=c11", "-O2", src, "-o", exe, "-lp4est", "-lsc"],
                           check=True, capture_output=True)
        except (OSError, subprocess.CalledProcessError):
            return None
    lines = [f"{H.nb[0][0]} {H.nb[0][1]} {H.L}"]
    for l in range(1, H.L):
        b = np.argwhere(H.present[l])
        lines += [str(len(b))] + [f"{i} {j}" for i, j in b]
    def leaves_of(args):
        r = subprocess.run([exe] + args, input="\n".join(lines) + "\n", capture_output=True,
                           text=True, env=benchrun.ENV, check=True)
        out = r.stdout.split("\n")
        return int(out[0].split()[1]), [ln for ln in out[1:] if ln.strip()]

    before, out = leaves_of([])
    _, unbalanced = leaves_of(["no-balance"])
    added = [tuple(int(v) for v in ln.split()) for ln in set(out) - set(unbalanced)]
    added_inside = sum(1 for l, i, j in added
                       if i * H.B < H.N0[0] * 2 ** l and j * H.B < H.N0[1] * 2 ** l)
    leaves = np.array([[int(v) for v in ln.split()] for ln in out])
    inner = [np.zeros(H.nb[l], bool) for l in range(H.L)]
    for l in range(1, H.L):
        b = np.argwhere(H.present[l])
        inner[l - 1][tuple((b // 2).T)] = True
    def inside(l, i, j):
        return i < H.nb[l][0] and j < H.nb[l][1]

    ours = [inside(l, i, j) and bool(H.present[l][i, j]) and not inner[l][i, j]
            for l, i, j in leaves]
    ours_order = [(l, i, j) for (l, i, j), o in zip(leaves.tolist(), ours) if o]
    mine = pq.curve(H)
    mine = [(l, i, j) for l, (i, j) in mine if not inner[l][i, j]]
    wt = np.array([w[l][i, j] if o else 0.0 for (l, i, j), o in zip(leaves, ours)])
    # Inner blocks: to the first leaf beneath them (their lower corner's finest leaf).
    first = {}
    for k, (l, i, j) in enumerate(leaves.tolist()):
        for up in range(1, l + 1):
            first.setdefault((l - up, i >> up, j >> up), k)
    for l in range(H.L - 1):
        for i, j in np.argwhere(inner[l] & H.present[l]):
            wt[first[(l, int(i), int(j))]] += w[l][i, j]
    pre = np.cumsum(wt) - wt
    res = {"leaves": before, "leaves_balanced": len(out), "added_in_domain": added_inside,
           "leaves_in_map": int(sum(ours)),
           "family_fill": int(len(leaves) - sum(ours)), "same_order": ours_order == mine}
    for P in ranks:
        own = np.minimum(P - 1, (pre * P / wt.sum()).astype(np.int64))
        load = np.bincount(own, wt, P)
        res[f"imbalance_{P}"] = float(load.max() / load.mean())
    return res


def fmt_rows(rows):
    out = ["| levels | B | ranks | method | blocks | max/mean load | empty ranks | ghost nodes "
           "max / mean | neighbours max / mean | restr./prol. crossing |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "imbalance" not in r:
            out.append(f"| {r['levels']} | {r['block']} | {r['ranks']} | {r['method']} | "
                       f"{r['blocks']} | no layout fits (level 0 < {GHOST} cells per rank) "
                       "| | | | |")
            continue
        out.append(f"| {r['levels']} | {r['block']} | {r['ranks']} | {r['method']} | "
                   f"{r['blocks']} | **{r['imbalance']:.2f}** | {r['empty_ranks']} | "
                   f"{r['ghost_max']:.0f} / {r['ghost_mean']:.0f} | "
                   f"{r['nbr_max']} / {r['nbr_mean']:.1f} | {100 * r['restrict_cross']:.1f} % |")
    return "\n".join(out)


def main():
    a = parse()
    os.makedirs(a.out, exist_ok=True)
    ranks = [int(v) for v in a.ranks.split(",")]
    levels = [int(v) for v in a.levels.split(",")]
    blocks = [int(v) for v in a.blocks.split(",")]
    bar_over = ["grid.dx=0.006", "time.t_end=0.0005"] if a.reduced else []
    bar = a.bar_run or run_case(a, "supersonic_bar.ini", "supersonic_bar", bar_over)
    scenes = [field_scene("supersonic_bar", last_snapshot(bar))]
    if not a.skip_rae:
        rae = a.rae_run or run_case(a, "rae2822.ini", "rae2822", [])
        scenes.append(field_scene("rae2822", last_snapshot(rae), rae_obstacle))
    sph = pm.sphere_scene(N=a.sphere_n)
    sph["name"] = "sphere_3d"
    scenes.append(sph)
    if a.node_cost is not None:
        r, cost = a.node_cost, {"given": a.node_cost}
    else:
        r, cost = node_cost(bar, scenes[0]["N0"])
    rows = []
    for s in scenes:
        for L in (levels if s["dim"] == 2 else [3]):
            for B in blocks:
                if B >= 2 ** (L - 1):
                    rows += evaluate(a, s, L, B, ranks, r)
    meta = {"commit": benchrun.git("rev-parse", "--short", "HEAD"),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "command": " ".join(["/usr/bin/python3", "bench/bench_partition.py"] + sys.argv[1:]),
            "node_cost": r, "node_cost_from": cost, "ghost": GHOST, "thresholds": THRESHOLDS,
            "scenes": [{k: v for k, v in s.items() if k in ("name", "N0", "h0", "time",
                        "snapshot", "sensor_share", "flag_share")} for s in scenes]}
    with open(os.path.join(a.out, "partition_quality.json"), "w") as f:
        json.dump({"meta": meta, "rows": rows}, f, indent=1, default=str)
    keys = sorted({k for r_ in rows for k in r_})
    with open(os.path.join(a.out, "partition_quality.csv"), "w", newline="") as f:
        wr = csv.DictWriter(f, keys)
        wr.writeheader()
        wr.writerows(rows)
    if not a.reduced:
        write_md(a.md, meta, scenes, rows)
    print(json.dumps(meta, default=str))
    for s in scenes:
        print(s["name"])
        print(fmt_rows([r_ for r_ in rows if r_["scene"] == s["name"]]))


def fmt_p4est(rows):
    """The p4est cross-check of a scene's maps (empty without --p4est)."""
    seen, out = {}, []
    for r in rows:
        if r.get("p4est") and (r["levels"], r["block"]) not in seen:
            seen[(r["levels"], r["block"])] = r["p4est"]
    if not seen:
        return []
    ranks = sorted({r["ranks"] for r in rows})
    sfc = {(r["levels"], r["block"], r["ranks"]): r.get("imbalance") for r in rows
           if r["method"] == "sfc"}
    out = ["p4est on the same maps (bench/p4est_check.c: brick of level-0 blocks, refined "
           "where the map has a finer block, p4est_balance over faces and corners; its leaves "
           "cut by the weighted rule, an inner block's weight on its first leaf):", "",
           "| levels | B | map's leaf blocks | leaves p4est adds to complete families | leaves "
           "p4est_balance adds (in the domain) | same order as sfc | leaf-cut max/mean (sfc's) "
           + " / ".join(f"P = {P}" for P in ranks) + " |", "|---|---|---|---|---|---|---|"]
    for (L, B), c in seen.items():
        cut = " / ".join(f"{c[f'imbalance_{P}']:.2f} ({sfc[(L, B, P)]:.2f})" for P in ranks)
        out.append(f"| {L} | {B} | {c['leaves_in_map']} | {c['family_fill']} | "
                   f"{c['leaves_balanced'] - c['leaves']} ({c['added_in_domain']}) | "
                   f"{'yes' if c['same_order'] else 'no'} | {cut} |")
    return out + [""]


def cost_text(meta):
    c = meta["node_cost_from"]
    if "given" in c:
        return "the node cost given on the command line"
    return (f"the main job's own timers: the grid phase {c['grid_ns_per_node_step']:.0f} ns per "
            f"node-step over the particle phases' {c['ns_per_particle_step']:.0f} ns per "
            f"particle-step ({c['steps']} steps, {c['nodes']:.0f} box nodes, "
            f"{c['particle_steps'] / 1e6:.0f} M particle-steps)")


def write_md(path, meta, scenes, rows):
    """The results page: the tables only; the reading and the recommendation are written by
    hand below the marker and kept on regeneration."""
    keep = ""
    if os.path.exists(path):
        text = open(path).read()
        if "<!-- analysis -->" in text:
            keep = text[text.index("<!-- analysis -->"):]
    lines = ["# Partition quality of the refinement on 64, 256 and 1024 ranks (issue 51)", "",
             f"Computed {meta['date']} on the build of {meta['commit']}: `{meta['command']}`. "
             "Block maps from real flow fields (the last snapshot of each run, on 2 ranks) and "
             "a geometric 3-D estimate; nothing runs on 64-1024 ranks. Method and choices: the "
             "driver's docstring and [below](#how-the-maps-are-made). Raw rows: "
             "`out/partition_quality/partition_quality.{json,csv}` (not tracked).", "",
             f"Weights: particles + {meta['node_cost']:.3f} x nodes, {cost_text(meta)}. "
             f"Ghost width {meta['ghost']} nodes at every level.", ""]
    for s in scenes:
        n0 = "x".join(map(str, s["N0"]))
        lines += [f"## {s['name']} (level 0: {n0} cells of {s['h0']:g}"
                  + (f", snapshot t = {s['time']:g}" if "time" in s else "") + ")", ""]
        if "flag_share" in s:
            lines += [f"Flagged for the finest level: {100 * s['flag_share']:.1f} % of the "
                      "level-0 cells (sensors alone: " + ", ".join(
                          f"{k} {100 * v:.1f} %" for k, v in s["sensor_share"].items()) + ").",
                      ""]
        sel = [r for r in rows if r["scene"] == s["name"]]
        seen = []
        for r in sel:
            key = (r["levels"], r["block"])
            if key not in seen:
                seen.append(key)
                lines.append(f"- {r['levels']} levels, B = {r['block']}: blocks per level "
                             f"{r['blocks_per_level']}, {r['particles'] / 1e6:.2f} M particles, "
                             f"{r['nodes'] / 1e6:.2f} M nodes, largest leaf-level jump "
                             f"{r['max_leaf_jump']}")
        lines += ["", fmt_rows(sel), ""] + fmt_p4est(sel)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n" + (keep or "<!-- analysis -->\n"))


if __name__ == "__main__":
    main()
