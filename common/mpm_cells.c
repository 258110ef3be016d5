/* Cell occupancy (see mpm_cells.h). */
#include "mpm_cells.h"

#include "mpm_error.h"

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
