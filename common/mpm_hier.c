/* The refinement hierarchy (mpm_hier.h): construction from boxes, the regions and masks of
 * every level, the level of a point, and the per-level phases and nodal solve.
 *
 * Invariants kept here:
 * - Level l >= 1 is built from level l - 1: its origin o_l = o_{l-1} - h_l / 2, its regions'
 *   boxes snapped outwards to whole level-(l-1) spans, its node box the smallest box holding,
 *   for every refined box with level-(l-1) spans [a, z] (i.e. level-l spans [2a, 2z + 1]), the
 *   nodes whose support meets those spans, [2a - 1, 2z + 2], plus one layer: [2a - 2, 2z + 3].
 * - Proper nesting (buffer >= 1 spans) puts the parents of every level-l box node, level-(l-1)
 *   nodes [a - 2, z + 2], inside level l - 1's box, so restriction and prolongation never
 *   leave a box (on level 0 the domain check and the grid's pad do the same).
 * - Masks outside a box: on level 0 every span is covered and none refined (the grid's own
 *   pad edges keep the plain rule); on finer levels nothing outside the box is covered.
 * - Walls (mpm_hier.h): every mask lookup (span_flag) first moves a span beyond a walled face
 *   onto its mirror, so the stored masks beyond a wall are never read and the regions are
 *   symmetric about it; a box touching a wall stores the nodes beyond it that its stencils
 *   reach (2a - 2 >= -2 on level 1, whose level-0 parents lie in the grid's pad of 3).
 * - Periodic axes (mpm_hier.h): masks are marked on every image of a span in the box, and
 *   looked up at the image in [0, period) along the axes where a level has a period, so the
 *   masks of images equal those of their nodes; a level's period is set when its box would
 *   reach a node outside [0, N_l) (then it stores the whole period), and a level without one
 *   along a periodic axis lies wholly inside [0, N_l), so it has no images there. */
#include "mpm_hier_impl.h"

#include "mpm_error.h"
#include "mpm_module.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char g_axis[MPM_MAX_DIM] = {'x', 'y', 'z'};

/* Level-(level-1) span index range [a[d], z[d]] of each box. */
typedef struct box_spans {
  int a[MPM_MAX_DIM], z[MPM_MAX_DIM];
} box_spans;

/* Refuse bad input: one sentence into why, nothing logged (the caller names the key). */
static int refuse(char *why, size_t why_len, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int refuse(char *why, size_t why_len, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (why && why_len) vsnprintf(why, why_len, fmt, ap);
  va_end(ap);
  return MPM_ERR_INPUT;
}

/* ---- input checks ----------------------------------------------------------------------- */

static int check_setup(const mpm_grid *grid, int nlevels, int buffer, char *why, size_t len) {
  if (nlevels < 1 || nlevels > MPM_HIER_MAX_LEVELS)
    return refuse(why, len, "%d levels: give 1 to %d (level 0 is the grid)", nlevels,
                  MPM_HIER_MAX_LEVELS);
  if (grid->shape != MPM_SHAPE_QUADRATIC)
    return refuse(why, len,
                  "refinement needs the quadratic B-spline shape (its nested levels use that "
                  "spline's two-scale relation), not %s: set the shape to quadratic",
                  mpm_shape_name(grid->shape));
  if (buffer < 1)
    return refuse(why, len,
                  "a buffer of %d spans between levels: give at least 1 (the restriction needs "
                  "one coarse span around every finer region)",
                  buffer);
  return 0;
}

/* One box alone: its level, extent and place in the domain. */
static int check_box(const mpm_grid *grid, int nlevels, const mpm_hier_box *b, int k, char *why,
                     size_t len) {
  if (b->level < 1 || b->level >= nlevels)
    return refuse(why, len, "box %d has level %d; with %d levels a box's level is 1 to %d", k,
                  b->level, nlevels, nlevels - 1);
  const double tol = 1e-9 * grid->dx;
  for (int d = 0; d < grid->dim; ++d) {
    if (!(b->hi[d] > b->lo[d]) || !isfinite(b->lo[d]) || !isfinite(b->hi[d]))
      return refuse(why, len, "box %d (level %d) is empty along %c ([%g, %g]): give lo < hi", k,
                    b->level, g_axis[d], b->lo[d], b->hi[d]);
    /* Along a periodic axis a box may cross the faces, by up to a period. */
    const double reach = grid->periodic[d] ? grid->hi[d] - grid->lo[d] : 0.0;
    if (b->lo[d] < grid->lo[d] - reach - tol || b->hi[d] > grid->hi[d] + reach + tol)
      return refuse(why, len,
                    "box %d (level %d) spans [%g, %g] along %c, %s the domain [%g, %g]: "
                    "move or shrink it into the domain",
                    k, b->level, b->lo[d], b->hi[d], g_axis[d],
                    reach > 0 ? "more than a period beyond the periodic faces of" : "outside",
                    grid->lo[d], grid->hi[d]);
  }
  return 0;
}

static int check_boxes(const mpm_grid *grid, int nlevels, const mpm_hier_box *box, int nbox,
                       char *why, size_t len) {
  int has[MPM_HIER_MAX_LEVELS] = {0};
  for (int k = 0; k < nbox; ++k) {
    const int rc = check_box(grid, nlevels, &box[k], k, why, len);
    if (rc) return rc;
    has[box[k].level] = 1;
  }
  for (int l = 1; l < nlevels; ++l)
    if (!has[l])
      return refuse(why, len, "level %d has no box: give every level 1 to %d at least one box", l,
                    nlevels - 1);
  return 0;
}

/* ---- regions ---------------------------------------------------------------------------- */

/* The spans of coarse lattice c that meet the open box (lo, hi), snapped outwards; a box face
 * within 1e-9 spans of a span face does not take in the next span. */
static box_spans snap_box(const mpm_grid *c, const mpm_hier_box *b) {
  const double eps = 1e-9;
  box_spans s = {{0, 0, 0}, {0, 0, 0}};
  for (int d = 0; d < c->dim; ++d) {
    s.a[d] = (int)floor(hier_xi(c, d, b->lo[d]) - 0.5 + eps) + 1;
    s.z[d] = (int)ceil(hier_xi(c, d, b->hi[d]) + 0.5 - eps) - 1;
  }
  return s;
}

/* Is index j in [a, z], taken modulo the period P (0: none)? */
static int in_range(int j, int a, int z, int P) {
  if (!P) return j >= a && j <= z;
  return z - a + 1 >= P || hier_mod(j - a, P) <= z - a;
}

/* Set mask to 1 on the box nodes of level lv with global indices in [a, z] (clipped to the
 * box), and on their images along the axes where the level has a period. Visits those nodes
 * only (the whole box along a periodic axis): a regrid builds a level from many small boxes. */
static void mark(const mpm_hier_level *lv, unsigned char *mask, const int *a, const int *z) {
  const mpm_grid *g = lv->grid;
  int lo[MPM_MAX_DIM] = {0, 0, 0}, hi[MPM_MAX_DIM] = {0, 0, 0}, gi[MPM_MAX_DIM];
  for (int d = 0; d < g->dim; ++d) {
    const int top = g->box_lo[d] + g->box_n[d] - 1;
    lo[d] = lv->period[d] ? g->box_lo[d] : MPM_MAX(a[d], g->box_lo[d]);
    hi[d] = lv->period[d] ? top : MPM_MIN(z[d], top);
    if (lo[d] > hi[d]) return;
  }
  for (gi[2] = lo[2]; gi[2] <= hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] <= hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] <= hi[0]; ++gi[0]) {
        int in = 1;
        for (int d = 0; d < g->dim; ++d) in &= in_range(gi[d], a[d], z[d], lv->period[d]);
        if (in) mask[mpm_grid_local_index(g, gi)] = 1;
      }
}

