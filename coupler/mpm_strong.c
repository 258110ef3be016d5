/* Strong coupling of the serial staggered scheme (see mpm_strong.h). */
#include "mpm_strong.h"

#include "mpm_error.h"
#include "mpm_log.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Steps that miss the tolerance are named up to this many times; later ones are only counted. */
#define MPM_STRONG_WARNINGS 5

struct mpm_strong {
  mpm_partitioned *pp;
  int iterations;
  double tolerance, relaxation;
  /* Nodal arrays, dim x nnodes: the trial load rate, the impulse owed after the solid's advance,
   * the residual of the iteration before, the gas's load rate. */
  double *q[MPM_MAX_DIM], *after_solid[MPM_MAX_DIM], *r_prev[MPM_MAX_DIM], *g[MPM_MAX_DIM];
  double *q_best[MPM_MAX_DIM]; /* the trial load with the smallest residual so far */
  /* The modules' particle data and the owed impulse at the start of the step. */
  double *mark[2], *owed0[MPM_MAX_DIM];
  size_t mark_cap[2];
  mpm_lidx mark_n[2];       /* the particle counts at the mark */
  const double *mark_at[2]; /* and their storage: a rewind needs the same set */
  long moved;               /* steps whose particle set changed under a retried substep */
  /* The run's figures. */
  long steps, iters, unconverged;
  int most;
  double worst; /* the largest relative residual a step was accepted with */
};

int mpm_strong_new(mpm_strong **sp, mpm_partitioned *pp, int iterations, double tolerance,
                   double relaxation) {
  mpm_strong *s;
  MPM_ALLOC(s, 1);
  *sp = s;
  s->pp = pp, s->iterations = iterations, s->tolerance = tolerance, s->relaxation = relaxation;
  const mpm_grid *grid = pp->ifc->grid;
  const size_t nn = (size_t)grid->nnodes;
  for (int d = 0; d < grid->dim; ++d) {
    MPM_ALLOC(s->q[d], nn);
    MPM_ALLOC(s->after_solid[d], nn);
    MPM_ALLOC(s->r_prev[d], nn);
    MPM_ALLOC(s->g[d], nn);
    MPM_ALLOC(s->q_best[d], nn);
    MPM_ALLOC(s->owed0[d], nn);
  }
  /* The predictor lives in the interface's `prev`, which checkpoints carry. */
  return mpm_interface_want_trend(pp->ifc);
}

void mpm_strong_destroy(mpm_strong **sp) {
  if (!sp || !*sp) return;
  mpm_strong *s = *sp;
  if (s->steps > 0)
    mpm_log(MPM_LOG_INFO,
            "strong coupling: %ld coupling steps, %.2f sub-iterations a step on average, at most "
            "%d; %ld steps missed coupling.tolerance = %g (largest residual accepted %.3g); %ld "
            "could not go back to their start",
            s->steps, (double)s->iters / (double)s->steps, s->most, s->unconverged, s->tolerance,
            s->worst, s->moved);
  for (int d = 0; d < MPM_MAX_DIM; ++d) {
    free(s->q[d]), free(s->after_solid[d]), free(s->r_prev[d]), free(s->g[d]);
    free(s->owed0[d]), free(s->q_best[d]);
  }
  free(s->mark[0]), free(s->mark[1]);
  free(s);
  *sp = NULL;
}

/* Keep (save) or put back the data of a module's particles. The particle set does not change
 * within a coupling step of one substep per module: the step loop's open faces and migration
 * run between coupling steps. */
static int keep_particles(mpm_strong *s, int k, mpm_particles *p, int save) {
  const size_t count = (size_t)p->ncomp * (size_t)p->n;
  if (save && count > s->mark_cap[k]) {
    free(s->mark[k]);
    s->mark[k] = NULL, s->mark_cap[k] = 0;
    MPM_ALLOC(s->mark[k], count);
    s->mark_cap[k] = count;
  }
  if (save) s->mark_n[k] = p->n, s->mark_at[k] = p->data;
  if (count > 0)
    memcpy(save ? s->mark[k] : p->data, save ? p->data : s->mark[k], sizeof(double) * count);
  return 0;
}

