/* The shared machinery of the partitioned time schemes (see mpm_partitioned.h). */
#include "mpm_partitioned.h"

#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int mpm_partitioned_new(mpm_timescheme *ts, const mpm_config *cfg, const char *scheme) {
  mpm_partitioned *pp;
  MPM_ALLOC(pp, 1);
  ts->content = pp;
  mpm_coupling *c = ts->coupling;
  if (!c)
    return mpm_config_fail(cfg, "coupling.time",
                           "%s advances a gas and a solid in turn, and this scene has no coupled "
                           "pair (one phase, or coupling.scheme = none); remove the key or add "
                           "the other phase",
                           scheme);
  const char *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "usl") != 0 && strcmp(method, "musl") != 0)
    return mpm_config_fail(cfg, "time.method",
                           "coupling.time = %s runs with the classic update (usl or musl): it "
                           "passes on the interface force of each step's one RHS, and the stages "
                           "of %s would each give another; use usl or musl, or coupling.time = "
                           "monolithic",
                           scheme, method);
  MPM_CALL(mpm_config_get_real(cfg, "time.dt_max", &pp->dt_max));
  if (pp->dt_max <= 0) pp->dt_max = HUGE_VAL;
  pp->solid = c->module[MPM_ROLE_SOLID], pp->gas = c->module[MPM_ROLE_FLUID];
  MPM_CALL(mpm_interface_new(&pp->ifc, ts->grid, pp->solid->phase));
  const mpm_cycle base = {.grid = ts->grid, .nmod = 1, .coupling = c, .iface = pp->ifc};
  mpm_cycle solid = base, gas = base;
  solid.mod = &pp->solid, solid.mode = MPM_CYCLE_LOADED;
  gas.mod = &pp->gas, gas.mode = MPM_CYCLE_HELD;
  pp->deposit = solid, pp->deposit.mode = MPM_CYCLE_JOINT;
  pp->gas_deposit = gas, pp->gas_deposit.mode = MPM_CYCLE_JOINT;
  MPM_CALL(mpm_integrator_new(&pp->it_solid, cfg, &solid));
  MPM_CALL(mpm_integrator_new(&pp->it_gas, cfg, &gas));
  return 0;
}

void mpm_partitioned_destroy(mpm_timescheme *ts) {
  mpm_partitioned *pp = ts->content;
  if (!pp) return;
  mpm_integrator_destroy(&pp->it_solid);
  mpm_integrator_destroy(&pp->it_gas);
  mpm_interface_destroy(&pp->ifc);
  free(pp);
}

int mpm_partitioned_start(mpm_timescheme *ts, double t, double h0) {
  mpm_partitioned *pp = ts->content;
  MPM_CALL(mpm_integrator_start(pp->it_solid, t, h0));
  return mpm_integrator_start(pp->it_gas, t, h0);
}

int mpm_partitioned_resize(mpm_timescheme *ts, double t) {
  mpm_partitioned *pp = ts->content;
  MPM_CALL(mpm_integrator_resize(pp->it_solid, t));
  return mpm_integrator_resize(pp->it_gas, t);
}

int mpm_partitioned_cfl_steps(mpm_timescheme *ts, double *h_solid, double *h_gas) {
  mpm_partitioned *pp = ts->content;
  MPM_CALL(mpm_integrator_cfl_step(pp->it_solid, h_solid));
  return mpm_integrator_cfl_step(pp->it_gas, h_gas);
}

int mpm_partitioned_cfl_step(mpm_timescheme *ts, double *h) {
  double hs, hg;
  MPM_CALL(mpm_partitioned_cfl_steps(ts, &hs, &hg));
  *h = hs > 0 && hg > 0 ? fmin(hs, hg) : fmax(hs, hg);
  return 0;
}

int mpm_partitioned_want_shared(mpm_timescheme *ts, const mpm_config *cfg) {
  mpm_partitioned *pp = ts->content;
  MPM_CALL(mpm_interface_want_shared(pp->ifc));
  mpm_cycle gas = pp->gas_deposit;
  gas.mode = MPM_CYCLE_FOLLOW;
  mpm_integrator_destroy(&pp->it_gas);
  MPM_CALL(mpm_integrator_new(&pp->it_gas, cfg, &gas));
  pp->shared = 1;
  return 0;
}

