"""Three ways to distribute a refinement hierarchy (bench/partition_maps.py) over P ranks, and
the quality of each (bench/bench_partition.py reports them; issue 51, DESIGN.md section 9).

- `sfc`: every block of every level on one weighted Morton curve (blocks ordered by the Morton
  index of their lower corner, a coarse block before the finer ones that start at its corner:
  p4est's order on a brick of level-0 blocks), cut into P pieces of equal weight.
- `box`: level 0 split as today's Cartesian box partition (common/mpm_grid.c: the layout of
  P ranks with the smallest halo that leaves every rank `ghost` cells per split axis, the
  splits at ncells * k / nproc); every finer block goes to the owner of the level-0 cell under
  its centre ("owner of the coarse region beneath").
- `wbox`: the same layout with its split planes moved to balance the weight (each block's
  weight counted at the level-0 cell under its centre): per axis in turn, the planes that
  minimise the heaviest rank with the other axes' planes fixed (exact, by dynamic programming),
  every slab keeping at least `ghost` cells.
- `hybrid`: level 0 as `box`; the finer blocks on the weighted curve, each rank filled up to
  the mean load (see `part_hybrid`).

An owner map is one array per level over "tiles" (blocks, or level-0 cells for box/wbox's level
0) with -1 where a level has no block, and the tile size in cells of that level. Quality
(`quality`): load max/mean; ghost nodes per rank (nodes of other ranks within `ghost` nodes of
a rank's own, per level, a node per cell); neighbour ranks (same-level halo or inter-level
partners); the share of restriction/prolongation traffic that crosses ranks (each fine block's
footprint on the coarser level, its parent cells and one coarse node around them for the
quadratic two-scale mask, counted by node and owner).
"""
import itertools

import numpy as np
from scipy import ndimage


# ---- weights ---------------------------------------------------------------------------------

def block_weights(H, node_cost):
    """Per level, the weight of each level-l block: particles + node_cost * nodes (0 where no
    block), in particle-equivalents."""
    return [np.where(H.present[l], H.particles(l) + node_cost * H.cells_in_domain(l), 0.0)
            for l in range(H.L)]


def level0_cell_weights(H, node_cost):
    """Level 0's weight per level-0 cell (its node and, where level 0 is the leaf, its
    particles)."""
    return node_cost + np.where(H.leaf == 0, H.n0, 0.0)


# ---- the level-0 Cartesian layout (common/mpm_grid.c) ----------------------------------------

