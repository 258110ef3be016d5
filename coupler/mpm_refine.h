/* The [refine] section: a refinement hierarchy over the shared grid (mpm_hier.h), given by
 * boxes in the case file or by a criterion, for a gas-only case on one rank, or by boxes for a
 * solid, alone or beside a gas (docs/refinement.md):
 *   [refine]              levels = 2 (1: off, the default), buffer = 2
 *                         criterion = density, threshold = 0.05, every = 10, dilate = 2
 *                         (or a list: criterion = compression, starvation, threshold = 0.003,
 *                         min_particles = 2: the union of their flags)
 *   [refine.NAME]         level = 1, lo = x y, hi = x y (static boxes, without a criterion)
 * The sim builds it after the modules and hands it to the gas (fluid_module_refine) and the solid
 * (solid_module_refine), which then deposit, solve and gather on every level
 * (coupler/mpm_cycle.c); the coupling scheme then acts on every level (mpm_coupling_set_hier). */
#ifndef MPM_REFINE_H
#define MPM_REFINE_H

#include "mpm_config.h"
#include "mpm_hier.h"
#include "mpm_module.h"

extern const mpm_key_spec mpm_refine_keys[];
extern const int mpm_refine_nkeys;

/* Build the hierarchy the case asks for over grid (*h = NULL with refine.levels = 1) and put
 * the modules on it; with seed = 1 the gas reseeds the finer regions. Every setting this slice
 * does not carry is refused with one line naming its key (MPM_ERR_INPUT). Collective. */
int mpm_refine_build(mpm_hier **h, const mpm_config *cfg, mpm_grid *grid, mpm_module **mod,
                     int nmod, int seed);

/* Dynamic refinement (refine.criterion): is it on? */
int mpm_refine_dynamic(const mpm_config *cfg);

/* Between steps of a dynamic refinement: every refine.every steps (or now, with force) rebuild
 * *h from the gas's flags and move the modules onto it (*h may become NULL: nothing flagged);
 * *changed says a regrid ran (the integrator must then restart its RHS). The particles are not
 * touched: mpm_refine_follow moves them onto the new levels. */
int mpm_refine_regrid(mpm_hier **h, const mpm_config *cfg, mpm_grid *grid, mpm_module **mod,
                      int nmod, long step, int force, int *changed);

/* After a regrid: split and merge the gas's particles onto the levels of the hierarchy the
 * modules now hold (fluid_relevel.c), as after a step; *changed (this rank's) says the set
 * changed. Collective. */
int mpm_refine_follow(mpm_module **mod, int nmod, int *changed);

#endif