/* Mask value of span gi on level l, looked up at its mirror beyond a wall and at its image
 * along the level's periodic axes, with the rule outside the box of the file comment. Axis by
 * axis (each axis's mirror and image are its own), building the box index as
 * mpm_grid_local_index does: a hot path (mpm_hier_level_of). */
static inline int span_flag(const mpm_hier *h, int l, const unsigned char *mask, const int *gi,
                            int out) {
  const mpm_grid *g = h->level[l].grid;
  mpm_lidx k = 0;
  int d = h->dim - 1;
  for (; d >= 0; --d) {
    const int *plain = h->level[l].plain[d];
    const int c = gi[d] >= plain[0] && gi[d] <= plain[1]
                      ? gi[d]
                      : hier_canon_1d(&h->level[l], d, hier_mirror(h, l, d, gi[d]));
    if (c < g->box_lo[d] || c >= g->box_lo[d] + g->box_n[d]) break;
    k = k * g->box_n[d] + (c - g->box_lo[d]);
  }
  if (d < 0) return mask[k];
  /* A rank's part of level 0 may hold the span's image but not its image in [0, period). */
  int m[MPM_MAX_DIM] = {gi[0], gi[1], gi[2]};
  for (int e = 0; e < h->dim; ++e) m[e] = hier_mirror(h, l, e, m[e]);
  if (hier_in_box(g, m)) return mask[mpm_grid_local_index(g, m)];
  /* On more than one rank, level 0's refined spans beyond the rank's box: span i is refined
   * when level 1 covers its span 2 i (its level-1 spans are 2 i and 2 i + 1), so every rank
   * finds every point's level. */
  if (l == 0 && h->nranks > 1 && h->nlevels > 1 && mask == h->level[0].refined) {
    int f[MPM_MAX_DIM] = {0, 0, 0};
    for (int e = 0; e < h->dim; ++e) f[e] = 2 * gi[e];
    return span_flag(h, 1, h->level[1].covered, f, 0);
  }
  return out;
}

/* Is every span in [a, z] covered on level l (periodically)? */
static int all_covered(const mpm_hier *h, int l, const int *a, const int *z) {
  int lo[MPM_MAX_DIM] = {0, 0, 0}, hi[MPM_MAX_DIM] = {0, 0, 0}, gi[MPM_MAX_DIM];
  for (int d = 0; d < h->dim; ++d) lo[d] = a[d], hi[d] = z[d];
  if (l == 0) return 1;
  for (gi[2] = lo[2]; gi[2] <= hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] <= hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] <= hi[0]; ++gi[0])
        if (!span_flag(h, l, h->level[l].covered, gi, 0)) return 0;
  return 1;
}

