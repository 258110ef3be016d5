/* The coupling scheme on the levels of a refinement hierarchy (see mpm_coupling.h,
 * mpm_coupling_set_hier; docs/refinement.md, "A gas beside a solid").
 *
 * Where the exchange sits. The cycle restricts both phases' deposits onto the active nodes of
 * every level, solves each phase there, runs the scheme, the constraints, and prolongs
 * (coupler/mpm_cycle.c). The composite basis is the active nodes' truncated B-splines, and the
 * nodal solve is lumped, one equation per active node: an active node of level l is, for the
 * coupling, a node like any of the uniform grid's. So the scheme runs on each level's active
 * nodes, after the solves and before the prolongation: the per-node exchange of velocity (both
 * phases take m-weighted mean velocity and acceleration) then balances node by node, and the
 * prolongation, linear and the same for both phases, hands them the same velocity wherever their
 * composite weights reach shared nodes only. Inactive nodes are empty after the restriction,
 * so a scheme skips them as it skips any empty node. A scheme's per-node state (traction's held
 * velocities, the walls' axes of its normals) is kept per level and swapped in with the grid.
 *
 * Carried: velocity and traction, under the ERK pairs and usl. Not carried: contact (not
 * measured on the levels; refused), traction's least-squares wall (mpm_solid_wall.h gathers the
 * solid on level 0's cells) and the per-body forces of several bodies.
 *
 * Invariants: without a hierarchy nlev = 0 and every hook runs once on the grid, as before, bit
 * for bit; c->grid, c->owned and the per-node state are level 0's between hooks. */
#include "mpm_coupling.h"

#include "mpm_error.h"

#include <stdlib.h>
#include <string.h>

/* Per-node state of level l >= 1: the walls' axes (none: beside a solid every box keeps off the
 * walls, coupler/mpm_refine.c) and the held velocities, as build() allocates level 0's. */
static int level_state(mpm_coupling *c, int l, mpm_lidx nn) {
  if (c->wall_axes) {
    c->lev_wall_axes[l] = calloc((size_t)nn, 1);
    if (!c->lev_wall_axes[l]) MPM_FAIL_OOM((size_t)nn);
  }
  for (int d = 0; c->held_v[0] && d < c->grid->dim; ++d) {
    MPM_ALLOC(c->lev_held[l][0][d], nn);
    MPM_ALLOC(c->lev_held[l][1][d], nn);
  }
  return 0;
}

int mpm_coupling_set_hier(mpm_coupling *c, const mpm_config *cfg, const mpm_hier *h) {
  if (!c) return 0;
  if (c->nlev > 0) { /* a regrid: the levels' state starts afresh on the new hierarchy */
    mpm_coupling_levels_free(c);
    memset(c->lev_grid, 0, sizeof c->lev_grid);
    memset(c->lev_owned, 0, sizeof c->lev_owned);
    memset(c->lev_wall_axes, 0, sizeof c->lev_wall_axes);
    memset(c->lev_held, 0, sizeof c->lev_held);
    c->nlev = 0;
  }
  if (!h || h->nlevels < 2) return 0;
  if (strcmp(c->type->name, "contact") == 0 || strcmp(c->type->name, "sharp") == 0)
    return mpm_config_fail(cfg, "coupling.scheme",
                           "coupling.scheme = %s is not carried to the refined levels "
                           "(refine.levels > 1); use velocity or traction, or set refine.levels "
                           "= 1 (docs/refinement.md)",
                           c->type->name);
  if (strcmp(c->type->name, "traction") == 0 && c->content) /* its least-squares wall */
    return mpm_config_fail(cfg, "fluid.wall_treatment",
                           "the solid's surface as the gas's least-squares wall is not carried "
                           "to the refined levels (refine.levels > 1): it gathers the solid on "
                           "level 0's cells; remove the key or set refine.levels = 1 "
                           "(docs/refinement.md)");
  if (c->nbodies > 0)
    return mpm_config_fail(cfg, "refine.levels",
                           "the solid has %d bodies, whose forces coupling.csv reports one by one "
                           "from level 0's nodes, which refinement does not carry; keep one "
                           "[solid.NAME] body or set refine.levels = 1 (docs/refinement.md)",
                           c->nbodies);
  c->nlev = h->nlevels;
  c->lev_grid[0] = c->grid, c->lev_owned[0] = c->owned, c->lev_wall_axes[0] = c->wall_axes;
  for (int d = 0; d < MPM_MAX_DIM; ++d)
    c->lev_held[0][0][d] = c->held_v[d], c->lev_held[0][1][d] = c->held_a[d];
  for (int l = 1; l < h->nlevels; ++l) {
    const mpm_hier_level *lv = &h->level[l];
    const mpm_lidx nn = lv->grid->nnodes;
    c->lev_grid[l] = lv->grid;
    MPM_ALLOC(c->lev_owned[l], nn);
    /* On more than one rank every rank holds a finer level whole and couples it alike
     * (mpm_hier.h, ranks); rank 0 alone books it, as the reports sum the ranks. */
    for (mpm_lidx n = 0; n < nn; ++n)
      c->lev_owned[l][n] = h->rank == 0 && lv->active[n] && !(lv->is_image && lv->is_image[n]);
    MPM_CALL(level_state(c, l, nn));
  }
  return 0;
}

void mpm_coupling_levels_free(mpm_coupling *c) {
  for (int l = 1; l < c->nlev; ++l) {
    free(c->lev_owned[l]), free(c->lev_wall_axes[l]);
    for (int d = 0; d < MPM_MAX_DIM; ++d) free(c->lev_held[l][0][d]), free(c->lev_held[l][1][d]);
  }
}

/* Point c's grid and per-node state at level l's. */
static void use_level(mpm_coupling *c, int l) {
  c->grid = c->lev_grid[l], c->owned = c->lev_owned[l], c->wall_axes = c->lev_wall_axes[l];
  for (int d = 0; d < MPM_MAX_DIM; ++d)
    c->held_v[d] = c->lev_held[l][0][d], c->held_a[d] = c->lev_held[l][1][d];
}

int mpm_coupling_each_level(mpm_coupling *c, mpm_coupling_level_fn fn, double t, double h,
                            mpm_pass pass) {
  if (c->nlev == 0) return fn(c, t, h, pass);
  int rc = 0;
  for (int l = 0; l < c->nlev && !rc; ++l) {
    use_level(c, l);
    rc = fn(c, t, h, pass);
  }
  use_level(c, 0);
  return rc;
}
