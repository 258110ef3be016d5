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
#include "mpm_hier.h"
#include "mpm_particles.h"
#include "mpm_shape.h"

/* Count the particles of p (all on the ranks that own their cells: call after migration) per
 * cell into grid->phase[phase].cell_n, owned cells and ghost cells. Collective. */
int mpm_cells_count(mpm_grid *grid, int phase, const mpm_particles *p);

/* On a hierarchy (mpm_hier.h), the cells of a finer level l are its spans: span i of level l is
 * centred on node i, [o_l + (i - 1/2) h_l, o_l + (i + 1/2) h_l], and these lie on the lattice
 * lo + k h_l of the domain's origin (k = i - 2^(l-1)), nested in level 0's cells, so a span's
 * particles are all on the rank owning the level-0 cell around it. Count the particles of p whose
 * position is on level l >= 1 (lev[i], mpm_hier_levels; NULL: looked up here) per span of level l
 * into h->level[l].grid->phase[phase].cell_n, at the span's node (its box index), summed over the
 * ranks: every rank holds every finer level's counts whole. A particle counts on its own level
 * only (level 0's counts are mpm_cells_count's). Collective over level 0's communicator. */
int mpm_cells_count_levels(mpm_hier *h, int phase, const mpm_particles *p,
                           const unsigned char *lev);

/* The box index on finer level l (>= 1) of h of the cell k (global coordinates on level l's cell
 * lattice lo + k h_l, wrapped into the domain along a periodic axis), or -1 when the cell lies
 * outside the domain or the level's box (it then holds no particle of level l). */
mpm_lidx mpm_cells_level_index(const mpm_hier *h, int l, const int *k);
/* The same for the cell of level l holding the point x. */
mpm_lidx mpm_cells_level_index_at(const mpm_hier *h, int l, const double *x);

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