/* Node gi of level l is active: spans gi - 1 .. gi + 1 all covered, not all refined. */
static int node_active(const mpm_hier *h, int l, const int *gi) {
  int s[MPM_MAX_DIM] = {0, 0, 0}, off[MPM_MAX_DIM] = {0, 0, 0}, refined = 1;
  const int n3 = h->dim == 2 ? 9 : 27;
  for (int q = 0; q < n3; ++q) {
    for (int d = 0, r = q; d < h->dim; ++d, r /= 3) off[d] = r % 3 - 1, s[d] = gi[d] + off[d];
    if (!span_flag(h, l, h->level[l].covered, s, l == 0)) return 0;
    refined &= span_flag(h, l, h->level[l].refined, s, 0);
  }
  return !refined;
}

/* node_active where spans gi - 1 .. gi + 1 all lie in the plain range (mpm_hier_level.plain):
 * the masks read in place around box index n. */
static int node_active_plain(const mpm_hier_level *lv, int dim, mpm_lidx n) {
  const mpm_grid *g = lv->grid;
  const mpm_lidx sy = g->box_n[0], sz = dim == 3 ? sy * g->box_n[1] : 0;
  int refined = 1;
  for (int c = dim == 3 ? -1 : 0; c <= (dim == 3 ? 1 : 0); ++c)
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a) {
        const mpm_lidx k = n + a + b * sy + c * sz;
        if (!lv->covered[k]) return 0;
        refined &= lv->refined[k];
      }
  return !refined;
}

static void set_active(mpm_hier *h, int l) {
  const mpm_hier_level *lv = &h->level[l];
  const mpm_grid *g = lv->grid;
  int gi[MPM_MAX_DIM];
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    hier_node_of(g, n, gi);
    int plain = 1;
    for (int d = 0; d < h->dim; ++d)
      plain &= gi[d] - 1 >= lv->plain[d][0] && gi[d] + 1 <= lv->plain[d][1];
    h->level[l].active[n] =
        (unsigned char)(plain ? node_active_plain(lv, h->dim, n) : node_active(h, l, gi));
  }
}

static int alloc_masks(mpm_hier_level *lv) {
  const mpm_lidx n = lv->grid->nnodes;
  MPM_ALLOC(lv->covered, n);
  MPM_ALLOC(lv->refined, n);
  MPM_ALLOC(lv->active, n);
  return 0;
}

/* The images of level l >= 1 (its nodes outside [0, period) along an axis with a period). */
static int find_images(mpm_hier_level *lv, int dim) {
  const mpm_grid *g = lv->grid;
  int any = 0, gi[MPM_MAX_DIM], c[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) any |= lv->period[d] != 0;
  if (!any) return 0;
  MPM_ALLOC(lv->is_image, g->nnodes);
  for (int pass = 0; pass < 2; ++pass) {
    lv->nimage = 0;
    for (mpm_lidx n = 0; n < g->nnodes; ++n) {
      hier_node_of(g, n, gi);
      memcpy(c, gi, sizeof c);
      hier_canon(lv, dim, c);
      if (!memcmp(c, gi, sizeof c)) continue;
      if (pass) lv->image[lv->nimage] = n, lv->canon[lv->nimage] = mpm_grid_local_index(g, c);
      lv->is_image[n] = 1, lv->nimage++;
    }
    if (!pass) MPM_ALLOC(lv->image, lv->nimage > 0 ? lv->nimage : 1);
    if (!pass) MPM_ALLOC(lv->canon, lv->nimage > 0 ? lv->nimage : 1);
  }
  return 0;
}

/* Along the periodic axes, level l stores the whole period when its region crosses a periodic
 * face, or its box [lo, hi] would reach a node outside [0, N_l): then
 * [-1, N_l + 2^(l-1) + 2], which holds the stencil of every point of the domain (at
 * 2^(l-1) - 1 + [0, N_l + 2] on level l's lattice) with a node to spare. The domain's low face
 * is at node 2^(l-1) - 1/2 of level l: the region (its box less two nodes) crosses it when
 * lo < 2^(l-1) - 2, which for l >= 3 is more than lo < 0 (a level-3 region from level-2 span 1,
 * wholly below the face, has lo = 0 and once wrote outside its box). */
static void wrap_level(const mpm_grid *g0, int l, int *lo, int *hi, int *period) {
  const int lo_min = MPM_MAX(0, (1 << (l - 1)) - 2);
  for (int d = 0; d < g0->dim; ++d) {
    const int N = g0->ncells[d] << l;
    if (!g0->periodic[d] || (lo[d] >= lo_min && hi[d] <= N - 1)) continue;
    lo[d] = -1, hi[d] = N + (1 << (l - 1)) + 2, period[d] = N;
  }
}

/* ---- levels ----------------------------------------------------------------------------- */

/* The box grid of level l (>= 1) holding the boxes of that level, its covered mask, and the
 * refined mask of level l - 1 from the same boxes. */
