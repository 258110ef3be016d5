/* Scene rules that span the modules: no two bodies share space.
 *
 * The bodies are the [solid.NAME] sections and the gas (its [gas.NAME] sections together: where
 * gas regions overlap the first one in the file seeds, so they never overlap one another).
 * Static obstacles are kept apart elsewhere: the gas is not seeded in them, and a solid in one
 * is refused by the coupling (check_reserved). */
#ifndef MPM_SCENE_H
#define MPM_SCENE_H

#include "mpm_config.h"
#include "mpm_grid.h"
#include "mpm_module.h"

/* After seeding: no particle seeded for one body lies inside the region of another (inside by
 * more than a millionth of a cell along every axis, so bodies whose boundaries meet may touch).
 * Such a point would carry the mass of both. The offender is the particle with the smallest id
 * in the first module that has one, so the message names the same bodies and point on any
 * number of ranks: one line naming both sections (the first at its geometry key, the second
 * with its file and line), the point, and what to do; MPM_ERR_INPUT on every rank.
 * Collective. */
int mpm_scene_check_overlaps(const mpm_config *cfg, const mpm_grid *grid, mpm_module **mods,
                             int nmod);

#endif
