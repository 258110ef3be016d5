/* `staggered`: one integrator per module, exchanging interface data once per coupling step H
 * (the partitioned procedures of Piperno and Farhat). The gas advances against the solid held
 * at its last deposit (a held cycle: the spatial scheme acts as in the monolithic step, and what
 * it gives the solid is captured, not applied); the solid advances alone under the load the gas
 * left it (a loaded cycle), so it receives exactly the momentum the gas gave up
 * (mpm_interface.h). The order, coupling.order:
 *   solid_first  conventional serial staggered: the solid advances under the load of the gas's
 *                last advance, then the gas against the solid's new state (the load is one
 *                coupling step late);
 *   gas_first    the gas advances against the solid's state at the start of the step, then the
 *                solid under the load the gas has just left (nothing is late at the end of a
 *                coupling step);
 *   parallel     both from the state at the start of the step: the solid under the load of the
 *                gas's last advance, the gas against the solid held at the start (the two
 *                advances are independent).
 * Each exchange is lagged by up to one coupling step; the energy that creates or destroys at
 * the interface is what coupling.csv reports (P_net, W_net), first order in H.
 *
 * The coupling step is time.cfl times the smaller of the two modules' stability limits (capped
 * by time.dt_max and by the next output time), and both modules take it in one step, or in more
 * after a retry. The classic update only (usl, musl): the captured load is the interface force
 * of each step's one RHS; an adaptive pair's stages would each capture another. */
#include "mpm_error.h"
#include "mpm_integrator.h"
#include "mpm_timescheme.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const mpm_key_spec staggered_keys[] = {
    {"coupling.order", MPM_KEY_ENUM, "solid_first", 0, 0, 0, 0, "solid_first|gas_first|parallel",
     "staggered: the order of the advances in a coupling step: solid_first (the conventional "
     "serial staggered scheme: the solid under the gas's last load, then the gas), gas_first, "
     "or parallel (both from the state at the start of the step)",
     0},
};

typedef enum { ORDER_SOLID_FIRST, ORDER_GAS_FIRST, ORDER_PARALLEL } stag_order;

typedef struct {
  stag_order order;
  mpm_module *solid, *gas;
  mpm_integrator *it_solid, *it_gas;
  mpm_interface *ifc;
  mpm_cycle deposit; /* the solid alone, for its deposit before the gas advances */
  double dt_max, h_last;
  long steps;
  mpm_coupling_record rec; /* the interface record of the last coupling step */
} staggered;

static int stag_create(mpm_timescheme *ts, const mpm_config *cfg) {
  staggered *st;
  MPM_ALLOC(st, 1);
  ts->content = st;
  mpm_coupling *c = ts->coupling;
  if (!c)
    return mpm_config_fail(cfg, "coupling.time",
                           "staggered advances a gas and a solid in turn, and this scene has no "
                           "coupled pair (one phase, or coupling.scheme = none); remove the key "
                           "or add the other phase");
  const char *method, *order;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "usl") != 0 && strcmp(method, "musl") != 0)
    return mpm_config_fail(cfg, "time.method",
                           "coupling.time = staggered runs with the classic update (usl or musl): "
                           "it passes on the interface force of each step's one RHS, and the "
                           "stages of %s would each give another; use usl or musl, or "
                           "coupling.time = monolithic",
                           method);
  MPM_CALL(mpm_config_get_string(cfg, "coupling.order", &order));
  st->order = strcmp(order, "gas_first") == 0  ? ORDER_GAS_FIRST
              : strcmp(order, "parallel") == 0 ? ORDER_PARALLEL
                                               : ORDER_SOLID_FIRST;
  MPM_CALL(mpm_config_get_real(cfg, "time.dt_max", &st->dt_max));
  if (st->dt_max <= 0) st->dt_max = HUGE_VAL;
  st->solid = c->module[MPM_ROLE_SOLID], st->gas = c->module[MPM_ROLE_FLUID];
  MPM_CALL(mpm_interface_new(&st->ifc, ts->grid, st->solid->phase));
  const mpm_cycle base = {.grid = ts->grid, .nmod = 1, .coupling = c, .iface = st->ifc};
  mpm_cycle solid = base, gas = base;
  solid.mod = &st->solid, solid.mode = MPM_CYCLE_LOADED;
  gas.mod = &st->gas, gas.mode = MPM_CYCLE_HELD;
  st->deposit = solid, st->deposit.mode = MPM_CYCLE_JOINT;
  MPM_CALL(mpm_integrator_new(&st->it_solid, cfg, &solid));
  MPM_CALL(mpm_integrator_new(&st->it_gas, cfg, &gas));
  return 0;
}

