/* `staggered`: one integrator per module, exchanging interface data once per coupling step H
 * (the partitioned procedures of Piperno and Farhat; the machinery is mpm_partitioned.h). The
 * order, coupling.order:
 *   solid_first  conventional serial staggered: the solid advances under the momentum the gas
 *                gave up in its last advance, then the gas against the solid's new state (the
 *                load is one coupling step late);
 *   gas_first    the gas advances against the solid's state at the start of the step, then the
 *                solid under the momentum the gas has just given up (with a one-stage update
 *                this is the monolithic step: the exchange is evaluated once, at the start);
 *   parallel     both from the state at the start of the step: the solid under the load of the
 *                gas's last advance, the gas against the solid held at the start (the two
 *                advances are independent of each other).
 * The energy the lag creates or destroys at the interface is what coupling.csv reports.
 *
 * The coupling step is time.cfl times the smaller of the two modules' stability limits (capped
 * by time.dt_max and by the next output time); both modules take it in one step, or in more
 * after a retry. */
#include "mpm_error.h"
#include "mpm_partitioned.h"

#include <math.h>
#include <string.h>

static const mpm_key_spec staggered_keys[] = {
    {"coupling.order", MPM_KEY_ENUM, "solid_first", 0, 0, 0, 0, "solid_first|gas_first|parallel",
     "staggered: the order of the advances in a coupling step: solid_first (the conventional "
     "serial staggered scheme: the solid under the gas's last load, then the gas), gas_first, "
     "or parallel (both from the state at the start of the step)",
     0},
};

typedef enum { ORDER_SOLID_FIRST, ORDER_GAS_FIRST, ORDER_PARALLEL } stag_order;

static int stag_create(mpm_timescheme *ts, const mpm_config *cfg) {
  MPM_CALL(mpm_partitioned_new(ts, cfg, "staggered"));
  mpm_partitioned *pp = ts->content;
  const char *order;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.order", &order));
  pp->order = strcmp(order, "gas_first") == 0  ? ORDER_GAS_FIRST
              : strcmp(order, "parallel") == 0 ? ORDER_PARALLEL
                                               : ORDER_SOLID_FIRST;
  return 0;
}

static int stag_step(mpm_timescheme *ts, double tstop, double *t, double *h) {
  const mpm_partitioned *pp = ts->content;
  double H;
  MPM_CALL(mpm_partitioned_cfl_step(ts, &H));
  const double t0 = *t, rest = tstop - t0;
  H = H > 0 ? fmin(fmin(H, pp->dt_max), rest) : fmin(pp->dt_max, rest);
  const double t1 = H < rest ? t0 + H : tstop;
  switch ((stag_order)pp->order) {
  case ORDER_SOLID_FIRST:
    MPM_CALL(mpm_partitioned_advance_solid(ts, t0, t1, 1));
    MPM_CALL(mpm_partitioned_hold(ts, t1));
    MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, 1));
    break;
  case ORDER_GAS_FIRST:
    MPM_CALL(mpm_partitioned_hold(ts, t0));
    MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, 1));
    MPM_CALL(mpm_partitioned_advance_solid(ts, t0, t1, 1));
    break;
  case ORDER_PARALLEL:
    MPM_CALL(mpm_partitioned_hold(ts, t0));
    MPM_CALL(mpm_partitioned_advance_solid(ts, t0, t1, 1));
    MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, 1));
    break;
  }
  MPM_CALL(mpm_partitioned_end(ts, t0, t1));
  *t = t1, *h = t1 - t0;
  return 0;
}

static const mpm_timescheme_ops stag_ops = {
    .create = stag_create,
    .destroy = mpm_partitioned_destroy,
    .start = mpm_partitioned_start,
    .step = stag_step,
    .resize = mpm_partitioned_resize,
    .cfl_step = mpm_partitioned_cfl_step,
    .next_step = mpm_partitioned_next_step,
    .counts = mpm_partitioned_counts,
    .record = mpm_partitioned_record,
    .save = mpm_partitioned_save,
    .restore = mpm_partitioned_restore,
};

const mpm_timescheme_type timescheme_staggered = {
    .name = "staggered",
    .help = "one integrator per module, exchanging once per coupling step in the order "
            "coupling.order (classic update only)",
    .keys = staggered_keys,
    .nkeys = (int)(sizeof staggered_keys / sizeof staggered_keys[0]),
    .ops = &stag_ops,
};
