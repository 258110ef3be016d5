/* Geometry for seeding particles (and later for obstacles and clamps): named regions from
 * the case file, each an inside test, and lattice seeding of particles inside a region.
 *
 * Region types: box (lo, hi), disk (2-D; center, radius), sphere (3-D; center, radius),
 * cylinder (3-D; p0, p1 axis ends, radius), polygon (2-D; a CSV/whitespace file of x y
 * vertices, closed implicitly; in 3-D extruded between lo[2] and hi[2] given by `z`),
 * union (of = a b ...), difference (of = a b ...: a minus the others). */
#ifndef MPM_GEOMETRY_H
#define MPM_GEOMETRY_H

#include "mpm_config.h"
#include "mpm_grid.h"
#include "mpm_types.h"

typedef struct mpm_region mpm_region;

/* Keys of [geometry.NAME] sections. */
extern const mpm_key_spec mpm_geometry_keys[];
extern const int mpm_geometry_nkeys;

/* Build region NAME from cfg (recursively for union/difference; a cycle or an unknown
 * name is an input error naming the key). */
int mpm_region_from_config(mpm_region **r, const mpm_config *cfg, int dim, const char *name);
void mpm_region_destroy(mpm_region **r);

/* The checks every polygon outline of the case passes, with one message each naming key:
 * at least 3 vertices, an outline that does not cross itself (inside tests and signed
 * distances would be wrong), a non-zero area. xy holds nv (x, y) pairs without a repeated
 * closing vertex. Shared by [geometry] polygons and the gas's polygon obstacles. */
int mpm_polygon_check(const mpm_config *cfg, const char *key, const double *xy, int nv);

/* 1 if x is inside (the boundary counts as inside). */
int mpm_region_contains(const mpm_region *r, const double *x);
/* Axis-aligned bounding box. */
void mpm_region_bounds(const mpm_region *r, double *lo, double *hi);
/* The region's volume (area in 2-D) by the midpoint rule on a lattice of spacing about h over
 * its bounding box, the spacing widened until the lattice holds at most max_points points: to
 * within about h times the surface's measure. Each rank computes the same value. */
double mpm_region_volume(const mpm_region *r, double h, double max_points);

/* Seed ppc particles per cell per direction at the cell-centred sub-lattice, in every cell
 * that this rank owns on grid, keeping the points inside r. For each point it gives the
 * position (component-major: x[d*cap + i]), and a global id that depends only on the
 * point's place in the global lattice (so the same particle has the same id on any number
 * of ranks): id = id_base + lattice index. *n is the count; arrays are malloc'ed.
 * Each particle's volume is (dx/ppc)^dim. */
int mpm_region_seed(const mpm_region *r, const mpm_grid *grid, int ppc, mpm_gidx id_base,
                    mpm_lidx *n, double **x, mpm_gidx **id);

/* Number of lattice points per body: ids of a body lie in [id_base, id_base + span). */
mpm_gidx mpm_region_seed_span(const mpm_grid *grid, int ppc);

#endif