static int make_level(mpm_hier *h, int l, const mpm_hier_box *box, const box_spans *sp, int nbox) {
  const mpm_grid *c = h->level[l - 1].grid;
  int lo[MPM_MAX_DIM] = {0, 0, 0}, hi[MPM_MAX_DIM] = {0, 0, 0}, n[MPM_MAX_DIM] = {1, 1, 1},
      first = 1;
  double origin[MPM_MAX_DIM] = {0, 0, 0};
  for (int k = 0; k < nbox; ++k) {
    if (box[k].level != l) continue;
    for (int d = 0; d < h->dim; ++d) {
      lo[d] = first ? 2 * sp[k].a[d] - 2 : MPM_MIN(lo[d], 2 * sp[k].a[d] - 2);
      hi[d] = first ? 2 * sp[k].z[d] + 3 : MPM_MAX(hi[d], 2 * sp[k].z[d] + 3);
    }
    first = 0;
  }
  const double hf = 0.5 * c->dx;
  mpm_hier_level *lv = &h->level[l];
  wrap_level(h->level[0].grid, l, lo, hi, lv->period);
  for (int d = 0; d < h->dim; ++d) h->wraps |= lv->period[d] != 0;
  for (int d = 0; d < h->dim; ++d) origin[d] = c->lo[d] - 0.5 * hf, n[d] = hi[d] - lo[d] + 1;
  MPM_CALL(mpm_grid_box_new(&lv->grid, h->dim, origin, hf, c->shape, lo, n));
  MPM_CALL(alloc_masks(lv));
  MPM_CALL(find_images(lv, h->dim));
  for (int k = 0; k < nbox; ++k) {
    if (box[k].level != l) continue;
    int fa[MPM_MAX_DIM] = {0, 0, 0}, fz[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < h->dim; ++d) fa[d] = 2 * sp[k].a[d], fz[d] = 2 * sp[k].z[d] + 1;
    mark(lv, lv->covered, fa, fz);
    mark(&h->level[l - 1], h->level[l - 1].refined, sp[k].a, sp[k].z);
  }
  return 0;
}

/* Every box of level l lies in Omega_{l-1} with `buffer` level-(l-1) spans to spare. */
static int check_nesting(const mpm_hier *h, int l, const box_spans *sp, const mpm_hier_box *box,
                         int nbox, char *why, size_t len) {
  for (int k = 0; k < nbox; ++k) {
    if (box[k].level != l) continue;
    int a[MPM_MAX_DIM] = {0, 0, 0}, z[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < h->dim; ++d) a[d] = sp[k].a[d] - h->buffer, z[d] = sp[k].z[d] + h->buffer;
    if (!all_covered(h, l - 1, a, z))
      return refuse(why, len,
                    "box %d (level %d) is not inside the region of level %d with a margin of %d "
                    "level-%d spans (%g long each): enlarge the level-%d boxes around it, or "
                    "shrink or move it",
                    k, l, l - 1, h->buffer, l - 1, h->level[l - 1].grid->dx, l - 1);
  }
  return 0;
}

/* On more than one rank: the box of level 0's nodes that are parents of level 1's box nodes,
 * [floor(lo / 2) - 1, floor(hi / 2) + 1] per axis (mpm_hier_impl.h, hier_parents_1d), and for
 * each the level-0 box index of the node this rank owns there (its image in [0, ncells) along
 * a periodic axis), or -1. */
static int make_parents_box(mpm_hier *h) {
  const mpm_grid *g0 = h->level[0].grid, *g1 = h->level[1].grid;
  int lo[MPM_MAX_DIM] = {0, 0, 0}, n[MPM_MAX_DIM] = {1, 1, 1}, gi[MPM_MAX_DIM];
  for (int d = 0; d < h->dim; ++d) {
    lo[d] = hier_half(g1->box_lo[d]) - 1;
    n[d] = hier_half(g1->box_lo[d] + g1->box_n[d] - 1) + 1 - lo[d] + 1;
  }
  mpm_hier_parents_box *pb = &h->pbox;
  MPM_CALL(mpm_grid_box_new(&pb->grid, h->dim, g0->lo, g0->dx, g0->shape, lo, n));
  MPM_ALLOC(pb->owned, pb->grid->nnodes);
  MPM_ALLOC(pb->buf, (size_t)pb->grid->nnodes * (1 + 3 * MPM_MAX_DIM));
  for (mpm_lidx k = 0; k < pb->grid->nnodes; ++k) {
    hier_node_of(pb->grid, k, gi);
    int own = 1;
    for (int d = 0; d < h->dim; ++d) {
      if (g0->periodic[d]) gi[d] = hier_mod(gi[d], g0->ncells[d]);
      own &= gi[d] >= g0->own_lo[d] && gi[d] < g0->own_hi[d];
    }
    pb->owned[k] = own ? mpm_grid_local_index(g0, gi) : -1;
  }
  return 0;
}

static int make_leaf(mpm_hier *h);

/* Does node gi of lattice g lie within three level-0 cells of a walled face? (The spans there
 * are left to the walk, and every node there may take a deposit: level_walk.) */
