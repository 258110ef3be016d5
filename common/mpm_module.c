/* Module helpers shared by every module: destruction, the nodal update, particle checks. */
#include "mpm_module.h"

#include "mpm_error.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

void mpm_module_destroy(mpm_module **m) {
  if (!m || !*m) return;
  if ((*m)->ops && (*m)->ops->destroy) (*m)->ops->destroy(*m);
  free(*m);
  *m = NULL;
}

int mpm_grid_phase_update(mpm_grid *grid, int phase, double h) {
  mpm_grid_phase *ph = &grid->phase[phase];
  const int dim = grid->dim;
  double local = 0.0, mmax;
  for (mpm_lidx l = 0; l < grid->nnodes; ++l) local = fmax(local, ph->m_i[l]);
  MPM_CALL_MPI(MPI_Allreduce(&local, &mmax, 1, MPI_DOUBLE, MPI_MAX, grid->comm));
  /* Nodes touched only by the far tail of a stencil carry roundoff-sized mass; dividing by it
   * would amplify noise, so they are treated as empty. */
  const double mmin = 1e-14 * mmax;
  for (mpm_lidx l = 0; l < grid->nnodes; ++l) {
    const double m = ph->m_i[l];
    for (int d = 0; d < dim; ++d) {
      if (m > mmin) {
        const double a = ph->f_i[d][l] / m;
        ph->a_i[d][l] = a;
        ph->v_i[d][l] = ph->mv_i[d][l] / m + h * a;
      } else {
        ph->a_i[d][l] = ph->v_i[d][l] = 0.0;
      }
    }
  }
  return 0;
}

int mpm_fault_at(mpm_fault *fault, const mpm_particles *p, const double *y, mpm_lidx i,
                 const char *fmt, ...) {
  va_list ap;
  fault->set = 1;
  fault->id = p->id[i];
  for (int d = 0; d < p->dim; ++d) fault->x[d] = y[(size_t)d * p->n + i];
  va_start(ap, fmt);
  vsnprintf(fault->cause, sizeof fault->cause, fmt, ap);
  va_end(ap);
  return 1;
}

int mpm_module_check_positions(const mpm_module *m, const double *y, mpm_fault *fault) {
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const mpm_lidx n = p->n;
  for (size_t k = 0; k < (size_t)p->nstate * (size_t)n; ++k)
    if (!isfinite(y[k]))
      return mpm_fault_at(fault, p, y, (mpm_lidx)(k % (size_t)(n ? n : 1)),
                          "a state value is not finite (NaN or Inf)");
  /* Beyond a periodic face a particle is fine until migration wraps it; only the drift
   * check (cells as doubles: a far particle's cell may not fit an int) limits it there. */
  for (mpm_lidx i = 0; i < n; ++i)
    for (int d = 0; d < p->dim; ++d) {
      const double x = y[(size_t)d * n + i];
      if (!g->periodic[d] && !(x >= g->lo[d] && x < g->hi[d]))
        return mpm_fault_at(fault, p, y, i, "the particle left the domain");
      const double cell = floor((x - g->lo[d]) / g->dx);
      const int c = g->coord[d];
      if (cell < g->cell_split[d][c] - 1 || cell > g->cell_split[d][c + 1])
        return mpm_fault_at(fault, p, y, i,
                            "the particle moved more than one cell within one step");
    }
  return 0;
}
