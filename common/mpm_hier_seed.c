/* Seeding the finer levels of a refinement hierarchy (see mpm_hier_seed.h).
 *
 * Invariant: a lattice point is kept on exactly one level, the one mpm_hier_level_of gives for
 * it, so seeding every level's lattice over the same region fills it once. */
#include "mpm_hier_seed.h"

#include "mpm_error.h"

#include <stdlib.h>
#include <string.h>

int mpm_hier_lattice(const mpm_hier *h, int l, int ppc, const mpm_region *r, double **xp,
                     mpm_lidx *np, mpm_gidx *span) {
  const mpm_grid *lg = h->level[l].grid, *g = h->level[0].grid;
  const int dim = g->dim;
  int per[MPM_MAX_DIM] = {1, 1, 1};
  mpm_lidx cap = 1;
  for (int d = 0; d < dim; ++d) per[d] = lg->box_n[d] * ppc, cap *= per[d];
  double *x;
  MPM_ALLOC(x, (size_t)dim * cap);
  mpm_lidx n = 0;
  for (mpm_lidx q = 0; q < cap; ++q) {
    double xq[3] = {0, 0, 0};
    int in = 1;
    mpm_lidx rest = q;
    for (int d = 0; d < dim; ++d) {
      const int k = (int)(rest % per[d]), j = lg->box_lo[d] + k / ppc, s = k % ppc;
      rest /= per[d];
      xq[d] = lg->lo[d] + (j - 0.5 + (s + 0.5) / ppc) * lg->dx;
      in &= xq[d] > g->lo[d] && xq[d] < g->hi[d];
    }
    if (!in || !mpm_region_contains(r, xq) || mpm_hier_level_of(h, xq) != l) continue;
    for (int d = 0; d < dim; ++d) x[(size_t)d * cap + n] = xq[d];
    ++n;
  }
  for (int d = 1; d < dim; ++d) memmove(x + (size_t)d * n, x + (size_t)d * cap, sizeof *x * n);
  *xp = x, *np = n, *span = cap;
  return 0;
}

mpm_lidx mpm_hier_keep_owned(const mpm_grid *g, double *x, mpm_gidx *id, mpm_lidx n) {
  if (g->size == 1) return n;
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    double xq[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < g->dim; ++d) xq[d] = x[(size_t)d * n + i];
    if (mpm_grid_owner_of(g, xq) != g->rank) continue;
    for (int d = 0; d < g->dim; ++d) x[(size_t)d * n + k] = xq[d];
    id[k++] = id[i];
  }
  for (int d = 1; d < g->dim; ++d) memmove(x + (size_t)d * k, x + (size_t)d * n, sizeof *x * k);
  return k;
}

int mpm_hier_drop_refined(const mpm_hier *h, mpm_particles *p, int field_x) {
  unsigned char *keep;
  MPM_ALLOC(keep, p->n);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double xq[3] = {0, 0, 0};
    for (int d = 0; d < p->dim; ++d) xq[d] = mpm_particles_comp(p, field_x, d)[i];
    keep[i] = mpm_hier_level_of(h, xq) == 0;
  }
  const int rc = mpm_particles_edit(p, keep, 0, NULL, NULL);
  free(keep);
  return rc;
}
