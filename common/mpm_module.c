/* Module helpers shared by every module: destruction, the nodal update, particle checks. */
#include "mpm_module.h"

#include "mpm_error.h"

#include <float.h>
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

/* v = mv/m + h a, a = f/m on the nodes of one velocity component (zero where m <= mmin).
 * Both branches are formed and one is selected, so the loop has no unpredictable jump. */
static void node_update(mpm_lidx nn, const double *restrict m, const double *restrict mv,
                        const double *restrict f, double *restrict v, double *restrict a,
                        double mmin, double h) {
  for (mpm_lidx l = 0; l < nn; ++l) {
    const int full = m[l] > mmin;
    const double q = full ? m[l] : 1.0, al = f[l] / q, vl = mv[l] / q + h * al;
    a[l] = full ? al : 0.0;
    v[l] = full ? vl : 0.0;
  }
}

/* Mass over scale and number of the owned nodes with m_i > mmin, into sum[0] and sum[1]: the
 * owned block of the box row by row (in index order, as a loop over the box would add them). */
static void owned_mass(const mpm_grid *g, const mpm_grid_phase *ph, double mmin, double scale,
                       double *sum) {
  const double *m = ph->m_i;
  int lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  mpm_lidx stride[3] = {1, 0, 0};
  for (int d = 0; d < g->dim; ++d) { /* (outside the phase's span it holds no mass) */
    lo[d] = g->own_lo[d] - g->box_lo[d], hi[d] = g->own_hi[d] - g->box_lo[d];
    if (mpm_phase_lo(g, ph, d) > lo[d]) lo[d] = mpm_phase_lo(g, ph, d);
    if (mpm_phase_hi(g, ph, d) < hi[d]) hi[d] = mpm_phase_hi(g, ph, d);
    if (d > 0) stride[d] = stride[d - 1] * g->box_n[d - 1];
  }
  for (int k = lo[2]; k < hi[2]; ++k)
    for (int j = lo[1]; j < hi[1]; ++j) {
      const double *row = m + k * stride[2] + j * stride[1];
      for (int i = lo[0]; i < hi[0]; ++i)
        if (row[i] > mmin) sum[0] += row[i] / scale, sum[1] += 1.0;
    }
}

/* Largest nodal mass of a phase over ngrids grids, reduced over grids[0]'s communicator. */
static int largest_mass(mpm_grid *const *grids, int ngrids, int phase, double *mmax) {
  double local = 0.0;
  for (int k = 0; k < ngrids; ++k) {
    const mpm_grid_phase *ph = &grids[k]->phase[phase];
    const double *m = ph->m_i;
    MPM_PHASE_FOR(grids[k], ph, l) { /* fmax without the call (NaN is skipped) */
      if (m[l] > local) local = m[l];
    }
  }
  MPM_CALL_MPI(MPI_Allreduce(&local, mmax, 1, MPI_DOUBLE, MPI_MAX, grids[0]->comm));
  return 0;
}

/* A node's volume on grid k over one on grids[0] (1 for grids[0] itself). */
static double node_scale(mpm_grid *const *grids, int k) {
  return k == 0 ? 1.0 : pow(grids[k]->dx / grids[0]->dx, grids[0]->dim);
}

/* Mean mass of the owned nodes heavier than mmin over ngrids grids (0 if none), each counted at
 * grids[0]'s spacing (node_scale). */
static int mean_mass(mpm_grid *const *grids, int ngrids, int phase, double mmin, double *mean) {
  double sum[2] = {0.0, 0.0}, all[2]; /* mass and count over the owned nodes with mass */
  /* The finer levels of a hierarchy (box grids, no communicator) are alike on every rank:
   * counted on rank 0 alone. */
  for (int k = 0; k < ngrids; ++k)
    if (k == 0 || grids[0]->rank == 0)
      owned_mass(grids[k], &grids[k]->phase[phase], mmin, node_scale(grids, k), sum);
  MPM_CALL_MPI(MPI_Allreduce(sum, all, 2, MPI_DOUBLE, MPI_SUM, grids[0]->comm));
  *mean = all[1] > 0.0 ? all[0] / all[1] : 0.0;
  return 0;
}

int mpm_grid_phase_update_many(mpm_grid *const *grids, int ngrids, int phase, double h) {
  const mpm_grid_phase *ph0 = &grids[0]->phase[phase];
  double mmax, mean = 0.0;
  MPM_CALL(largest_mass(grids, ngrids, phase, &mmax));
  /* Nodes touched only by the far tail of a stencil carry roundoff-sized mass; dividing by it
   * would amplify noise, so they are treated as empty (a module may raise the fraction). */
  const double mempty = ph0->empty_fraction * mmax;
  if (ph0->light_fraction > 0.0) MPM_CALL(mean_mass(grids, ngrids, phase, mempty, &mean));
  for (int k = 0; k < ngrids; ++k) {
    mpm_grid *g = grids[k];
    mpm_grid_phase *ph = &g->phase[phase];
    double mmin = mempty;
    if (ph0->light_fraction > 0.0) {
      ph->m_mean = mean * node_scale(grids, k);
      mmin = fmax(mmin, ph0->light_fraction * ph->m_mean);
    }
    ph->m_max = mmax, ph->m_empty = mmin;
    if (!ph->narrowed) {
      for (int d = 0; d < g->dim; ++d)
        node_update(g->nnodes, ph->m_i, ph->mv_i[d], ph->f_i[d], ph->v_i[d], ph->a_i[d], mmin, h);
      continue;
    }
    const mpm_lidx n = ph->act_hi[0] - ph->act_lo[0];
    for (int kz = mpm_phase_lo(g, ph, 2); n > 0 && kz < mpm_phase_hi(g, ph, 2); ++kz)
      for (int j = mpm_phase_lo(g, ph, 1); j < mpm_phase_hi(g, ph, 1); ++j) {
        const mpm_lidx r = mpm_phase_row(g, ph, j, kz);
        for (int d = 0; d < g->dim; ++d)
          node_update(n, ph->m_i + r, ph->mv_i[d] + r, ph->f_i[d] + r, ph->v_i[d] + r,
                      ph->a_i[d] + r, mmin, h);
      }
  }
  return 0;
}

