/* The wall rule on the finer levels of the hierarchy (mpm_hier.h, walls): every node of a level
 * l >= 1 beyond a walled face is folded into its mirror before the solve (its deposit is the
 * mirror image's, the constrained components negated) and set from it after the solve.
 *
 * Invariants: a wall face is a knot of every finer level, so no finer node lies on it (level 0's
 * face nodes, held by mpm_bc.c, have no counterpart here) and every node beyond it has a mirror
 * inside; a node whose mirror lies outside the level's box (the box's outermost layers, whose
 * supports stay beyond the wall) is skipped. Faces are taken axis by axis in both calls, so a
 * corner node folds through the first wall onto a node beyond the second, which then folds
 * inside, and is set back in the same order. Level 0 is left to mpm_bc.c. */
#include "mpm_hier_impl.h"

/* The mirror of box node n of level l along axis d (its box index), or -1 when n is not beyond
 * a wall of d or its mirror leaves the box. */
mpm_lidx mpm_hier_wall_mirror(const mpm_hier *h, int l, int d, mpm_lidx n) {
  const mpm_grid *g = h->level[l].grid;
  int gi[MPM_MAX_DIM];
  hier_node_of(g, n, gi);
  const int m = hier_mirror(h, l, d, gi[d]);
  if (m == gi[d]) return -1;
  gi[d] = m;
  return hier_in_box(g, gi) ? mpm_grid_local_index(g, gi) : -1;
}

static int has_walls(const mpm_hier *h, int d) {
  return h->wall[d][0] || h->wall[d][1];
}

/* Call fn on every node n of a finer level beyond a wall of axis d, with its mirror s and the
 * components the wall flips there (the wall on n's side): both passes walk the same nodes, axis
 * by axis. Only the layers beyond a wall are visited: along d the mirror maps layer j of the box
 * onto layer m, so node n's mirror is n + (m - j) stride_d. Within one axis every mirror lies
 * inside and takes one node, so the order of the layers does not change a sum. */
typedef void (*mirror_fn)(mpm_grid_phase *ph, int dim, mpm_lidx n, mpm_lidx s, unsigned char mask);

static void each_mirror(mpm_hier *h, int phase, mirror_fn fn) {
  for (int l = 1; l < h->nlevels; ++l) {
    mpm_grid *g = h->level[l].grid;
    mpm_grid_phase *ph = &g->phase[phase];
    for (int d = 0; d < h->dim; ++d) {
      if (!has_walls(h, d)) continue;
      mpm_lidx stride = 1; /* nodes per layer step along d */
      for (int e = 0; e < d; ++e) stride *= g->box_n[e];
      const mpm_lidx slab = stride * g->box_n[d], outer = g->nnodes / slab;
      const int lo = g->box_lo[d], hi = lo + g->box_n[d];
      for (int j = lo; j < hi; ++j) {
        const int m = hier_mirror(h, l, d, j);
        if (m == j || m < lo || m >= hi) continue; /* not beyond a wall, or its mirror outside */
        const unsigned char mask = h->wall[d][2 * j > (1 << l) - 1];
        const mpm_lidx shift = (mpm_lidx)(m - j) * stride;
        for (mpm_lidx o = 0; o < outer; ++o)
          for (mpm_lidx q = 0; q < stride; ++q) {
            const mpm_lidx n = o * slab + (mpm_lidx)(j - lo) * stride + q;
            fn(ph, h->dim, n, n + shift, mask);
          }
      }
    }
  }
}

/* Add node n's m, m v and f into its mirror s (the flipped components negated), zero n. */
static void fold_node(mpm_grid_phase *ph, int dim, mpm_lidx n, mpm_lidx s, unsigned char mask) {
  ph->m_i[s] += ph->m_i[n], ph->m_i[n] = 0.0;
  for (int e = 0; e < dim; ++e) {
    const double sign = (mask >> e) & 1 ? -1.0 : 1.0;
    ph->mv_i[e][s] += sign * ph->mv_i[e][n], ph->mv_i[e][n] = 0.0;
    ph->f_i[e][s] += sign * ph->f_i[e][n], ph->f_i[e][n] = 0.0;
  }
}

/* Set node n's v and a to its mirror s's (the flipped components negated). */
static void apply_node(mpm_grid_phase *ph, int dim, mpm_lidx n, mpm_lidx s, unsigned char mask) {
  for (int e = 0; e < dim; ++e) {
    const double sign = (mask >> e) & 1 ? -1.0 : 1.0;
    ph->v_i[e][n] = sign * ph->v_i[e][s];
    ph->a_i[e][n] = sign * ph->a_i[e][s];
  }
}

void mpm_hier_walls_fold(mpm_hier *h, int phase) {
  each_mirror(h, phase, fold_node);
}

void mpm_hier_walls_apply(mpm_hier *h, int phase) {
  each_mirror(h, phase, apply_node);
}