/* Can the step go back to its mark? Not if a retried substep let the step loop's open faces or
 * migration change a particle set (its count or storage) since. Collective. */
static int can_rewind(mpm_strong *s, const mpm_grid *grid) {
  const mpm_particles *p[2] = {s->pp->solid->particles, s->pp->gas->particles};
  int same = 1;
  for (int k = 0; k < 2; ++k) same &= p[k]->n == s->mark_n[k] && p[k]->data == s->mark_at[k];
  MPI_Allreduce(MPI_IN_PLACE, &same, 1, MPI_INT, MPI_LAND, grid->comm);
  return same;
}

static void copy_nodal(const mpm_grid *grid, double *const *to, double *const *from) {
  for (int d = 0; d < grid->dim; ++d) memcpy(to[d], from[d], sizeof(double) * (size_t)grid->nnodes);
}

static int keep_state(mpm_strong *s, int save) {
  mpm_partitioned *pp = s->pp;
  MPM_CALL(keep_particles(s, 0, pp->solid->particles, save));
  MPM_CALL(keep_particles(s, 1, pp->gas->particles, save));
  if (save)
    copy_nodal(pp->ifc->grid, s->owed0, pp->ifc->impulse);
  else
    copy_nodal(pp->ifc->grid, pp->ifc->impulse, s->owed0);
  return 0;
}

/* Sums over the owned nodes of a.b, reduced over the ranks: dots[j] for the pairs (a[j], b[j]). */
static int dots(const mpm_timescheme *ts, int npair, double *const *const *a,
                double *const *const *b, double *out) {
  const mpm_grid *grid = ts->grid;
  const unsigned char *owned = ts->coupling->owned;
  for (int j = 0; j < npair; ++j) {
    double sum = 0.0;
    for (int d = 0; d < grid->dim; ++d)
      for (mpm_lidx l = 0; l < grid->nnodes; ++l)
        if (owned[l]) sum += a[j][d][l] * b[j][d][l];
    out[j] = sum;
  }
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, out, npair, MPI_DOUBLE, MPI_SUM, grid->comm));
  return 0;
}

/* One sub-iteration from t0 under the trial load rate q (first: the modules are at t0 already,
 * else they go back there): the gas's load rate g, the residual r = g - q (in after_solid) and
 * its size relative to g. */
static int pass(mpm_strong *s, mpm_timescheme *ts, double t0, double t1, int first,
                const double *const *q, double *rel) {
  mpm_partitioned *pp = s->pp;
  mpm_interface *ifc = pp->ifc;
  const int dim = ts->grid->dim;
  const mpm_lidx nn = ts->grid->nnodes;
  const size_t bytes = sizeof(double) * (size_t)nn;
  const double H = t1 - t0;
  if (!first) {
    MPM_CALL(keep_state(s, 0));
    memset(&pp->sum, 0, sizeof pp->sum);
    MPM_CALL(mpm_integrator_start(pp->it_solid, t0, 0.0));
    MPM_CALL(mpm_integrator_start(pp->it_gas, t0, 0.0));
  }
  MPM_CALL(mpm_partitioned_advance_solid_under(ts, t0, t1, 1, q));
  for (int d = 0; d < dim; ++d) memcpy(s->after_solid[d], ifc->impulse[d], bytes);
  MPM_CALL(mpm_partitioned_hold(ts, t1));
  MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, 1));
  double **r = s->after_solid;
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx l = 0; l < nn; ++l) {
      s->g[d][l] = (ifc->impulse[d][l] - s->after_solid[d][l]) / H;
      r[d][l] = s->g[d][l] - q[d][l];
    }
  double norms[2];
  MPM_CALL(
      dots(ts, 2, (double *const *const[]){r, s->g}, (double *const *const[]){r, s->g}, norms));
  *rel = norms[1] > 0 ? sqrt(norms[0] / norms[1]) : 0.0;
  return 0;
}

