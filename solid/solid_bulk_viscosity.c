/* The solids' bulk viscosity (solid_bulk_viscosity.h): its stress, batched over a body. */
#include "solid_bulk_viscosity.h"

#include <stddef.h>

void solid_bulkq_add(const solid_bulkq *q, int dim, mpm_lidx n, mpm_lidx count, const mpm_lidx *idx,
                     const double *m, const double *divv, double *vsig) {
  for (mpm_lidx k = 0; k < count; ++k) {
    const mpm_lidx i = idx[k];
    if (!(divv[i] < 0.0)) continue;
    const double vq = solid_bulkq_vq(q, m[i], divv[i]);
    for (int d = 0; d < dim; ++d) vsig[(size_t)(d * dim + d) * (size_t)n + (size_t)i] -= vq;
  }
}
