/* Virtual gas particles (see fluid_virtual.h). */
#include "fluid_virtual.h"

#include "mpm_error.h"
#include "mpm_kernels.h"

#include <stdlib.h>
#include <string.h>

int fluid_virtual_add(fluid_virtual *v, int dim, const double *x, double V, double p) {
  if (v->n == v->cap) {
    const mpm_lidx cap = v->cap ? 2 * v->cap : 1024;
    double *nx = realloc(v->x, sizeof *nx * 3 * (size_t)cap);
    if (nx) v->x = nx;
    double *nvp = realloc(v->Vp, sizeof *nvp * (size_t)cap);
    if (nvp) v->Vp = nvp;
    if (!nx || !nvp) MPM_FAIL(MPM_ERR_MEMORY, "cannot grow the virtual gas particles");
    v->cap = cap;
  }
  for (int d = 0; d < 3; ++d) v->x[3 * (size_t)v->n + d] = d < dim ? x[d] : 0.0;
  v->Vp[v->n++] = V * p;
  return 0;
}

int fluid_virtual_init(fluid_virtual *v, mpm_grid *grid) {
  if (v->phase >= 0) return 0;
  return mpm_grid_add_phase(grid, "fluid_virtual", &v->phase);
}

int fluid_virtual_deposit(fluid_virtual *v, mpm_grid *grid, double lp) {
  const int dim = grid->dim;
  const mpm_lidx n = v->n;
  if (v->phase < 0) return 0;
  if (n > v->work_cap || !v->work) {
    free(v->work);
    v->work_cap = n + n / 4 + 64;
    MPM_ALLOC(v->work, (size_t)(dim + dim * dim + 2) * v->work_cap);
  }
  double *x = v->work, *vsig = x + (size_t)dim * n, *zero = vsig + (size_t)dim * dim * n;
  memset(vsig, 0, sizeof *vsig * (size_t)(dim * dim + 2) * (size_t)n);
  for (mpm_lidx q = 0; q < n; ++q) {
    for (int d = 0; d < dim; ++d) {
      x[(size_t)d * n + q] = v->x[3 * (size_t)q + d];
      vsig[(size_t)(d * dim + d) * n + q] = -v->Vp[q];
    }
  }
  mpm_grid_phase_zero(grid, v->phase);
  mpm_p2g_args a = {.n = n, .m = zero, .vsig = vsig, .lp = lp};
  for (int d = 0; d < dim; ++d) a.x[d] = x + (size_t)d * n, a.v[d] = zero + n;
  mpm_kernels_get(dim)->p2g(grid, v->phase, &a);
  return 0;
}

int fluid_virtual_forces(fluid_virtual *v, mpm_grid *grid, int gas_phase, const mpm_lidx *skip,
                         mpm_lidx nskip) {
  if (v->phase < 0) return 0;
  mpm_grid_phase *ph = &grid->phase[gas_phase], *vp = &grid->phase[v->phase];
  MPM_CALL(mpm_grid_halo_reverse(grid, vp->f_i, grid->dim));
  for (mpm_lidx k = 0; k < nskip; ++k)
    for (int d = 0; d < grid->dim; ++d) vp->f_i[d][skip[k]] = 0.0;
  for (int d = 0; d < grid->dim; ++d)
    for (mpm_lidx l = 0; l < grid->nnodes; ++l) ph->f_i[d][l] += vp->f_i[d][l];
  return 0;
}

void fluid_virtual_free(fluid_virtual *v) {
  free(v->x), free(v->Vp), free(v->work);
  memset(v, 0, sizeof *v);
  v->phase = -1;
}