def layout(N0, P, ghost):
    """mpm_grid.c's choice: among the factorisations of P (earlier axes more ranks on ties)
    that leave every rank >= ghost cells per split axis, the smallest halo (cut faces in
    cells). None if no layout fits."""
    dim, best, best_cost = len(N0), None, float("inf")

    def search(d, size, dims):
        nonlocal best, best_cost
        if d == dim:
            if size != 1 or any(dims[e] > 1 and N0[e] // dims[e] < ghost for e in range(dim)):
                return
            cost = sum((dims[e] - 1) * np.prod([N0[k] for k in range(dim) if k != e])
                       for e in range(dim))
            if cost < best_cost:
                best, best_cost = list(dims), cost
            return
        for n in range(size, 0, -1):
            if size % n == 0:
                search(d + 1, size // n, dims + [n])

    search(0, P, [])
    return best


def uniform_splits(N0, dims):
    return [np.array([n * k // p for k in range(p + 1)]) for n, p in zip(N0, dims)]


def box_owner_cells(N0, splits):
    """Owner of every level-0 cell for splits per axis (ranks numbered x fastest)."""
    coord = [np.searchsorted(s, np.arange(n), side="right") - 1 for n, s in zip(N0, splits)]
    grids = np.meshgrid(*coord, indexing="ij")
    rank, stride = np.zeros(N0, np.int64), 1
    for d, s in enumerate(splits):
        rank += grids[d] * stride
        stride *= len(s) - 1
    return rank


def _bottleneck_splits(M, p, ghost):
    """Splits of the rows of M (n x J, non-negative) into p slabs of >= ghost rows minimising
    max over slabs and columns of the slab's column sum: exact, by dynamic programming over
    (slab, end row). (A greedy sweep under a bisected cap is not: with a minimum width,
    stretching a slab can push the next one's minimum width into heavy rows.)"""
    n = M.shape[0]
    if p == 1:
        return np.array([0, n])
    C = np.vstack([np.zeros(M.shape[1]), np.cumsum(M, axis=0)])
    cost = (C[None, :, :] - C[:, None, :]).max(axis=2)  # cost[s, e] of rows [s, e)
    s_idx, e_idx = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    cost[e_idx - s_idx < ghost] = np.inf
    dp = cost[0].copy()  # best bottleneck of one slab [0, e)
    back = []
    for _ in range(1, p):
        cand = np.maximum(dp[:, None], cost)
        arg = cand.argmin(axis=0)
        back.append(arg)
        dp = cand[arg, np.arange(n + 1)]
    cuts, e = [n], n
    for arg in reversed(back):
        e = int(arg[e])
        cuts.append(e)
    return np.array([0] + cuts[::-1])


def weighted_splits(W, dims, ghost, rounds=4):
    """Rectilinear splits of the level-0 weight W over dims ranks per axis (see `wbox`)."""
    splits = uniform_splits(W.shape, dims)
    dim = W.ndim
    for _ in range(rounds):
        for d in range(dim):
            # Collapse the other axes onto their current parts: M[x, j].
            A = W
            for e in range(dim):
                if e == d:
                    continue
                A = np.add.reduceat(A, splits[e][:-1], axis=e)
            A = np.moveaxis(A, d, 0).reshape(W.shape[d], -1)
            splits[d] = _bottleneck_splits(A, dims[d], ghost)
    return splits


# ---- the three partitions --------------------------------------------------------------------

def morton(coords, bits=16):
    """Morton (Z-order) keys of integer coordinates (n x d), x the lowest bit."""
    key = np.zeros(coords.shape[0], np.int64)
    d = coords.shape[1]
    for b in range(bits):
        for a in range(d):
            key |= ((coords[:, a] >> b) & 1).astype(np.int64) << (b * d + a)
    return key


def _curve_order(H):
    """Every block of every level, its level, index and position on the Morton curve."""
    keys, lev, idx = [], [], []
    for l in range(H.L):
        b = np.argwhere(H.present[l])
        keys.append(morton(b << (H.L - 1 - l)))
        lev.append(np.full(len(b), l))
        idx.append(b)
    keys, lev = np.concatenate(keys), np.concatenate(lev)
    return lev, idx, np.lexsort((lev, keys))


def curve(H):
    """The blocks in curve order, as (level, index tuple)."""
    lev, idx, order = _curve_order(H)
    flat = np.concatenate(idx)
    return [(int(lev[k]), tuple(int(v) for v in flat[k])) for k in order]


def part_sfc(H, w, P):
    """(a) the weighted Morton curve over all blocks of all levels, cut at equal weight (a
    block goes to the rank whose share holds its weight's midpoint)."""
    lev, idx, order = _curve_order(H)
    wt = np.concatenate([w[l][tuple(idx[l].T)] for l in range(H.L)])
    cum = np.cumsum(wt[order]) - wt[order] / 2
    rank = np.empty(len(order), np.int64)
    rank[order] = np.minimum(P - 1, (cum * P / cum[-1] if cum[-1] > 0 else cum).astype(np.int64))
    owners, k = [], 0
    for l in range(H.L):
        o = np.full(H.nb[l], -1, np.int64)
        o[tuple(idx[l].T)] = rank[k:k + len(idx[l])]
        k += len(idx[l])
        owners.append((o, H.B))
    return owners


def part_hybrid(H, w, w0cell, P, splits):
    """(d) level 0 as today's boxes; the finer blocks on the weighted Morton curve, cut so that
    each rank is filled up to the mean load (its level-0 load counted), the ranks taken in the
    Morton order of their boxes' centres so that a rank's piece of the curve lies near its box
    where the loads allow."""
    own0 = box_owner_cells(H.N0, splits)
    load0 = np.bincount(own0.ravel(), w0cell.ravel(), P)
    lev, idx, order = _curve_order(H)
    wt = np.concatenate([w[l][tuple(idx[l].T)] for l in range(H.L)])
    fine = order[lev[order] > 0]
    total = load0.sum() + wt[fine].sum()
    cap = np.maximum(0.0, total / P - load0)
    cap *= wt[fine].sum() / cap.sum() if cap.sum() > 0 else 0
    coords = np.array(list(itertools.product(*[range(len(sp) - 1) for sp in splits])))
    centre = np.array([[(sp[c] + sp[c + 1]) // 2 for sp, c in zip(splits, co)] for co in coords])
    # box_owner_cells numbers the ranks x fastest
    rank_of = np.ravel_multi_index(tuple(coords.T), [len(sp) - 1 for sp in splits], order="F")
    ranks = rank_of[np.argsort(morton(centre), kind="stable")]
    bound = np.cumsum(cap[ranks])
    mid = np.cumsum(wt[fine]) - wt[fine] / 2
    pos = np.minimum(P - 1, np.searchsorted(bound, mid, side="right"))
    rank = np.full(len(lev), -1, np.int64)
    rank[fine] = ranks[pos]
    owners, k = [(own0, 1)], len(idx[0])
    for l in range(1, H.L):
        o = np.full(H.nb[l], -1, np.int64)
        o[tuple(idx[l].T)] = rank[k:k + len(idx[l])]
        k += len(idx[l])
        owners.append((o, H.B))
    return owners


def _beneath(H, own0, l):
    """Owner of the level-0 cell under each level-l block's centre (-1 where no block)."""
    centre = [np.minimum(n - 1, (np.arange(nb) * H.s[l] + H.s[l] // 2))
              for n, nb in zip(H.N0, H.nb[l])]
    o = own0[np.ix_(*centre)]
    return np.where(H.present[l], o, -1)


def part_box(H, splits):
    """(b)/(c): level 0 as boxes with the given splits; finer blocks to the owner beneath."""
    own0 = box_owner_cells(H.N0, splits)
    return [(own0, 1)] + [(_beneath(H, own0, l), H.B) for l in range(1, H.L)]


def wbox_weights(H, w, node_cost):
    """The weight per level-0 cell that `wbox` balances: level 0's own, plus every finer
    block's at the cell under its centre."""
    W = level0_cell_weights(H, node_cost).astype(float)
    for l in range(1, H.L):
        b = np.argwhere(H.present[l])
        c = np.minimum(np.array(H.N0) - 1, b * H.s[l] + H.s[l] // 2)
        np.add.at(W, tuple(c.T), w[l][tuple(b.T)])
    return W


# ---- quality ---------------------------------------------------------------------------------

def cell_owner(H, owners, l):
    """Owner of every level-l cell (-1 where level l has no block)."""
    o, t = owners[l]
    a = o
    for d in range(H.dim):
        a = np.repeat(a, t, axis=d)
    n = [N * 2 ** l for N in H.N0]
    return a[tuple(slice(0, k) for k in n)]


def loads(H, owners, w, w0cell, P):
    load = np.zeros(P)
    o0, t0 = owners[0]
    np.add.at(load, o0.ravel(), (w0cell if t0 == 1 else w[0]).ravel())
    for l in range(1, H.L):
        o = owners[l][0]
        m = o >= 0
        np.add.at(load, o[m], w[l][m])
    return load


def halo_pairs(A, ghost):
    """Unique (ghost cell, rank needing it) pairs of one level's cell-owner array A: cells of
    other ranks within `ghost` cells (Chebyshev) of a rank's own."""
    big = np.iinfo(np.int64).max
    hi = ndimage.maximum_filter(A, size=2 * ghost + 1, mode="constant", cval=-1)
    lo = ndimage.minimum_filter(np.where(A < 0, big, A), size=2 * ghost + 1, mode="constant",
                                cval=big)
    cand = np.nonzero((A >= 0) & ((hi != A) | (lo != A)))
    if not len(cand[0]):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    cand = np.array(cand)
    shape = np.array(A.shape)[:, None]
    pairs = []
    for off in itertools.product(range(-ghost, ghost + 1), repeat=A.ndim):
        if not any(off):
            continue
        nb = cand + np.array(off)[:, None]
        ok = np.all((nb >= 0) & (nb < shape), axis=0)
        r = np.full(cand.shape[1], -1, np.int64)
        r[ok] = A[tuple(nb[:, ok])]
        own = A[tuple(cand)]
        m = (r >= 0) & (r != own)
        flat = np.ravel_multi_index(tuple(cand[:, m]), A.shape)
        pairs.append(flat * (1 << 20) + r[m])
    u = np.unique(np.concatenate(pairs))
    return u >> 20, u & ((1 << 20) - 1)


def quality(H, owners, w, w0cell, P, ghost):
    """Load imbalance, ghost nodes per rank, neighbour ranks and the crossing share of the
    restriction/prolongation traffic of one partition."""
    load = loads(H, owners, w, w0cell, P)
    ghosts = np.zeros(P)
    edges = set()
    cells = [cell_owner(H, owners, l) for l in range(H.L)]
    for l, A in enumerate(cells):
        cell, need = halo_pairs(A, ghost)
        np.add.at(ghosts, need, 1)
        pair = np.unique(need * (1 << 20) + A.ravel()[cell])
        edges |= set(zip((pair >> 20).tolist(), (pair & ((1 << 20) - 1)).tolist()))
    cross = total = 0
    for l in range(1, H.L):
        C = cells[l - 1]
        o = owners[l][0]
        half = H.B // 2
        for j in np.argwhere(o >= 0):
            sl = tuple(slice(max(0, k * half - 1), min(n, (k + 1) * half + 1))
                       for k, n in zip(j, C.shape))
            c = C[sl]
            c = c[c >= 0]
            me = o[tuple(j)]
            other = c[c != me]
            cross += len(other)
            total += len(c)
            edges |= {(me, int(r)) for r in np.unique(other)}
    nbr = np.zeros(P)
    und = {(min(a, b), max(a, b)) for a, b in edges if a != b}
    for a, b in und:
        nbr[a] += 1
        nbr[b] += 1
    return {"imbalance": float(load.max() / load.mean()), "load_max": float(load.max()),
            "load_mean": float(load.mean()), "empty_ranks": int(np.sum(load == 0)),
            "ghost_max": float(ghosts.max()), "ghost_mean": float(ghosts.mean()),
            "nbr_max": int(nbr.max()), "nbr_mean": float(nbr.mean()),
            "restrict_cross": float(cross / total) if total else 0.0}