static int beside_wall(const mpm_hier *h, const mpm_grid *g, const int *gi) {
  const mpm_grid *g0 = h->level[0].grid;
  int near = 0;
  for (int d = 0; d < h->dim; ++d) {
    const double x = g->lo[d] + gi[d] * g->dx, reach = 3.0 * g0->dx;
    near |= (h->wall[d][0] && x < g0->lo[d] + reach) || (h->wall[d][1] && x > g0->hi[d] - reach);
  }
  return near;
}

/* near[n] = 1 for the nodes of level l's box within one node (per axis) of a span of level l's
 * own points (in Omega_l, not refined: where its particles deposit; a point's stencil spans its
 * span's node and the two beside it) or within three level-0 cells of a walled face (a point
 * beyond a wall may stay on a coarser level than its span's, level_walk), mirrors and images
 * looked up as span_flag does: those spans' flags, dilated by one along each axis in turn. (The
 * box holds every span of Omega_l within reach of its nodes.) */
static void near_mask(const mpm_hier *h, int l, unsigned char *near, unsigned char *tmp) {
  const mpm_hier_level *lv = &h->level[l];
  const mpm_grid *g = lv->grid;
  int gi[MPM_MAX_DIM];
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    hier_node_of(g, n, gi);
    near[n] = (unsigned char)(span_flag(h, l, lv->covered, gi, 0) &&
                              (beside_wall(h, g, gi) || !span_flag(h, l, lv->refined, gi, 0)));
  }
  mpm_lidx stride = 1;
  for (int d = 0; d < h->dim; stride *= g->box_n[d], ++d) {
    const int len = g->box_n[d];
    for (mpm_lidx n = 0; n < g->nnodes; ++n) {
      const int i = (int)((n / stride) % len);
      unsigned char v = 0;
      for (int o = -1; o <= 1 && !v; ++o)
        if (i + o >= 0 && i + o < len) v = near[n + o * stride];
      tmp[n] = v;
    }
    memcpy(near, tmp, (size_t)g->nnodes);
  }
}

/* Mark in near the parents on level l of level l + 1's near nodes (their values pass through
 * level l), each image's node with the image (the restriction folds it there). */
static void mark_parents(const mpm_hier *h, int l, unsigned char *near) {
  const mpm_hier_level *lv = &h->level[l], *fv = &h->level[l + 1];
  const size_t np = (size_t)1 << h->dim;
  for (mpm_lidx k = 0; k < fv->nnear; ++k)
    for (size_t q = 0; q < np; ++q) near[fv->near_idx[(size_t)k * np + q]] = 1;
  for (mpm_lidx q = 0; q < lv->nimage; ++q)
    if (near[lv->image[q]]) near[lv->canon[q]] = 1;
}

/* mpm_hier_level.near, near_idx and near_w of level l >= 1 (after make_parents_box). */
static int make_near(mpm_hier *h, int l) {
  mpm_hier_level *lv = &h->level[l];
  const mpm_grid *g = lv->grid;
  const mpm_grid *c = h->nranks > 1 && l == 1 ? h->pbox.grid : h->level[l - 1].grid;
  const int np = 1 << h->dim;
  unsigned char *mask, *tmp;
  MPM_ALLOC(mask, g->nnodes);
  tmp = malloc((size_t)g->nnodes);
  if (!tmp) {
    free(mask);
    MPM_FAIL_OOM((size_t)g->nnodes);
  }
  near_mask(h, l, mask, tmp);
  free(tmp);
  if (l + 1 < h->nlevels) mark_parents(h, l, mask);
  lv->nnear = 0;
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    mask[n] &= !lv->active[n] && !(lv->is_image && lv->is_image[n]);
    lv->nnear += mask[n];
  }
  const size_t nn = (size_t)MPM_MAX(lv->nnear, 1);
  lv->near = malloc(sizeof *lv->near * nn);
  lv->near_idx = malloc(sizeof *lv->near_idx * nn * (size_t)np);
  lv->near_w = malloc(sizeof *lv->near_w * nn * (size_t)np);
  if (!lv->near || !lv->near_idx || !lv->near_w) {
    free(mask);
    MPM_FAIL_OOM(nn * (size_t)np * (sizeof(double) + sizeof(mpm_lidx)));
  }
  int gi[MPM_MAX_DIM];
  for (mpm_lidx n = 0, k = 0; n < g->nnodes; ++n) {
    if (!mask[n]) continue;
    hier_node_of(g, n, gi);
    lv->near[k] = n;
    mpm_hier_parents(c, gi, lv->near_idx + (size_t)k * np, lv->near_w + (size_t)k * np);
    ++k;
  }
  free(mask);
  return 0;
}

/* mpm_hier_level.plain of level l (its box, period and h's walls set). */
static void set_plain(mpm_hier *h, int l) {
  mpm_hier_level *lv = &h->level[l];
  const mpm_grid *g = lv->grid;
  for (int d = 0; d < h->dim; ++d) {
    int a = g->box_lo[d], z = g->box_lo[d] + g->box_n[d] - 1;
    int twice_lo, twice_hi;
    hier_faces(h, l, d, &twice_lo, &twice_hi);
    if (h->wall[d][0]) a = MPM_MAX(a, (twice_lo + 1) / 2); /* (hier_mirror: 2 i >= twice_lo) */
    if (h->wall[d][1]) z = MPM_MIN(z, twice_hi / 2);       /* (2 i <= twice_hi) */
    if (lv->period[d]) a = MPM_MAX(a, 0), z = MPM_MIN(z, lv->period[d] - 1);
    lv->plain[d][0] = a, lv->plain[d][1] = z;
  }
}

