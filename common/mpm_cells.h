/* Cell occupancy: how many particles of each phase every cell of the grid holds, shared on
 * the grid so that one module can see where another's material is without knowing it.
 *
 * Cell c (global cell coordinates) is stored at node c, its lower corner, in the phase's box
 * array `cell_n`: the owner of a cell owns that node, so a count taken after migration needs
 * no reverse halo, and the forward halo gives every rank the counts of the cells up to `ghost`
 * (at least 2) beyond its own. Cells outside the domain read 0. */
#ifndef MPM_CELLS_H
#define MPM_CELLS_H

#include "mpm_grid.h"
#include "mpm_particles.h"
#include "mpm_shape.h"

/* Count the particles of p (all on the ranks that own their cells: call after migration) per
 * cell into grid->phase[phase].cell_n, owned cells and ghost cells. Collective. */
int mpm_cells_count(mpm_grid *grid, int phase, const mpm_particles *p);

/* Global cell coordinate of x along d, clamped into the domain (as mpm_grid_owner_of). */
static inline int mpm_cells_coord(const mpm_grid *g, int d, double x) {
  const int c = mpm_shape_floor((x - g->lo[d]) / g->dx);
  return c < 0 ? 0 : c >= g->ncells[d] ? g->ncells[d] - 1 : c;
}

/* Is global cell c inside the domain, after wrapping periodic axes into [0, ncells)? */
static inline int mpm_cells_wrap(const mpm_grid *g, int *c) {
  for (int d = 0; d < g->dim; ++d) {
    if (g->periodic[d]) c[d] = (c[d] % g->ncells[d] + g->ncells[d]) % g->ncells[d];
    if (c[d] < 0 || c[d] >= g->ncells[d]) return 0;
  }
  return 1;
}

#endif
