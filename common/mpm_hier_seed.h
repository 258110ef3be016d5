/* Seeding the finer levels of a refinement hierarchy (mpm_hier.h), shared by the modules that
 * run on one (the gas, fluid/fluid_seed.c; the solid, solid/solid_refine.c): a region's points
 * on a level's particle lattice, and the level-0 particles a finer region replaces.
 *
 * The lattice of level l holds ppc points per axis in every level-l span, at
 * o_l + (i - 1/2 + (q + 1/2) / ppc) h_l. For an even ppc no point of level 0's lattice
 * (mpm_region_seed) lies on a span face, so a region's level-0 particles leave no part of a
 * level-0 span behind when they are dropped. */
#ifndef MPM_HIER_SEED_H
#define MPM_HIER_SEED_H

#include "mpm_geometry.h"
#include "mpm_hier.h"
#include "mpm_particles.h"

/* The points of level l's lattice (ppc per axis and span) that lie strictly inside the domain,
 * inside region r and on level l (mpm_hier_level_of), into *x (component-major, malloc'd, the
 * caller frees) and their number into *n; the number of lattice points generated, kept or not,
 * into *span (a block of ids as wide, like mpm_region_seed_span). */
int mpm_hier_lattice(const mpm_hier *h, int l, int ppc, const mpm_region *r, double **x,
                     mpm_lidx *n, mpm_gidx *span);

/* Keep the points of x (n, component-major) and their ids that this rank of g owns, in order;
 * returns their number. Every rank generates a finer level's whole lattice (mpm_hier_lattice)
 * and numbers it, so that a point's id does not depend on the ranks. */
mpm_lidx mpm_hier_keep_owned(const mpm_grid *g, double *x, mpm_gidx *id, mpm_lidx n);

/* Drop the particles of p whose position (field field_x) lies on a level above 0. */
int mpm_hier_drop_refined(const mpm_hier *h, mpm_particles *p, int field_x);

#endif