/* Levels 1 .. nlevels - 1 in turn (each snaps its boxes to the level before); why is set on an
 * input error. */
static int build_levels(mpm_hier *h, const mpm_hier_box *box, int nbox, char *why, size_t len) {
  box_spans *sp;
  MPM_ALLOC(sp, nbox);
  int rc = 0;
  set_plain(h, 0);
  for (int l = 1; l < h->nlevels && !rc; ++l) {
    for (int k = 0; k < nbox; ++k)
      if (box[k].level == l) sp[k] = snap_box(h->level[l - 1].grid, &box[k]);
    rc = check_nesting(h, l, sp, box, nbox, why, len);
    if (!rc) rc = make_level(h, l, box, sp, nbox);
    if (!rc) set_plain(h, l);
  }
  free(sp);
  for (int l = 0; l < h->nlevels && !rc; ++l)
    set_active(h, l), h->level[l].inv_h = 1.0 / h->level[l].grid->dx;
  if (!rc && h->nranks > 1 && h->nlevels > 1) rc = make_parents_box(h);
  for (int l = h->nlevels - 1; l >= 1 && !rc; --l) rc = make_near(h, l); /* (finest first) */
  if (!rc) rc = make_leaf(h);
  return rc;
}

int mpm_hier_new(mpm_hier **hp, mpm_grid *grid, int nlevels, const mpm_hier_box *box, int nbox,
                 int buffer, char *why, size_t why_len) {
  return mpm_hier_new_walled(hp, grid, nlevels, box, nbox, buffer, NULL, why, why_len);
}

int mpm_hier_new_walled(mpm_hier **hp, mpm_grid *grid, int nlevels, const mpm_hier_box *box,
                        int nbox, int buffer, const unsigned char (*wall)[2], char *why,
                        size_t why_len) {
  *hp = NULL;
  if (why && why_len) why[0] = '\0';
  int rc = check_setup(grid, nlevels, buffer, why, why_len);
  if (!rc) rc = check_boxes(grid, nlevels, box, nbox, why, why_len);
  if (rc) return rc;
  mpm_hier *h;
  MPM_ALLOC(h, 1);
  h->dim = grid->dim, h->nlevels = nlevels, h->buffer = buffer;
  h->nranks = grid->size, h->rank = grid->rank;
  for (int d = 0; wall && d < grid->dim; ++d)
    h->wall[d][0] = grid->periodic[d] ? 0 : wall[d][0],
    h->wall[d][1] = grid->periodic[d] ? 0 : wall[d][1];
  h->level[0].grid = grid;
  for (int d = 0; d < grid->dim; ++d)
    h->level[0].period[d] = grid->periodic[d] ? grid->ncells[d] : 0;
  rc = alloc_masks(&h->level[0]);
  if (!rc) memset(h->level[0].covered, 1, (size_t)grid->nnodes);
  if (!rc) rc = build_levels(h, box, nbox, why, why_len);
  if (!rc) rc = mpm_hier_add_phases(h);
  if (rc) {
    mpm_hier_destroy(&h);
    return rc;
  }
  *hp = h;
  return 0;
}

void mpm_hier_destroy(mpm_hier **hp) {
  if (!hp || !*hp) return;
  mpm_hier *h = *hp;
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l) {
    mpm_hier_level *lv = &h->level[l];
    if (l > 0) mpm_grid_destroy(&lv->grid);
    free(lv->covered), free(lv->refined), free(lv->active);
    free(lv->image), free(lv->canon), free(lv->is_image);
    free(lv->near), free(lv->near_idx), free(lv->near_w);
  }
  mpm_grid_destroy(&h->pbox.grid);
  free(h->pbox.owned), free(h->pbox.buf), free(h->sum_buf);
  mpm_hier_scratch_free(h->scratch);
  mpm_hier_census_free(h->census);
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l) free(h->leaf[l]);
  free(h);
  *hp = NULL;
}

/* ---- points ----------------------------------------------------------------------------- */

/* Does h carry a wall (mpm_hier.h, walls)? */
static int walled(const mpm_hier *h) {
  int any = 0;
  for (int d = 0; d < h->dim; ++d) any |= h->wall[d][0] | h->wall[d][1];
  return any;
}

/* Does g's box hold the quadratic stencil of x? Only a point beyond a wall can fail it: its
 * mirrored masks may send it to a finer level whose box stops two nodes past the wall (a point
 * in an integrator's stage may step past a wall before the walls return it); it then stays on
 * the coarser level, whose pad holds it. */
static int stencil_in_box(const mpm_grid *g, const double *x) {
  for (int d = 0; d < g->dim; ++d) {
    const int first = hier_span_of(hier_xi(g, d, x[d])) - 1;
    if (first < g->box_lo[d] || first + 2 > g->box_lo[d] + g->box_n[d] - 1) return 0;
  }
  return 1;
}

