/* The level lookup (mpm_hier.leaf), from every first guess, against the walk down the masks
 * (mpm_hier_level_walk), at a
 * point and at the point moved onto the nearest level-0 span face along each axis in turn and
 * just beside it (0, +-1e-12, +-1e-7, +-3e-6 of a level-0 cell: within and beyond the lookup's
 * margin), where the two could part by roundoff. Include after cmocka.h. */
#ifndef HIER_LEVEL_CHECK_H
#define HIER_LEVEL_CHECK_H

#include "mpm_hier.h"

#include <math.h>
#include <string.h>

/* The lookup from every first guess (mpm_hier_level_from: each level, and none) at y. */
static inline void hier_check_level_at(const mpm_hier *h, const double *y) {
  const int walk = mpm_hier_level_walk(h, y);
  for (int hint = -1; hint <= h->nlevels; ++hint)
    assert_int_equal(mpm_hier_level_from(h, y, hint), walk);
}

static inline void hier_check_level(const mpm_hier *h, const double *x) {
  static const double off[] = {0.0, 1e-12, -1e-12, 1e-7, -1e-7, 3e-6, -3e-6};
  const mpm_grid *g = h->level[0].grid;
  hier_check_level_at(h, x);
  for (int d = 0; d < h->dim; ++d) {
    const double face = g->lo[d] + (floor((x[d] - g->lo[d]) / g->dx - 0.5) + 0.5) * g->dx;
    for (size_t k = 0; k < sizeof off / sizeof off[0]; ++k) {
      double y[MPM_MAX_DIM] = {0, 0, 0};
      memcpy(y, x, sizeof(double) * (size_t)h->dim);
      y[d] = face + off[k] * g->dx;
      hier_check_level_at(h, y);
    }
  }
}

#endif
