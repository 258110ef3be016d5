/* Cell occupancy (see mpm_cells.h). */
#include "mpm_cells.h"

#include "mpm_error.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int mpm_cells_count(mpm_grid *g, int phase, const mpm_particles *p) {
  mpm_grid_phase *ph = &g->phase[phase];
  if (!ph->cell_n) MPM_ALLOC(ph->cell_n, g->nnodes);
  memset(ph->cell_n, 0, sizeof *ph->cell_n * (size_t)g->nnodes);
  const double *x[MPM_MAX_DIM]; /* (read once: cell_n may alias the block) */
  for (int d = 0; d < g->dim; ++d) x[d] = mpm_particles_comp(p, 0, d);
  double *restrict count = ph->cell_n;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    int c[MPM_MAX_DIM] = {0};
    for (int d = 0; d < g->dim; ++d) c[d] = mpm_cells_coord(g, d, x[d][i]);
    count[mpm_grid_local_index(g, c)] += 1.0;
  }
  double *f[1] = {ph->cell_n};
  return mpm_grid_halo_forward(g, f, 1);
}

mpm_lidx mpm_cells_level_index(const mpm_hier *h, int l, const int *k) {
  const mpm_grid *g0 = h->level[0].grid, *g = h->level[l].grid;
  mpm_lidx idx = 0;
  for (int d = g->dim - 1; d >= 0; --d) {
    const int n = g0->ncells[d] << l;
    int c = k[d];
    if (g0->periodic[d]) c = (c % n + n) % n;
    if (c < 0 || c >= n) return -1;
    const int j = c + (1 << (l - 1)) - g->box_lo[d]; /* span c + 2^(l-1), box-relative */
    if (j < 0 || j >= g->box_n[d]) return -1;
    idx = idx * g->box_n[d] + j;
  }
  return idx;
}

mpm_lidx mpm_cells_level_index_at(const mpm_hier *h, int l, const double *x) {
  const mpm_grid *g0 = h->level[0].grid;
  int k[MPM_MAX_DIM] = {0};
  for (int d = 0; d < g0->dim; ++d) k[d] = (int)floor((x[d] - g0->lo[d]) * h->level[l].inv_h);
  return mpm_cells_level_index(h, l, k);
}

int mpm_cells_count_levels(mpm_hier *h, int phase, const mpm_particles *p,
                           const unsigned char *lev) {
  const mpm_grid *g0 = h->level[0].grid;
  const int dim = g0->dim;
  for (int l = 1; l < h->nlevels; ++l) {
    mpm_grid_phase *ph = &h->level[l].grid->phase[phase];
    if (!ph->cell_n) MPM_ALLOC(ph->cell_n, h->level[l].grid->nnodes);
    memset(ph->cell_n, 0, sizeof *ph->cell_n * (size_t)h->level[l].grid->nnodes);
  }
  if (h->nlevels < 2) return 0;
  const double *x[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, 0, d);
  if (!lev) lev = mpm_hier_levels(h, x, p->n); /* (NULL when out of memory: looked up below) */
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double xi[MPM_MAX_DIM] = {0};
    for (int d = 0; d < dim; ++d) xi[d] = x[d][i];
    const int l = lev ? lev[i] : mpm_hier_level_of(h, xi);
    if (l < 1) continue;
    const mpm_lidx j = mpm_cells_level_index_at(h, l, xi);
    if (j >= 0) h->level[l].grid->phase[phase].cell_n[j] += 1.0;
  }
  if (h->nranks < 2) return 0;
  for (int l = 1; l < h->nlevels; ++l) {
    const mpm_grid *g = h->level[l].grid;
    if (g->nnodes > INT_MAX) MPM_FAIL(MPM_ERR_INTERNAL, "cells: level %d's box is too large", l);
    MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, g->phase[phase].cell_n, (int)g->nnodes, MPI_DOUBLE,
                               MPI_SUM, g0->comm));
  }
  return 0;
}