/* The walk from level 0 (x wrapped). */
static int level_walk(const mpm_hier *h, const double *x) {
  int l = 0, gi[MPM_MAX_DIM] = {0, 0, 0};
  const int walls = walled(h);
  for (; l + 1 < h->nlevels; ++l) {
    const mpm_grid *g = h->level[l].grid;
    for (int d = 0; d < h->dim; ++d) {
      const double xi = hier_xi(g, d, x[d]);
      /* Also false for NaN: such a point stays where it is. On more than one rank level 0's
       * box is the rank's: span_flag finds the spans beyond it on level 1. */
      if (!(xi > g->box_lo[d] - 1.0 && xi < g->box_lo[d] + g->box_n[d]) &&
          (l > 0 || h->nranks == 1 || xi != xi))
        return l;
      gi[d] = hier_span_of(xi);
    }
    if (!span_flag(h, l, h->level[l].refined, gi, 0)) return l;
    if (walls && !stencil_in_box(h->level[l + 1].grid, x)) return l;
  }
  return l;
}

int mpm_hier_level_walk(const mpm_hier *h, const double *xp) {
  double x[MPM_MAX_DIM];
  hier_wrap_point(h, xp, x);
  return level_walk(h, x);
}

/* How far inside its span (in spans) a point must lie for a table to answer: then the next
 * level puts it in one of the span's children, whatever the roundoff of its position in that
 * level's units. */
#define LEAF_MARGIN 1e-6

/* How far inside a span (in spans) the box mpm_hier_level_box gives stops: twice the table's
 * margin, so that every point of the box passes leaf_at's test whatever the roundoff of its
 * position in level units (a few ulps of the span index). */
#define BOX_MARGIN (2.0 * LEAF_MARGIN)

/* Level l's table entry for x (wrapped), or -1 when x lies within the margin of its span's
 * faces or outside the level's box. With lo and hi set, also the span's box shrunk by
 * BOX_MARGIN (lo[d] <= x[d] <= hi[d]: every point in it has the same entry). */
static inline int leaf_at(const mpm_hier *h, int l, const double *x, double *lo, double *hi) {
  const mpm_grid *g = h->level[l].grid;
  const double inv_h = h->level[l].inv_h; /* (hier_xi's value, without its division) */
  mpm_lidx k = 0;
  for (int d = h->dim - 1; d >= 0; --d) {
    const double t = (x[d] - g->lo[d]) * inv_h + 0.5; /* the span's index plus its fraction */
    /* Inside the box's spans (false for NaN and for any point far outside: no cast overflows),
     * then away from the span's faces. */
    if (!(t >= g->box_lo[d] && t < g->box_lo[d] + g->box_n[d])) return -1;
    const int f = mpm_shape_floor(t);
    const double frac = t - (double)f;
    if (!(frac > LEAF_MARGIN && frac < 1.0 - LEAF_MARGIN)) return -1;
    k = k * g->box_n[d] + (f - g->box_lo[d]);
    if (lo) {
      lo[d] = g->lo[d] + ((double)f - 0.5 + BOX_MARGIN) * g->dx;
      hi[d] = g->lo[d] + ((double)f + 0.5 - BOX_MARGIN) * g->dx;
    }
  }
  return h->leaf[l][k] == MPM_HIER_WALK ? -1 : h->leaf[l][k];
}

int mpm_hier_level_of(const mpm_hier *h, const double *xp) {
  return mpm_hier_level_from(h, xp, -1);
}

int mpm_hier_level_from(const mpm_hier *h, const double *xp, int hint) {
  return mpm_hier_level_box(h, xp, hint, NULL, NULL);
}

/* The box of a table's answer for x (wrapped) clipped to the domain along the axes the
 * hierarchy wraps (to [lo, hi - 1e-9 dx], where wrapping changes no point), so that a point in
 * it is its own image; the point alone otherwise. */
static void answer_box(const mpm_hier *h, const double *x, int tabled, double *lo, double *hi) {
  const mpm_grid *g = h->level[0].grid;
  for (int d = 0; d < h->dim; ++d) {
    if (!tabled) {
      lo[d] = hi[d] = x[d];
    } else if (h->wraps && g->periodic[d]) {
      const double top = g->hi[d] - 1e-9 * g->dx;
      lo[d] = lo[d] < g->lo[d] ? g->lo[d] : lo[d];
      hi[d] = hi[d] > top ? top : hi[d];
    }
  }
}

int mpm_hier_level_box(const mpm_hier *h, const double *xp, int hint, double *lo, double *hi) {
  double x[MPM_MAX_DIM];
  hier_wrap_point(h, xp, x);
  /* A span of level `hint` whose table entry is the level itself answers for every point
   * inside it (uncovered spans of the finer levels hold MPM_HIER_WALK: they never answer). */
  if (hint >= 0 && hint < h->nlevels && h->leaf[0] && leaf_at(h, hint, x, lo, hi) == hint) {
    if (lo) { /* the coarsest span about x all of whose points have that level: the widest box */
      double a[MPM_MAX_DIM], z[MPM_MAX_DIM];
      for (int l = hint - 1; l >= 0 && leaf_at(h, l, x, a, z) == hint; --l)
        for (int d = 0; d < h->dim; ++d) lo[d] = a[d], hi[d] = z[d];
      answer_box(h, x, 1, lo, hi);
    }
    return hint;
  }
  for (int l = 0; l < h->nlevels && h->leaf[0]; ++l) {
    const int v = leaf_at(h, l, x, lo, hi);
    if (v < 0) break;
    if (v != MPM_HIER_MIXED) {
      if (lo) answer_box(h, x, 1, lo, hi);
      return v;
    }
  }
  /* The walk's answer holds for the point itself: the box of an unmoved point (the raw x, which
   * wrapping may change). */
  if (lo) answer_box(h, xp, 0, lo, hi);
  return level_walk(h, x);
}

