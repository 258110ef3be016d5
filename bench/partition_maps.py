"""Block maps of a refinement hierarchy, built from a real flow field or a geometric estimate,
with per-block weights (bench/bench_partition.py uses them; issue 51, DESIGN.md section 9).

The hierarchy follows the design: level 0 is today's grid (N0 cells per axis, spacing h0);
level l (1 <= l < L) is a set of fixed-size blocks of B^d cells of spacing h0 / 2^l, aligned
to the origin, so a level-l block j has the parent block j // 2 on level l - 1 (a quadtree /
octree over level-0 blocks of B^d cells: p4est's forest on a brick of level-0 blocks).

Invariants of a `Hierarchy` (checked by `check_balance`):
- B >= 2^(L-1): every block covers whole level-0 cells (s_l = B / 2^l of them per axis), so the
  leaf level can be held per level-0 cell (`leaf`).
- Nesting with a buffer: the level-l blocks contain every level-(l+1) block's parent and its
  3^d - 1 neighbours (one block of buffer), hence 2:1 balance over faces, edges and corners
  (adjacent level-0 cells' leaf levels differ by at most 1).
- Particles live on their leaf: a level-0 cell of leaf level l holds n0 * 2^(d l) particles
  (each level splits a gas particle into 2^d children; the solid is seeded at the same ppc per
  cell of its level), all in the level-l block above it. Every present block holds nodes
  (one per cell, ghosts not counted), also where a finer level covers it (restriction target).
"""
import configparser
import math

import numpy as np
from scipy import ndimage


# ---- the flow field on level-0 cells ---------------------------------------------------------

def read_config(h5):
    """The resolved case stored in a snapshot's `config` attribute, as a ConfigParser."""
    text = h5.attrs["config"]
    if isinstance(text, bytes):
        text = text.decode()
    cp = configparser.ConfigParser(inline_comment_prefixes=("#",), strict=False)
    cp.read_string(text)
    return cp


def _cells(x, lo, h, n):
    idx = np.floor((x - lo) / h).astype(np.int64)
    return np.clip(idx, 0, np.array(n) - 1)


def cell_fields(h5):
    """Mass-weighted cell means of a snapshot's gas (rho, p, v, c) on the level-0 grid, the gas
    and solid particle counts per cell, and the grid (lo, h0, N0, dim)."""
    cfg = read_config(h5)
    dim = int(cfg["domain"]["dim"])
    lo = np.array([float(v) for v in cfg["domain"]["lo"].split()])
    hi = np.array([float(v) for v in cfg["domain"]["hi"].split()])
    h = float(cfg["grid"]["dx"])
    gamma = float(cfg["fluid"].get("gamma", "1.4")) if cfg.has_section("fluid") else 1.4
    n = tuple(int(round(v)) for v in (hi - lo) / h)
    out = {"dim": dim, "lo": lo, "hi": hi, "h0": h, "N0": n}
    g = h5["fluid"]
    x, m = g["x"][...], g["m"][...][:, 0]
    flat = np.ravel_multi_index(tuple(_cells(x, lo, h, n).T), n)
    size = int(np.prod(n))
    msum = np.bincount(flat, m, size)
    with np.errstate(invalid="ignore", divide="ignore"):
        def mean(q):
            return (np.bincount(flat, m * q, size) / msum).reshape(n)
        out["rho"] = mean(g["rho"][...][:, 0])
        out["p"] = mean(g["p"][...][:, 0])
        out["v"] = [mean(g["v"][...][:, d]) for d in range(dim)]
        out["c"] = np.sqrt(gamma * out["p"] / out["rho"])
    out["n_gas"] = np.bincount(flat, None, size).reshape(n).astype(float)
    out["n_solid"] = np.zeros(n)
    if "solid" in h5 and h5["solid"]["x"].shape[0]:
        xs = h5["solid"]["x"][...]
        fs = np.ravel_multi_index(tuple(_cells(xs, lo, h, n).T), n)
        out["n_solid"] = np.bincount(fs, None, size).reshape(n).astype(float)
    return out


