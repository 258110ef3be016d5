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
 * so a scheme skips them as it skips any empty node.
 *
 * Invariants: without a hierarchy nlev = 0 and every hook runs once on the grid, as before, bit
 * for bit; c->grid and c->owned are the shared grid's between hooks. */
#include "mpm_coupling.h"

#include "mpm_error.h"

#include <stdlib.h>
#include <string.h>

/* The schemes carried onto the levels: their hooks touch only the phases' nodal fields through
 * c->grid (contact and traction also keep per-node state of level 0: the walls' axes, the held
 * velocities, a wall given to the gas). */
static int carried(const mpm_coupling_type *t) {
  return strcmp(t->name, "velocity") == 0;
}

int mpm_coupling_set_hier(mpm_coupling *c, const mpm_config *cfg, const mpm_hier *h) {
  if (!c || !h || h->nlevels < 2) return 0;
  if (!carried(c->type))
    return mpm_config_fail(cfg, "coupling.scheme",
                           "coupling.scheme = %s is not carried to the refined levels "
                           "(refine.levels > 1): it keeps per-node state of level 0; use "
                           "coupling.scheme = velocity or set refine.levels = 1 "
                           "(docs/refinement.md)",
                           c->type->name);
  if (c->nbodies > 0)
    return mpm_config_fail(cfg, "refine.levels",
                           "the solid has %d bodies, whose forces coupling.csv reports one by one "
                           "from level 0's nodes, which refinement does not carry; keep one "
                           "[solid.NAME] body or set refine.levels = 1 (docs/refinement.md)",
                           c->nbodies);
  c->nlev = h->nlevels;
  c->lev_grid[0] = c->grid, c->lev_owned[0] = c->owned;
  for (int l = 1; l < h->nlevels; ++l) {
    const mpm_hier_level *lv = &h->level[l];
    const mpm_lidx nn = lv->grid->nnodes;
    c->lev_grid[l] = lv->grid;
    MPM_ALLOC(c->lev_owned[l], nn);
    for (mpm_lidx n = 0; n < nn; ++n)
      c->lev_owned[l][n] = lv->active[n] && !(lv->is_image && lv->is_image[n]);
  }
  return 0;
}

int mpm_coupling_each_level(mpm_coupling *c, mpm_coupling_level_fn fn, double t, double h,
                            mpm_pass pass) {
  if (c->nlev == 0) return fn(c, t, h, pass);
  int rc = 0;
  for (int l = 0; l < c->nlev && !rc; ++l) {
    c->grid = c->lev_grid[l], c->owned = c->lev_owned[l];
    rc = fn(c, t, h, pass);
  }
  c->grid = c->lev_grid[0], c->owned = c->lev_owned[0];
  return rc;
}