static void stag_destroy(mpm_timescheme *ts) {
  staggered *st = ts->content;
  if (!st) return;
  mpm_integrator_destroy(&st->it_solid);
  mpm_integrator_destroy(&st->it_gas);
  mpm_interface_destroy(&st->ifc);
  free(st);
}

static int stag_start(mpm_timescheme *ts, double t, double h0) {
  staggered *st = ts->content;
  MPM_CALL(mpm_integrator_start(st->it_solid, t, h0));
  return mpm_integrator_start(st->it_gas, t, h0);
}

static int stag_resize(mpm_timescheme *ts, double t) {
  staggered *st = ts->content;
  MPM_CALL(mpm_integrator_resize(st->it_solid, t));
  return mpm_integrator_resize(st->it_gas, t);
}

static int stag_cfl_step(mpm_timescheme *ts, double *h) {
  staggered *st = ts->content;
  double hs, hg;
  MPM_CALL(mpm_integrator_cfl_step(st->it_solid, &hs));
  MPM_CALL(mpm_integrator_cfl_step(st->it_gas, &hg));
  *h = hs > 0 && hg > 0 ? fmin(hs, hg) : fmax(hs, hg);
  return 0;
}

/* Advance one module's integrator to t1 (one step, or more after a retry), adding each step's
 * interface record, weighted by its size, to sum (force and power of the module's role). With
 * the gas, each accepted step's captured force becomes owed impulse. */
static int advance(mpm_timescheme *ts, mpm_integrator *it, mpm_role role, double t, double t1,
                   mpm_coupling_record *sum) {
  staggered *st = ts->content;
  while (t < t1) {
    double h;
    MPM_CALL(mpm_integrator_step(it, t1, &t, &h));
    if (role == MPM_ROLE_FLUID) mpm_interface_capture_accept(st->ifc, h);
    mpm_coupling_record r;
    MPM_CALL(mpm_coupling_step_record(ts->coupling, t, &r));
    for (int d = 0; d < MPM_MAX_DIM; ++d) sum->force[role][d] += h * r.force[role][d];
    sum->power[role] += h * r.power[role];
    if (role == MPM_ROLE_FLUID) sum->gas_inside = r.gas_inside;
    for (int b = 0; role == MPM_ROLE_SOLID && b < MPM_COUPLING_MAX_BODIES; ++b)
      for (int d = 0; d < MPM_MAX_DIM; ++d) sum->body[b][d] += h * r.body[b][d];
  }
  return 0;
}

static int advance_solid(mpm_timescheme *ts, double t, double t1, mpm_coupling_record *sum) {
  staggered *st = ts->content;
  mpm_interface_load(st->ifc, t1 - t);
  MPM_CALL(advance(ts, st->it_solid, MPM_ROLE_SOLID, t, t1, sum));
  mpm_interface_unload(st->ifc);
  return 0;
}

/* Deposit the solid as it is now and hold it for the gas. */
static int hold_solid(mpm_timescheme *ts, double t) {
  staggered *st = ts->content;
  double *y = st->solid->particles->data;
  MPM_CALL(mpm_cycle_deposit(&st->deposit, t, &y));
  mpm_interface_hold(st->ifc);
  return 0;
}

