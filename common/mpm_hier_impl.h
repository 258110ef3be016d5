/* What the files of the refinement hierarchy share (mpm_hier.c: construction, regions and
 * phases; mpm_hier_basis.c: the two-scale relation, restriction, prolongation and the
 * composite basis; mpm_hier_transfer.c: composite P2G and G2P). Not for other modules.
 *
 * Invariants the three files rely on: level l's lattice is the box grid level[l].grid (the
 * shared grid at l = 0) with lo = o_l and dx = h_l; a point's position along d in level units
 * is computed exactly as the kernels compute it (hier_xi), so the span a point is assigned
 * to here is the span whose stencil the kernel uses, bit for bit. */
#ifndef MPM_HIER_IMPL_H
#define MPM_HIER_IMPL_H

#include "mpm_hier.h"

/* x along d in units of g's spacing from its node 0, as mpm_kernels_dim.c computes it. */
static inline double hier_xi(const mpm_grid *g, int d, double x) {
  return (x - g->lo[d]) * (1.0 / g->dx);
}

/* The span (dual cell) of g's lattice holding xi: the centre node of the quadratic stencil,
 * whose first node the kernels take as floor(xi - 1/2). */
static inline int hier_span_of(double xi) {
  return mpm_shape_floor(xi - 0.5) + 1;
}

/* floor(a / 2) for either sign. */
static inline int hier_half(int a) {
  return a >= 0 ? a / 2 : -((1 - a) / 2);
}

/* i mod n in [0, n), for either sign of i (n > 0). */
static inline int hier_mod(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

/* Move gi (global indices of level lv's lattice, first dim entries) onto its image in
 * [0, period[d]) along every axis where the level has a period (mpm_hier.h, periodic axes). */
static inline int hier_canon_1d(const mpm_hier_level *lv, int d, int i) {
  const int P = lv->period[d]; /* (the division only for an image: this is a hot path) */
  return P && (i < 0 || i >= P) ? hier_mod(i, P) : i;
}

static inline void hier_canon(const mpm_hier_level *lv, int dim, int *gi) {
  for (int d = 0; d < dim; ++d) gi[d] = hier_canon_1d(lv, d, gi[d]);
}

/* Twice the index of level l's lattice along d at the domain's low and high faces. */
static inline void hier_faces(const mpm_hier *h, int l, int d, int *twice_lo, int *twice_hi) {
  *twice_lo = (1 << l) - 1;
  *twice_hi = 2 * (h->level[0].grid->ncells[d] << l) + *twice_lo;
}

/* Index i of level l's lattice along d at its mirror when it lies beyond a walled face
 * (mpm_hier.h, walls), else i: beyond the low face when 2 i < 2^l - 1, the high face when
 * 2 i > 2 N_l + 2^l - 1 (N_l = ncells[d] 2^l). */
static inline int hier_mirror(const mpm_hier *h, int l, int d, int i) {
  int twice_lo, twice_hi;
  hier_faces(h, l, d, &twice_lo, &twice_hi);
  if (h->wall[d][0] && 2 * i < twice_lo) return twice_lo - i;
  if (h->wall[d][1] && 2 * i > twice_hi) return twice_hi - i;
  return i;
}

/* x into out, wrapped into the domain along the periodic axes when the hierarchy wraps (a
 * level stores a whole period); a plain copy otherwise. */
static inline void hier_wrap_point(const mpm_hier *h, const double *x, double *out) {
  const mpm_grid *g = h->level[0].grid;
  for (int d = 0; d < MPM_MAX_DIM; ++d) out[d] = d < h->dim ? x[d] : 0.0;
  for (int d = 0; h->wraps && d < h->dim; ++d)
    if (g->periodic[d]) out[d] = mpm_wrap_coord(out[d], g->lo[d], g->hi[d]);
}

/* Does box node gi (global indices of g, first dim entries) lie in g's box? */
static inline int hier_in_box(const mpm_grid *g, const int *gi) {
  for (int d = 0; d < g->dim; ++d)
    if (gi[d] < g->box_lo[d] || gi[d] >= g->box_lo[d] + g->box_n[d]) return 0;
  return 1;
}

/* Global indices gi (first dim entries; 0 beyond) of g's box node l. */
static inline void hier_node_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  for (int d = 0; d < MPM_MAX_DIM; ++d) {
    gi[d] = d < g->dim ? g->box_lo[d] + (int)(l % g->box_n[d]) : 0;
    l /= g->box_n[d];
  }
}

/* The two parents of fine node j along one axis: p[0] = floor(j / 2) with weight 3/4 and
 * p[1] = p[0] - 1 + 2 (j mod 2) with weight 1/4. */
static inline void hier_parents_1d(int j, int p[2]) {
  const int m = hier_half(j);
  p[0] = m, p[1] = m - 1 + 2 * (j - 2 * m);
}

/* Parent k (0 .. 2^dim - 1) of a fine node whose per-axis parents are p (hier_parents_1d):
 * its global indices q (first dim entries) and its two-scale weight, the product over the axes
 * of 3/4 (bit d of k clear: parent p[d][0]) or 1/4 (bit set: p[d][1]). */
static inline double hier_parent_k(int dim, const int (*p)[2], int k, int *q) {
  double w = 1.0;
  for (int d = 0; d < dim; ++d) {
    const int b = (k >> d) & 1;
    q[d] = p[d][b];
    w *= b ? 0.25 : 0.75;
  }
  return w;
}

/* The 2^dim parents on the coarse lattice c of the fine node gi (the two-scale relation: along
 * each axis fine node 2m + r has parents m, weight 3/4, and m - 1 + 2r, weight 1/4): their box
 * indices in c and weights; returns 2^dim. */
int mpm_hier_parents(const mpm_grid *c, const int *gi, mpm_lidx *idx, double *w);

/* mpm_hier_level_from, and a box lo[d] <= y[d] <= hi[d] (first dim entries) of points y that
 * all have the level found (raw points: no wrapping needed). The box is the answering table
 * span's, shrunk by a margin (and clipped to the domain along the axes the hierarchy wraps),
 * or x alone when the walk answered. lo and hi may be NULL. */
int mpm_hier_level_box(const mpm_hier *h, const double *x, int hint, double *lo, double *hi);

/* Release the transfer scratch (mpm_hier_transfer.c). */
void mpm_hier_scratch_free(void *scratch);
/* Release the remembered levels (mpm_hier_census.c). */
void mpm_hier_census_free(void *census);

#endif