int mpm_partitioned_share(mpm_timescheme *ts, double t) {
  mpm_partitioned *pp = ts->content;
  double *y = pp->gas->particles->data;
  MPM_CALL(mpm_cycle_deposit(&pp->gas_deposit, t, &y));
  mpm_interface_share(pp->ifc, pp->gas->phase);
  return 0;
}

int mpm_partitioned_hold(mpm_timescheme *ts, double t) {
  mpm_partitioned *pp = ts->content;
  double *y = pp->solid->particles->data;
  MPM_CALL(mpm_cycle_deposit(&pp->deposit, t, &y));
  mpm_interface_hold(pp->ifc);
  mpm_interface_predict_hold(pp->ifc, t);
  return 0;
}

/* A substep is planned from the module's stable step, so it takes one integrator step, or a
 * few after retries; this many means the module's stable step collapsed within one coupling
 * step: the blow-up guard (which sees coupling steps) could not. */
#define MPM_PARTITIONED_MAX_STEPS 1000

/* Advance one integrator from t0 to t1 in n equal substeps (each one step, or more after a
 * retry), adding each step's interface record for the module's role, times its size, to the
 * step's sums. The gas's accepted steps add what they captured to the owed momentum, the
 * solid's take off what they delivered. */
static int advance(mpm_timescheme *ts, mpm_integrator *it, mpm_role role, double t0, double t1,
                   int n) {
  mpm_partitioned *pp = ts->content;
  mpm_coupling_record *sum = &pp->sum;
  mpm_module *m = role == MPM_ROLE_SOLID ? pp->solid : pp->gas;
  double t = t0, h = 0.0;
  /* A substep ends within this of its end time: the rest is roundoff (t0 + (t1 - t0) k / n and
   * the sum of the steps taken need not agree to the last bit), and a step of that size would
   * not advance the time at all. */
  const double arrived = 1e-9 * (t1 - t0) / n;
  for (int k = 1; k <= n; ++k) {
    const double tk = k == n ? t1 : t0 + (t1 - t0) * k / n;
    for (long taken = 0; tk - t > arrived; ++taken) {
      if (taken == MPM_PARTITIONED_MAX_STEPS)
        MPM_FAIL(MPM_ERR_UNPHYSICAL,
                 "the run blew up at t = %.6g: the %s module has taken %d steps inside one "
                 "substep of %.3g s, its stable step %.3g s and falling (it was planned from "
                 "the module's stable step when the coupling step began): reduce time.cfl, "
                 "refine the grid, or check the scene near the interface",
                 t, m->name, MPM_PARTITIONED_MAX_STEPS, (t1 - t0) / n, h);
      if (t > t0 && ts->between) { /* the step loop's work between two substeps */
        int changed = 0;
        MPM_CALL(ts->between(ts->between_ctx, m, t, h, &changed));
        MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_LOR, ts->grid->comm));
        if (changed) MPM_CALL(mpm_integrator_resize(it, t));
      }
      MPM_CALL(mpm_integrator_step(it, tk, &t, &h));
      mpm_interface_capture_accept(pp->ifc, h, role == MPM_ROLE_FLUID ? 1 : -1);
      mpm_coupling_record r;
      MPM_CALL(mpm_coupling_step_record(ts->coupling, t, &r));
      for (int d = 0; d < MPM_MAX_DIM; ++d) sum->force[role][d] += h * r.force[role][d];
      sum->power[role] += h * r.power[role];
      if (role == MPM_ROLE_FLUID) sum->gas_inside = r.gas_inside;
      for (int b = 0; role == MPM_ROLE_SOLID && b < MPM_COUPLING_MAX_BODIES; ++b)
        for (int d = 0; d < MPM_MAX_DIM; ++d) sum->body[b][d] += h * r.body[b][d];
    }
  }
  return 0;
}

int mpm_partitioned_advance_gas(mpm_timescheme *ts, double t0, double t1, int n) {
  mpm_partitioned *pp = ts->content;
  return advance(ts, pp->it_gas, MPM_ROLE_FLUID, t0, t1, n);
}

int mpm_partitioned_advance_solid(mpm_timescheme *ts, double t0, double t1, int n) {
  return mpm_partitioned_advance_solid_under(ts, t0, t1, n, NULL);
}