int mpm_grid_phase_update(mpm_grid *grid, int phase, double h) {
  return mpm_grid_phase_update_many(&grid, 1, phase, h);
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
  fault->advice[0] = '\0';
  return 1;
}

/* Particle i lies beyond face (d, side): the cause and what to change. A solid particle there
 * has been carried to the edge of the domain, which no body may leave, and a smaller step does
 * not bring it back (at Mach 50 the flow tore the main job's bar from its clamp and swept it
 * onto the outflow face). A gas particle beyond an open face by more than the cell it may cross
 * moved too far in one step; beyond a wall it went through the wall. */
static int fault_beyond(const mpm_module *m, const double *y, mpm_lidx i, int d, int side,
                        mpm_fault *fault) {
  const char face[] = {"xyz"[d], '_', side ? 'h' : 'l', side ? 'i' : 'o', '\0'};
  if (m->role == MPM_ROLE_SOLID) {
    mpm_fault_at(fault, m->particles, y, i,
                 "the solid particle reached the domain's face boundary.%s, which no body may "
                 "cross: the body moved, or the flow or the load tore or carried it, out of the "
                 "domain",
                 face);
    snprintf(fault->advice, sizeof fault->advice,
             "A smaller step does not help: make the body stiffer or hold it better (clamp.*), "
             "ease the load or the flow, or extend the domain beyond boundary.%s",
             face);
  } else if (m->open[d][side]) {
    mpm_fault_at(
        fault, m->particles, y, i,
        "the gas particle crossed the open face boundary.%s by more than a cell within one step",
        face);
    snprintf(fault->advice, sizeof fault->advice,
             "The step is too long for the flow's speed there: lower time.cfl or time.dt_max");
  } else {
    mpm_fault_at(fault, m->particles, y, i, "the particle went through the wall boundary.%s", face);
  }
  return 1;
}

int mpm_module_check_positions(const mpm_module *m, const double *y, mpm_fault *fault) {
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const mpm_lidx n = p->n;
  /* One pass without jumps (|y| <= DBL_MAX is false for NaN and Inf alike); the culprit is
   * found only when there is one. */
  const size_t total = (size_t)p->nstate * (size_t)n;
  int nonfinite = 0;
  for (size_t k = 0; k < total; ++k) nonfinite |= !(fabs(y[k]) <= DBL_MAX);
  for (size_t k = 0; nonfinite && k < total; ++k)
    if (!isfinite(y[k]))
      return mpm_fault_at(fault, p, y, (mpm_lidx)(k % (size_t)(n ? n : 1)),
                          "a state value is not finite (NaN or Inf)");
  /* Beyond a periodic face a particle is fine until migration wraps it; only the drift
   * check (cells as doubles: a far particle's cell may not fit an int) limits it there. */
  for (int d = 0; d < p->dim; ++d) {
    const double *x = y + (size_t)d * n;
    const double lo = g->lo[d] - (m->open[d][0] ? 1.0 : m->wall_slack) * g->dx;
    const double hi = g->hi[d] + (m->open[d][1] ? 1.0 : m->wall_slack) * g->dx;
    /* The rank's cells, widened by the one cell a particle may cross in a step. */
    const int c = g->coord[d];
    const double near_lo = g->lo[d] + (g->cell_split[d][c] - 1) * g->dx;
    const double near_hi = g->lo[d] + (g->cell_split[d][c + 1] + 1) * g->dx;
    /* One pass without jumps, as above; a periodic axis has no domain bounds to check. */
    const double lo_b = g->periodic[d] ? near_lo : fmax(lo, near_lo);
    const double hi_b = g->periodic[d] ? near_hi : fmin(hi, near_hi);
    int bad = 0;
    for (mpm_lidx i = 0; i < n; ++i) bad |= !(x[i] >= lo_b && x[i] < hi_b);
    for (mpm_lidx i = 0; bad && i < n; ++i) {
      if (!g->periodic[d] && !(x[i] >= lo && x[i] < hi))
        return fault_beyond(m, y, i, d, !(x[i] < lo), fault);
      if (!(x[i] >= near_lo && x[i] < near_hi))
        return mpm_fault_at(fault, p, y, i,
                            "the particle moved more than one cell within one step");
    }
  }
  return 0;
}