def _second_diff_ratio(p, d):
    """|p+ - 2p + p-| / (p+ + 2p + p-) along axis d, 0 where a neighbour is missing."""
    pp, pm = np.roll(p, -1, d), np.roll(p, 1, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.abs(pp - 2 * p + pm) / (pp + 2 * p + pm)
    edge = [slice(None)] * p.ndim
    for i in (0, -1):
        edge[d] = i
        s[tuple(edge)] = 0
    return np.nan_to_num(s)


def _central(q, d):
    r = (np.roll(q, -1, d) - np.roll(q, 1, d)) / 2
    edge = [slice(None)] * q.ndim
    for i in (0, -1):
        edge[d] = i
        r[tuple(edge)] = 0
    return np.nan_to_num(r)


def sensors(f):
    """The design's three flow sensors on level-0 cells (dimensionless, 0 where undefined):
    pressure jump max_d |p+ - 2p + p-|/(p+ + 2p + p-), density gradient h|grad rho|/rho and
    compression h max(0, -div v)/c (the differences are over one cell, so h cancels)."""
    dim = f["dim"]
    pj = np.max([_second_diff_ratio(f["p"], d) for d in range(dim)], axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        grad = np.sqrt(sum(_central(f["rho"], d) ** 2 for d in range(dim)))
        dg = np.nan_to_num(grad / f["rho"])
        div = sum(_central(f["v"][d], d) for d in range(dim))
        cs = np.nan_to_num(np.maximum(0, -div) / f["c"])
    return {"pressure_jump": pj, "density_gradient": dg, "compression": cs}


def dilate(mask, cells):
    """mask grown by `cells` cells in every direction (Chebyshev)."""
    if cells <= 0:
        return mask.copy()
    return ndimage.maximum_filter(mask.astype(np.uint8), size=2 * cells + 1,
                                  mode="constant") > 0


# ---- the hierarchy ---------------------------------------------------------------------------

class Hierarchy:
    """Blocks of every level over a level-0 grid of N0 cells (see the file comment).
    present[l]: bool over the level-l block grid; leaf: leaf level per level-0 cell;
    n0: particles per leaf cell (per level-0 cell's footprint at its leaf level)."""

    def __init__(self, N0, B, L, need, n0):
        self.N0, self.B, self.L, self.dim = tuple(N0), B, L, len(N0)
        if B < 2 ** (L - 1):
            raise ValueError(f"blocks of {B} cells cannot hold {L} levels on whole level-0 cells")
        self.s = [B // 2 ** l for l in range(L)]  # level-0 cells per block side, per level
        self.nb = [tuple(-(-n // s) for n in N0) for s in self.s]
        self.present = [None] * L
        self.present[0] = np.ones(self.nb[0], bool)
        for l in range(L - 1, 0, -1):
            p = np.zeros(self.nb[l], bool)
            if need.get(l) is not None:
                p |= self._touching(need[l], l)
            if l + 1 < L:
                p |= self._buffered_parents(l)
            self.present[l] = p
        self.leaf = np.zeros(self.N0, np.int8)
        for l in range(1, L):
            self.leaf[self.up(self.present[l], l)] = l
        self.n0 = n0

    def _pad(self, a, s):
        """a (level-0 cells) padded with zeros to whole blocks of s cells."""
        return np.pad(a, [(0, (-n) % s) for n in a.shape])

    def block_sum(self, a, l):
        """Sum of a level-0 cell array over each level-l block."""
        s, a = self.s[l], self._pad(a, self.s[l])
        shape = []
        for n in a.shape:
            shape += [n // s, s]
        return a.reshape(shape).sum(axis=tuple(range(1, 2 * self.dim, 2)))

    def up(self, b, l):
        """A level-l block array expanded to level-0 cells (cropped to N0)."""
        a = b
        for d in range(self.dim):
            a = np.repeat(a, self.s[l], axis=d)
        return a[tuple(slice(0, n) for n in self.N0)]

    def _touching(self, mask, l):
        return self.block_sum(mask.astype(np.int64), l) > 0

    def _buffered_parents(self, l):
        """Level-l blocks holding a level-(l+1) block, and one block around them."""
        par = np.zeros(self.nb[l], bool)
        idx = np.nonzero(self.present[l + 1])
        par[tuple(i // 2 for i in idx)] = True
        return dilate(par, 1)

    def cells_in_domain(self, l):
        """Level-l cells of each level-l block that lie in the domain (its nodes)."""
        return self.block_sum(np.ones(self.N0, np.int64), l) * 2 ** (self.dim * l)

    def particles(self, l):
        """Particles of each level-l block: those of its leaf cells."""
        return self.block_sum(np.where(self.leaf == l, self.n0, 0.0), l) * 2 ** (self.dim * l)

    def check_balance(self):
        """Largest leaf-level jump between Chebyshev-adjacent level-0 cells (2:1 needs <= 1)."""
        hi = ndimage.maximum_filter(self.leaf, size=3, mode="nearest")
        lo = ndimage.minimum_filter(self.leaf, size=3, mode="nearest")
        return int(np.max(hi.astype(int) - lo))

    def summary(self):
        return {"blocks": [int(p.sum()) for p in self.present],
                "particles": [float(self.particles(l)[self.present[l]].sum())
                              for l in range(self.L)],
                "nodes": [float(self.cells_in_domain(l)[self.present[l]].sum())
                          for l in range(self.L)],
                "max_leaf_jump": self.check_balance()}


# ---- the three scenes ------------------------------------------------------------------------

def flags_from_field(f, thresholds, solid_buffer, obstacle=None, dilation=1):
    """Level-0 cells the finest level must cover: any flow sensor above its threshold, the
    solid's cells and `solid_buffer` cells around them, an obstacle mask (already buffered),
    all grown by `dilation` level-0 cells (the regrid's dilation)."""
    s = sensors(f)
    flow = np.zeros(f["N0"], bool)
    share = {}
    for k, t in thresholds.items():
        flow |= s[k] > t
        share[k] = float(np.mean(s[k] > t))
    solid = dilate(f["n_solid"] > 0, solid_buffer)
    m = flow | solid
    if obstacle is not None:
        m |= obstacle
    return dilate(m, dilation), share


def aerofoil_mask(csv_path, N0, lo, h, chord, le, alpha_deg, buffer_cells):
    """Level-0 cells within buffer_cells * h of an aerofoil outline (x/c, y/c rows) or inside
    it, turned nose up by alpha about the leading edge."""
    xy = _outline(csv_path) * chord
    a = -math.radians(alpha_deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    xy = xy @ rot.T + np.asarray(le)
    # Sample the outline densely and mark the cells it crosses, then grow and fill.
    seg = []
    for i in range(len(xy) - 1):
        k = max(2, int(np.hypot(*(xy[i + 1] - xy[i])) / (0.25 * h)) + 1)
        seg.append(np.linspace(xy[i], xy[i + 1], k))
    s = np.concatenate(seg)
    m = np.zeros(N0, bool)
    m[tuple(_cells(s, lo, h, N0).T)] = True
    m = ndimage.binary_fill_holes(m)
    return dilate(m, buffer_cells)


def _outline(path):
    """The (x/c, y/c) rows of an outline file: numeric first two columns, comments skipped."""
    rows = []
    with open(path) as fh:
        for line in fh:
            cols = line.split("#")[0].split(",")
            try:
                rows.append((float(cols[0]), float(cols[1])))
            except (ValueError, IndexError):
                continue
    return np.array(rows)


def sphere_scene(N=40, size=10.0, d=1.0, centre=(3.5, 5.0, 5.0), ppc=2, L=3):
    """Geometric estimate of issue 52's sphere scene (Mach 0.8, domain size^3, N^3 coarsest):
    need[L-1] = the sphere with a shell of d/4, the shoulder's shock (a ring from the equator
    to 0.5 d downstream, radius up to 1.0 d from the axis) and the near wake (radius 0.6 d to
    2 d behind the centre); need[1] = the far wake (radius 1.0 d to 6 d behind). Gas particles
    ppc^3 per cell outside the sphere (uniform density), none inside (a static obstacle)."""
    h = size / N
    sub = 4  # sub-samples per cell per axis for the sphere's volume fraction
    g = (np.arange(N * sub) + 0.5) * h / sub
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    dx, r = X - centre[0], np.hypot(Y - centre[1], Z - centre[2])
    dist = np.sqrt(dx ** 2 + r ** 2)

    def cellwise(mask, how):
        a = mask.reshape(N, sub, N, sub, N, sub)
        return a.mean(axis=(1, 3, 5)) if how == "mean" else a.any(axis=(1, 3, 5))

    inside = cellwise(dist < d / 2, "mean")
    fine = (dist < d / 2 + d / 4) | ((dx > 0) & (dx < d / 2) & (r < d)) | \
        ((dx > 0) & (dx < 2 * d) & (r < 0.6 * d))
    wake = (dx > 0) & (dx < 6 * d) & (r < d)
    need = {L - 1: cellwise(fine, "any")}
    if L > 2:
        need[1] = cellwise(wake, "any")
    n0 = ppc ** 3 * (1 - inside)
    return {"dim": 3, "N0": (N, N, N), "h0": h, "need": need, "n0": n0}