int mpm_partitioned_advance_solid_under(mpm_timescheme *ts, double t0, double t1, int n,
                                        const double *const *q) {
  mpm_partitioned *pp = ts->content;
  mpm_interface_load(pp->ifc, t0, t1 - t0, pp->interpolate);
  for (int d = 0; q && d < ts->grid->dim; ++d)
    for (mpm_lidx l = 0; l < ts->grid->nnodes; ++l) pp->ifc->load[d][l] += q[d][l];
  const int rc = advance(ts, pp->it_solid, MPM_ROLE_SOLID, t0, t1, n);
  mpm_grid_phase_widen(ts->grid, pp->solid->phase); /* (its substeps narrowed it) */
  MPM_CALL(rc);
  return pp->shared ? 0 : mpm_interface_rehome(pp->ifc, ts->coupling->owned);
}

int mpm_partitioned_end(mpm_timescheme *ts, double t0, double t1) {
  mpm_partitioned *pp = ts->content;
  mpm_coupling_record *sum = &pp->sum;
  const double w = 1.0 / (t1 - t0);
  for (int r = 0; r < MPM_ROLE_COUNT; ++r) {
    for (int d = 0; d < MPM_MAX_DIM; ++d) sum->force[r][d] *= w;
    sum->power[r] *= w;
  }
  for (int b = 0; b < MPM_COUPLING_MAX_BODIES; ++b)
    for (int d = 0; d < MPM_MAX_DIM; ++d) sum->body[b][d] *= w;
  double owed[MPM_MAX_DIM] = {0};
  mpm_interface_owed(pp->ifc, ts->coupling->owned, owed);
  MPM_CALL_MPI(MPI_Allreduce(owed, sum->owed, MPM_MAX_DIM, MPI_DOUBLE, MPI_SUM, ts->grid->comm));
  pp->rec = *sum;
  memset(sum, 0, sizeof *sum);
  pp->steps++;
  pp->h_last = t1 - t0;
  return 0;
}

double mpm_partitioned_next_step(const mpm_timescheme *ts) {
  const mpm_partitioned *pp = ts->content;
  return pp->h_last;
}

void mpm_partitioned_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                            long *retries) {
  const mpm_partitioned *pp = ts->content;
  long s[2], r[2], f[2], q[2];
  mpm_integrator_counts(pp->it_solid, &s[0], &r[0], &f[0], &q[0]);
  mpm_integrator_counts(pp->it_gas, &s[1], &r[1], &f[1], &q[1]);
  *steps = pp->steps, *rhs = r[0] + r[1], *fails = f[0] + f[1], *retries = q[0] + q[1];
}

int mpm_partitioned_record(mpm_timescheme *ts, double t, mpm_coupling_record *out) {
  (void)t;
  const mpm_partitioned *pp = ts->content;
  *out = pp->rec;
  return 0;
}

int mpm_partitioned_save(mpm_timescheme *ts, mpm_particles **p, const char **name) {
  mpm_partitioned *pp = ts->content;
  MPM_CALL(mpm_interface_particles_new(p, ts->grid->dim, pp->ifc->mprev != NULL));
  *name = MPM_INTERFACE_PHASE;
  return mpm_interface_pack(pp->ifc, ts->coupling->owned, *p);
}

int mpm_partitioned_restore(mpm_timescheme *ts, mpm_checkpoint *ck) {
  mpm_partitioned *pp = ts->content;
  mpm_particles *p = NULL;
  int rc = mpm_interface_particles_new(&p, ts->grid->dim, pp->ifc->mprev != NULL);
  if (!rc) rc = mpm_checkpoint_read_particles(ck, MPM_INTERFACE_PHASE, p);
  if (!rc) rc = mpm_particles_migrate(p, ts->grid, NULL);
  if (!rc) mpm_interface_unpack(pp->ifc, p);
  mpm_particles_destroy(&p);
  MPM_CALL(rc);
  /* The momentum owed at the checkpoint, as the record of the step that reached it had it. */
  double owed[MPM_MAX_DIM] = {0};
  mpm_interface_owed(pp->ifc, ts->coupling->owned, owed);
  MPM_CALL_MPI(MPI_Allreduce(owed, pp->rec.owed, MPM_MAX_DIM, MPI_DOUBLE, MPI_SUM, ts->grid->comm));
  return 0;
}