int mpm_strong_step(mpm_strong *s, mpm_timescheme *ts, double t0, double t1) {
  mpm_partitioned *pp = s->pp;
  mpm_interface *ifc = pp->ifc;
  const mpm_grid *grid = ts->grid;
  const int dim = grid->dim;
  const mpm_lidx nn = grid->nnodes;
  copy_nodal(grid, s->q, ifc->prev); /* the predictor */
  MPM_CALL(keep_state(s, 1));
  double w = s->relaxation, rel = 0.0, best = HUGE_VAL;
  int k = 1, best_k = 0;
  int stuck = 0;
  for (;; ++k) {
    if (k > 1 && !can_rewind(s, grid)) { /* keep what the last sub-iteration reached */
      stuck = 1, --k;
      break;
    }
    MPM_CALL(pass(s, ts, t0, t1, k == 1, (const double *const *)s->q, &rel));
    mpm_log(MPM_LOG_TRACE, "strong coupling: t = %.6g, sub-iteration %d: residual %.3g", t0, k,
            rel);
    if (rel <= s->tolerance) break;
    if (rel < best) best = rel, best_k = k, copy_nodal(grid, s->q_best, s->q);
    if (k == s->iterations) {
      /* Not converged: keep the best iterate, not the last (an iteration that wanders off
       * would pass its wild trial load to the solid). */
      if (best_k != k && can_rewind(s, grid)) {
        MPM_CALL(pass(s, ts, t0, t1, 0, (const double *const *)s->q_best, &rel));
        ++k;
      }
      break;
    }
    double **r = s->after_solid;
    if (k > 1) { /* Aitken: w = -w r_prev.(r - r_prev) / |r - r_prev|^2 */
      for (int d = 0; d < dim; ++d)
        for (mpm_lidx l = 0; l < nn; ++l) s->r_prev[d][l] = r[d][l] - s->r_prev[d][l];
      double ad[2]; /* dr.dr, and r.dr, where r_prev.dr = r.dr - dr.dr */
      MPM_CALL(dots(ts, 2, (double *const *const[]){s->r_prev, r},
                    (double *const *const[]){s->r_prev, s->r_prev}, ad));
      if (ad[0] > 0) w = -w * (ad[1] - ad[0]) / ad[0];
      w = fmax(-1.0, fmin(1.0, w));
    }
    for (int d = 0; d < dim; ++d)
      for (mpm_lidx l = 0; l < nn; ++l) {
        s->q[d][l] += w * r[d][l];
        s->r_prev[d][l] = r[d][l];
      }
  }
  /* The next step's predictor: this step's load from the gas. */
  copy_nodal(grid, ifc->prev, s->g);
  s->steps++, s->iters += k;
  if (k > s->most) s->most = k;
  if (stuck && ++s->moved <= MPM_STRONG_WARNINGS)
    mpm_log(MPM_LOG_WARN,
            "strong coupling: at t = %.6g a retried substep changed a particle set (open faces or "
            "migration), so the step could not go back to its start: it keeps sub-iteration %d "
            "(relative residual %.3g)",
            t0, k, rel);
  if (rel > s->tolerance) {
    if (++s->unconverged <= MPM_STRONG_WARNINGS)
      mpm_log(MPM_LOG_WARN,
              "strong coupling: the step at t = %.6g kept a relative interface residual of %.3g "
              "after coupling.iterations = %d (coupling.tolerance = %g); the difference stays "
              "owed to the solid. Raise coupling.iterations or lower time.cfl%s",
              t0, rel, s->iterations, s->tolerance,
              s->unconverged == MPM_STRONG_WARNINGS ? " (later such steps are only counted)" : "");
  }
  if (rel > s->worst) s->worst = rel;
  mpm_log(MPM_LOG_DEBUG, "strong coupling: t = %.6g, %d sub-iterations, residual %.3g", t0, k, rel);
  return 0;
}
