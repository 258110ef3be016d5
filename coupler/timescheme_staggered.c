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
 * Strong coupling (solid_first only): coupling.iterations > 1 repeats the step from its start
 * until the solid's load matches what the gas then gives up, to coupling.tolerance, with Aitken
 * relaxation (mpm_strong.h). gas_first needs none with the classic update (its exchange is
 * already that of the monolithic step), and parallel's gas never sees the solid's new state, so
 * iterating it would converge to its own lagged answer: both are refused.
 *
 * The coupling step is time.cfl times the smaller of the two modules' stability limits (capped
 * by time.dt_max and by the next output time); both modules take it in one step, or in more
 * after a retry. */
#include "mpm_error.h"
#include "mpm_partitioned.h"
#include "mpm_strong.h"

#include <math.h>
#include <string.h>

static const mpm_key_spec staggered_keys[] = {
    {"coupling.order", MPM_KEY_ENUM, "solid_first", 0, 0, 0, 0, "solid_first|gas_first|parallel",
     "staggered: the order of the advances in a coupling step: solid_first (the conventional "
     "serial staggered scheme: the solid under the gas's last load, then the gas), gas_first, "
     "or parallel (both from the state at the start of the step)",
     0, NULL},
    {"coupling.iterations", MPM_KEY_INT, "1", 1, 1000, 0, 0, NULL,
     "staggered solid_first: the most sub-iterations in a coupling step (1: none, the weak "
     "scheme; > 1: strong coupling, with coupling.tolerance)",
     0, "-"},
    {"coupling.tolerance", MPM_KEY_REAL, NULL, 0, 1, 1, 0, NULL,
     "staggered with coupling.iterations > 1: the sub-iterations stop when the interface load's "
     "residual is this fraction of the load (2-norms over the nodes), e.g. 1e-6",
     1, "-"},
    {"coupling.relaxation", MPM_KEY_REAL, "0.5", 0, 1, 1, 0, NULL,
     "staggered with coupling.iterations > 1: the relaxation factor of the first sub-iteration "
     "in (0, 1]; Aitken's rule sets the later ones",
     0, "-"},
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
  int iterations;
  double relaxation, tolerance = 0.0;
  MPM_CALL(mpm_config_get_int(cfg, "coupling.iterations", &iterations));
  MPM_CALL(mpm_config_get_real(cfg, "coupling.relaxation", &relaxation));
  const int has_tol = mpm_config_has(cfg, "coupling.tolerance");
  if (iterations == 1) {
    if (has_tol || mpm_config_has(cfg, "coupling.relaxation"))
      return mpm_config_fail(cfg, has_tol ? "coupling.tolerance" : "coupling.relaxation",
                             "acts only on sub-iterations, and coupling.iterations is 1 (none); "
                             "set coupling.iterations > 1 for strong coupling, or remove the key");
    return 0;
  }
  if (pp->order != ORDER_SOLID_FIRST)
    return mpm_config_fail(cfg, "coupling.iterations",
                           "sub-iterations are offered with coupling.order = solid_first only: "
                           "%s needs none (gas_first with the classic update is already the "
                           "monolithic exchange) or cannot converge to the coupled answer "
                           "(parallel's gas never sees the solid's new state)",
                           order);
  if (!has_tol)
    return mpm_config_fail(cfg, "coupling.iterations",
                           "%d sub-iterations need a stopping rule: give coupling.tolerance, the "
                           "relative interface residual to reach (e.g. 1e-6)",
                           iterations);
  MPM_CALL(mpm_config_get_real(cfg, "coupling.tolerance", &tolerance));
  pp->iterations = iterations;
  return mpm_strong_new(&pp->strong, pp, iterations, tolerance, relaxation);
}

static void stag_destroy(mpm_timescheme *ts) {
  mpm_partitioned *pp = ts->content;
  if (pp) mpm_strong_destroy(&pp->strong);
  mpm_partitioned_destroy(ts);
}

/* A step that never converges takes every sub-iteration (and is accepted with a warning): the
 * budget counts them all. */
static int stag_work(mpm_timescheme *ts, double *advances, double *need, const char **key) {
  const mpm_partitioned *pp = ts->content;
  *advances = pp->strong ? pp->iterations : 1, *key = pp->strong ? "coupling.iterations" : NULL;
  *need = *advances; /* a step may need every sub-iteration it allows */
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
    if (pp->strong) {
      MPM_CALL(mpm_strong_step(pp->strong, ts, t0, t1));
      break;
    }
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
    .destroy = stag_destroy,
    .start = mpm_partitioned_start,
    .step = stag_step,
    .resize = mpm_partitioned_resize,
    .cfl_step = mpm_partitioned_cfl_step,
    .work = stag_work,
    .next_step = mpm_partitioned_next_step,
    .counts = mpm_partitioned_counts,
    .record = mpm_partitioned_record,
    .save = mpm_partitioned_save,
    .restore = mpm_partitioned_restore,
};

const mpm_timescheme_type timescheme_staggered = {
    .name = "staggered",
    .help = "one integrator per module, exchanging once per coupling step in the order "
            "coupling.order, optionally sub-iterated to convergence (coupling.iterations; "
            "classic update only)",
    .keys = staggered_keys,
    .nkeys = (int)(sizeof staggered_keys / sizeof staggered_keys[0]),
    .ops = &stag_ops,
};
