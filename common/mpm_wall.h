/* A moving wall that one module is given in another module's place: the interface of a coupling
 * scheme as the gas's least-squares wall treatment sees it (fluid/fluid_wall_ls.h). The coupler
 * fills the function table from the solid (coupler/mpm_solid_wall.h); the module that takes it
 * knows a wall, not a solid, so the modules stay unaware of each other.
 *
 * Calls, all within one G2P of the module that holds the wall (the classic update):
 *   prepare   collective, first: bring the wall up to the nodal solve just made and flag the
 *             cells near it;
 *   at        per particle, any number: where the wall is and how it moves;
 *   impulse   per particle the module changed next to the wall: what the wall gave it;
 *   finish    collective, last: the wall takes the reactions of the impulses, before the
 *             partner module's G2P reads its nodes. */
#ifndef MPM_WALL_H
#define MPM_WALL_H

#include "mpm_types.h"

typedef struct mpm_wall_source {
  void *ctx;
  /* Flag the cells of this rank's box (by their lower corner node, box index) that hold points
   * within reach (m) of the wall: 1, or 2 where `at` may find the wall within range (m) of such
   * a point (elsewhere it finds none); and give the wall's bounding box [lo, hi] (dim values, m;
   * the same on every rank; lo > hi if there is no wall); h is the step. Collective. */
  int (*prepare)(void *ctx, double h, double reach, double range, unsigned char *cells, double *lo,
                 double *hi);
  /* At x: 1, with the signed distance phi (m; > 0 outside the wall's body), the unit outward
   * normal n and the wall's velocity v, if a wall surface lies within range (m) of x; else 0. */
  int (*at)(void *ctx, const double *x, double range, double *phi, double *n, double *v);
  /* The module gave the particle at x the momentum J (N s, the impulse of the wall on it): the
   * wall takes -J. Returns the work the wall did (J), which the module's energy gains: J times
   * the wall's velocity over the step as the wall's own energy balance counts it. */
  double (*impulse)(void *ctx, const double *x, const double *J);
  /* The impulses are complete on every rank. Collective. */
  int (*finish)(void *ctx);
} mpm_wall_source;

#endif