static int stag_step(mpm_timescheme *ts, double tstop, double *t, double *h) {
  staggered *st = ts->content;
  double H;
  MPM_CALL(stag_cfl_step(ts, &H));
  const double t0 = *t, rest = tstop - t0;
  H = H > 0 ? fmin(fmin(H, st->dt_max), rest) : fmin(st->dt_max, rest);
  const double t1 = H < rest ? t0 + H : tstop;
  mpm_coupling_record sum = {0};
  switch (st->order) {
  case ORDER_SOLID_FIRST:
    MPM_CALL(advance_solid(ts, t0, t1, &sum));
    MPM_CALL(hold_solid(ts, t1));
    MPM_CALL(advance(ts, st->it_gas, MPM_ROLE_FLUID, t0, t1, &sum));
    break;
  case ORDER_GAS_FIRST:
    MPM_CALL(hold_solid(ts, t0));
    MPM_CALL(advance(ts, st->it_gas, MPM_ROLE_FLUID, t0, t1, &sum));
    MPM_CALL(advance_solid(ts, t0, t1, &sum));
    break;
  case ORDER_PARALLEL:
    MPM_CALL(hold_solid(ts, t0));
    MPM_CALL(advance_solid(ts, t0, t1, &sum));
    MPM_CALL(advance(ts, st->it_gas, MPM_ROLE_FLUID, t0, t1, &sum));
    break;
  }
  /* Rates over the coupling step, and what the gas gave up that the solid has yet to get. */
  const double w = 1.0 / (t1 - t0);
  for (int r = 0; r < MPM_ROLE_COUNT; ++r) {
    for (int d = 0; d < MPM_MAX_DIM; ++d) sum.force[r][d] *= w;
    sum.power[r] *= w;
  }
  for (int b = 0; b < MPM_COUPLING_MAX_BODIES; ++b)
    for (int d = 0; d < MPM_MAX_DIM; ++d) sum.body[b][d] *= w;
  double owed[MPM_MAX_DIM] = {0};
  mpm_interface_owed(st->ifc, ts->coupling->owned, owed);
  MPM_CALL_MPI(MPI_Allreduce(owed, sum.owed, MPM_MAX_DIM, MPI_DOUBLE, MPI_SUM, ts->grid->comm));
  st->rec = sum;
  st->steps++;
  *t = t1, *h = st->h_last = t1 - t0;
  return 0;
}

static double stag_next_step(const mpm_timescheme *ts) {
  const staggered *st = ts->content;
  return st->h_last;
}

static void stag_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                        long *retries) {
  const staggered *st = ts->content;
  long s[2], r[2], f[2], q[2];
  mpm_integrator_counts(st->it_solid, &s[0], &r[0], &f[0], &q[0]);
  mpm_integrator_counts(st->it_gas, &s[1], &r[1], &f[1], &q[1]);
  *steps = st->steps, *rhs = r[0] + r[1], *fails = f[0] + f[1], *retries = q[0] + q[1];
}

static int stag_record(mpm_timescheme *ts, double t, mpm_coupling_record *out) {
  (void)t;
  const staggered *st = ts->content;
  *out = st->rec;
  return 0;
}

static const mpm_timescheme_ops stag_ops = {
    .create = stag_create,
    .destroy = stag_destroy,
    .start = stag_start,
    .step = stag_step,
    .resize = stag_resize,
    .cfl_step = stag_cfl_step,
    .next_step = stag_next_step,
    .counts = stag_counts,
    .record = stag_record,
};

const mpm_timescheme_type timescheme_staggered = {
    .name = "staggered",
    .help = "one integrator per module, exchanging once per coupling step in the order "
            "coupling.order (classic update only)",
    .keys = staggered_keys,
    .nkeys = (int)(sizeof staggered_keys / sizeof staggered_keys[0]),
    .ops = &stag_ops,
};