/* The level every point of span gi of level l reaches, or -1 when it differs within it: the
 * span's own level if it is not refined, else its 2^dim children's on level l + 1 when they
 * all agree. */
static int uniform_level(const mpm_hier *h, int l, const int *gi) {
  if (l + 1 == h->nlevels || !span_flag(h, l, h->level[l].refined, gi, 0)) return l;
  int level = -1, c[MPM_MAX_DIM] = {0, 0, 0};
  for (int k = 0; k < 1 << h->dim; ++k) {
    for (int d = 0; d < h->dim; ++d) c[d] = 2 * gi[d] + ((k >> d) & 1);
    const int u = uniform_level(h, l + 1, c);
    if (u < 0 || (level >= 0 && u != level)) return -1;
    level = u;
  }
  return level;
}

/* uniform_level, reading the next level's answers from below (box order, found first) for
 * children in its plain range, where the box node is the child itself. */
static int uniform_below(const mpm_hier *h, int l, const int *gi, const signed char *below) {
  if (l + 1 == h->nlevels || !span_flag(h, l, h->level[l].refined, gi, 0)) return l;
  const mpm_hier_level *fv = &h->level[l + 1];
  int level = -1, c[MPM_MAX_DIM] = {0, 0, 0};
  for (int k = 0; k < 1 << h->dim; ++k) {
    int plain = 1;
    for (int d = 0; d < h->dim; ++d) {
      c[d] = 2 * gi[d] + ((k >> d) & 1);
      plain &= c[d] >= fv->plain[d][0] && c[d] <= fv->plain[d][1];
    }
    const int u = plain ? below[mpm_grid_local_index(fv->grid, c)] : uniform_level(h, l + 1, c);
    if (u < 0 || (level >= 0 && u != level)) return -1;
    level = u;
  }
  return level;
}

/* mpm_hier.leaf. Spans within three level-0 cells of a walled face are left to the walk (its
 * stencil test for points beyond the face); so are the spans of a finer level outside its region,
 * which the lookup down the levels never reaches and mpm_hier_level_from's hint may. */
static int make_leaf(mpm_hier *h) {
  int gi[MPM_MAX_DIM];
  signed char *below = NULL;                  /* level l + 1's uniform_level at each box node */
  for (int l = h->nlevels - 1; l >= 0; --l) { /* (finest first) */
    const mpm_grid *g = h->level[l].grid;
    signed char *uni = malloc((size_t)g->nnodes);
    h->leaf[l] = malloc((size_t)g->nnodes);
    if (!uni || !h->leaf[l]) {
      free(uni), free(below);
      MPM_FAIL_OOM(2 * (size_t)g->nnodes);
    }
    for (mpm_lidx k = 0; k < g->nnodes; ++k) {
      hier_node_of(g, k, gi);
      const int near_wall =
          beside_wall(h, g, gi) || (l > 0 && !span_flag(h, l, h->level[l].covered, gi, 0));
      const int u = uni[k] = (signed char)uniform_below(h, l, gi, below);
      h->leaf[l][k] = near_wall ? MPM_HIER_WALK : u < 0 ? MPM_HIER_MIXED : (unsigned char)u;
    }
    free(below);
    below = uni;
  }
  free(below);
  return 0;
}

/* ---- phases ----------------------------------------------------------------------------- */

int mpm_hier_add_phases(mpm_hier *h) {
  const mpm_grid *g0 = h->level[0].grid;
  for (int l = 1; l < h->nlevels; ++l) {
    mpm_grid *g = h->level[l].grid;
    for (int p = g->nphases; p < g0->nphases; ++p) {
      MPM_CALL(mpm_grid_add_phase(g, g0->phase[p].name, NULL));
      g->phase[p].empty_fraction = g0->phase[p].empty_fraction;
      g->phase[p].light_fraction = g0->phase[p].light_fraction;
    }
  }
  return 0;
}

void mpm_hier_phase_zero(mpm_hier *h, int phase) {
  const int normals = h->level[0].grid->phase[phase].normals;
  for (int l = 0; l < h->nlevels; ++l) {
    h->level[l].grid->phase[phase].normals = normals;
    mpm_grid_phase_zero(h->level[l].grid, phase);
  }
  h->pending[phase] = h->summed[phase] = 0;
}

int mpm_hier_phase_update(mpm_hier *h, int phase, double hstep) {
  mpm_grid *grids[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < h->nlevels; ++l) grids[l] = h->level[l].grid;
  MPM_CALL(mpm_grid_phase_update_many(grids, h->nlevels, phase, hstep));
  return 0;
}
