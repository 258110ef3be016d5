/* Which nodes of a finer level the prolongation fills (mpm_hier_level.near): the active nodes,
 * the inactive ones near the region, and the images of either. The others, which no deposit
 * reaches and no particle reads, keep what they held. For the refinement tests. */
#ifndef HIER_NEAR_H
#define HIER_NEAR_H

#include "mpm_hier.h"

static inline int hier_near_listed(const mpm_hier_level *lv, mpm_lidx n) {
  mpm_lidx a = 0, b = lv->nnear; /* near is in box order: bisect */
  while (a < b) {
    const mpm_lidx m = a + (b - a) / 2;
    if (lv->near[m] < n)
      a = m + 1;
    else
      b = m;
  }
  return a < lv->nnear && lv->near[a] == n;
}

/* Does the prolongation fill node n of level l >= 1? */
static inline int hier_node_filled(const mpm_hier *h, int l, mpm_lidx n) {
  const mpm_hier_level *lv = &h->level[l];
  for (mpm_lidx q = 0; lv->is_image && lv->is_image[n] && q < lv->nimage; ++q)
    if (lv->image[q] == n) n = lv->canon[q];
  return lv->active[n] || hier_near_listed(lv, n);
}

#endif
