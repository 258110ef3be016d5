/* `multirate`: each module steps at its own rate. The module with the larger stable step is the
 * slow one and sets the coupling step H (time.cfl times its limit); the other, the fast one,
 * takes m substeps of H / m inside it (coupling.substeps, or the fewest its own limit allows).
 * The subcycled form of the classic update (machinery: mpm_partitioned.h): the gas advances
 * first, against the solid held at the start of the step, then the solid under exactly the
 * momentum the gas gave up, spread over H either evenly (coupling.load = held) or with the
 * load's linear trend since the last coupling step (interpolated; the same momentum). With
 * m = 1 this is the monolithic classic step (see timescheme_staggered.c, gas_first). With
 * coupling.predictor = linear the gas meets the held solid's interface velocity extrapolated
 * from its last two coupling steps instead (mpm_interface.h); the exchange stays exact.
 * With coupling.exchange = shared (velocity scheme, usl) the solid goes first and its substeps
 * advance the nodes it shares with the gas with the gas's nodal mass and force beside its own;
 * the gas, in one step, then takes the velocity they left there (mpm_interface.h, the shared
 * nodes): where the solid is light beside the gas, the held exchange makes its face ring.
 *
 * H is the slow module's stable step. On the shock panel that is the gas's, and in it the
 * artificial viscosity's diffusion limit (fluid.viscous_step, fluid_stress.h): a trace-level log
 * line gives both modules' stable steps and the substeps of every coupling step.
 *
 * An ablation of multirate's own error: with coupling.slow_substeps = n the slow module, too,
 * takes n substeps of H / n against the fast one held at the start of the coupling step (0: as
 * many as the fast module). At n = 0 both modules step at the fast module's rate, and what
 * separates the run from monolithic at the same step is the held partner, the coupling lag
 * (and the step loop's work between steps, the gas's shifting for one, which every partitioned
 * scheme does once per coupling step); the rest of multirate's error is the slow module's own
 * step. On the shock panel at 1 mm the lag is the smaller part (docs/time.md).
 *
 * Which is fast depends on the scene: a steel panel in air is the fast module (its stable step
 * is about a tenth of the air's), a soft bar in a Mach 2.5 stream the slow one.
 *
 * With an ERK pair (time.method = ralston21, bs32, zonneveld43, dp54) the scheme is ARKODE's
 * MRIStep instead (mpm_integrator_new_multirate): one integrator over both modules' state, the
 * solid's own dynamics the fast partition and the rest (the gas and everything the coupling
 * adds to either) the slow one, with the MRI coupling table coupling.mri_table. SUNDIALS 6.4's
 * MRIStep takes a fixed slow step, so both partitions take fixed steps from their CFL limits
 * (time.adaptive = false is required: the pair's error estimate is not used). The gas is always
 * the slow partition: its particles enter, leave and change rank between steps only. */
#include "mpm_error.h"
#include "mpm_integrator.h"
#include "mpm_log.h"
#include "mpm_partitioned.h"

#include <arkode/arkode_mristep.h>
#include <math.h>
#include <string.h>

enum {
  KEY_SUBSTEPS,
  KEY_SLOW_SUBSTEPS,
  KEY_LOAD,
  KEY_MRI_TABLE,
  KEY_PREDICTOR,
  KEY_EXCHANGE
}; /* in order */
/* The substep keys go up to MULTIRATE_MAX_SUBSTEPS, the most the scheme takes on its own before
 * it calls the fast module's step collapsed (below): 10-100 is what two stable modules need.
 * Up to 1e6 was allowed: at that setting a coupling step took 84 s (issue 54), while the run's
 * budget counted coupling steps only (it now counts the substeps too). */
static const mpm_key_spec multirate_keys[] = {
    {"coupling.substeps", MPM_KEY_INT, NULL, 1, 1e4, 0, 0, NULL,
     "multirate: substeps of the fast module in each coupling step, >= 1 (unset: the fewest its "
     "own stable step allows; 1: the monolithic step)",
     1, "-"},
    {"coupling.slow_substeps", MPM_KEY_INT, "1", 0, 1e4, 0, 0, NULL,
     "multirate, classic update: substeps of the slow module in each coupling step, against the "
     "fast one held (1: one step, multirate itself; 0: as many as the fast module, an ablation: "
     "the coupling lag without the slow module's own step error)",
     0, "-"},
    {"coupling.load", MPM_KEY_ENUM, "held", 0, 0, 0, 0, "held|interpolated",
     "multirate: how the solid's substeps see the gas's load: held (constant over the coupling "
     "step) or interpolated (with its linear trend since the last coupling step); both pass "
     "the same momentum",
     0, NULL},
    {"coupling.mri_table", MPM_KEY_ENUM, "mri_gark_erk33a", 0, 0, 0, 0,
     "mri_gark_erk33a|mis_kw3|mri_gark_erk45a",
     "multirate with an ERK pair (MRIStep): the MRI coupling table, MRI-GARK-ERK33a (order 3), "
     "MIS-KW3 (order 3) or MRI-GARK-ERK45a (order 4)",
     0, NULL},
    {"coupling.predictor", MPM_KEY_ENUM, "none", 0, 0, 0, 0, "none|linear",
     "multirate, classic update: the solid's interface velocity the gas meets over a coupling "
     "step: none (the solid at the step's start, advanced by its own nodal force then) or "
     "linear (extrapolated from its last two coupling steps); the momentum exchanged stays "
     "exact either way",
     0, NULL},
    {"coupling.exchange", MPM_KEY_ENUM, "held", 0, 0, 0, 0, "held|shared",
     "multirate, classic update, velocity scheme: held (the gas first, against the solid held "
     "at the step's start; the solid then under the gas's impulse as a load) or shared (the "
     "solid first, its substeps advancing the nodes it shares with the gas with the gas's "
     "nodal mass and force beside its own; the gas then takes the velocity they left there)",
     0, NULL},
};

/* coupling.mri_table's choices and their ARKODE tables. */
static const struct {
  const char *name;
  ARKODE_MRITableID id;
} mri_tables[] = {{"mri_gark_erk33a", ARKODE_MRI_GARK_ERK33a},
                  {"mis_kw3", ARKODE_MIS_KW3},
                  {"mri_gark_erk45a", ARKODE_MRI_GARK_ERK45a}};

/* The MRIStep form: a type of its own whose ops are the one-integrator scheme's. */
static const mpm_timescheme_type multirate_mri = {
    .name = "multirate",
    .help = "multirate with an ERK pair: ARKODE MRIStep",
    .ops = &timescheme_monolithic_ops,
};

/* A key of the other form, set away from its default. */
static int foreign_key(const mpm_config *cfg, int k, const char *why) {
  if (!mpm_config_set_off_default(cfg, &multirate_keys[k])) return 0;
  return mpm_config_fail(cfg, multirate_keys[k].key, "%s", why);
}

static int multirate_mri_create(mpm_timescheme *ts, const mpm_config *cfg, const char *method) {
  if (!ts->coupling)
    return mpm_config_fail(cfg, "coupling.time",
                           "multirate advances a gas and a solid at their own rates, and this "
                           "scene has no coupled pair (one phase, or coupling.scheme = none); "
                           "remove the key or add the other phase");
  MPM_CALL(foreign_key(cfg, KEY_LOAD,
                       "is read with the classic update only: MRIStep (an ERK pair) passes the "
                       "gas's stages to the solid itself; remove it or use time.method = usl"));
  MPM_CALL(foreign_key(cfg, KEY_PREDICTOR,
                       "is read with the classic update only: MRIStep (an ERK pair) passes the "
                       "solid's stages to the gas itself; remove it or use time.method = usl"));
  MPM_CALL(foreign_key(cfg, KEY_SLOW_SUBSTEPS,
                       "is read with the classic update only: MRIStep (an ERK pair) takes one "
                       "slow step per coupling step; remove it or use time.method = usl"));
  MPM_CALL(foreign_key(cfg, KEY_EXCHANGE,
                       "is read with the classic update only: MRIStep (an ERK pair) advances "
                       "the shared nodes with the gas; remove it or use time.method = usl"));
  int adaptive;
  MPM_CALL(mpm_config_get_bool(cfg, "time.adaptive", &adaptive));
  if (adaptive)
    return mpm_config_fail(cfg, "time.adaptive",
                           "coupling.time = multirate with %s runs ARKODE MRIStep, which takes "
                           "fixed steps (SUNDIALS 6.4): set time.adaptive = false (each "
                           "partition then steps at time.cfl of its own stable step), or use "
                           "coupling.time = monolithic for error control",
                           method);
  int substeps = 0, fast = -1;
  if (mpm_config_has(cfg, "coupling.substeps"))
    MPM_CALL(mpm_config_get_int(cfg, "coupling.substeps", &substeps));
  const char *table;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.mri_table", &table));
  int t = 0; /* the key's choices are checked: one matches */
  for (int k = 0; k < (int)(sizeof mri_tables / sizeof mri_tables[0]); ++k)
    if (strcmp(table, mri_tables[k].name) == 0) t = k;
  for (int k = 0; k < ts->nmod; ++k)
    if (ts->mod[k] == ts->coupling->module[MPM_ROLE_SOLID]) fast = k;
  const mpm_cycle cycle = mpm_cycle_joint(ts->grid, ts->mod, ts->nmod, ts->coupling);
  mpm_integrator *it = NULL;
  ts->type = &multirate_mri; /* from here on, also for the destroy after a failure */
  const int rc = mpm_integrator_new_multirate(&it, cfg, &cycle, fast, substeps, mri_tables[t].id);
  ts->content = it;
  return rc;
}

/* coupling.exchange = shared: what it needs, and the gas's follow cycles. */
static int want_shared(mpm_timescheme *ts, const mpm_config *cfg, const char *method,
                       const char *predictor) {
  const mpm_partitioned *pp = ts->content;
  if (strcmp(ts->coupling->type->name, "velocity") != 0)
    return mpm_config_fail(cfg, "coupling.exchange",
                           "shared advances the nodes both phases share as one velocity, which "
                           "is coupling.scheme = velocity; this scene uses %s: use held, or "
                           "coupling.scheme = velocity",
                           ts->coupling->type->name);
  if (strcmp(method, "usl") != 0)
    return mpm_config_fail(cfg, "coupling.exchange",
                           "shared takes the gas's nodal force of the step's first transfer, and "
                           "%s transfers twice: use held, or time.method = usl",
                           method);
  if (strcmp(predictor, "none") != 0)
    return mpm_config_fail(cfg, "coupling.predictor",
                           "predicts the held solid for the gas, and coupling.exchange = shared "
                           "holds no solid (the solid goes first): remove one of the two keys");
  if (pp->slow_substeps != 1)
    return mpm_config_fail(cfg, "coupling.slow_substeps",
                           "coupling.exchange = shared takes the gas in one step per coupling "
                           "step: remove the key or use coupling.exchange = held");
  return mpm_partitioned_want_shared(ts, cfg);
}

static int multirate_create(mpm_timescheme *ts, const mpm_config *cfg) {
  const char *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  /* MRIStep steps the gas (the slow partition) with its coupling table, never the method's:
   * ssprk2 would change the solid's substeps only, and name a gas step it is not. */
  if (strcmp(method, "ssprk2") == 0)
    return mpm_config_fail(
        cfg, "time.method",
        "ssprk2 steps the whole scene at one step, and coupling.time = "
        "multirate steps the gas with the classic update (usl, musl) or MRIStep's "
        "own coupling table (bs32 with time.adaptive = false); choose one of "
        "those, or coupling.time = monolithic");
  if (strcmp(method, "usl") != 0 && strcmp(method, "musl") != 0 && strcmp(method, "euler") != 0)
    return multirate_mri_create(ts, cfg, method);
  MPM_CALL(foreign_key(cfg, KEY_MRI_TABLE,
                       "is read with an ERK pair only (MRIStep); the classic update subcycles "
                       "with coupling.load: remove it or choose time.method = bs32"));
  MPM_CALL(mpm_partitioned_new(ts, cfg, "multirate"));
  mpm_partitioned *pp = ts->content;
  if (mpm_config_has(cfg, "coupling.substeps"))
    MPM_CALL(mpm_config_get_int(cfg, "coupling.substeps", &pp->substeps));
  MPM_CALL(mpm_config_get_int(cfg, "coupling.slow_substeps", &pp->slow_substeps));
  const char *load;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.load", &load));
  pp->interpolate = strcmp(load, "interpolated") == 0;
  if (pp->interpolate) MPM_CALL(mpm_interface_want_trend(pp->ifc));
  const char *predictor;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.predictor", &predictor));
  if (strcmp(predictor, "linear") == 0) MPM_CALL(mpm_interface_want_predictor(pp->ifc));
  const char *exchange;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.exchange", &exchange));
  if (strcmp(exchange, "shared") == 0) MPM_CALL(want_shared(ts, cfg, method, predictor));
  return 0;
}

/* More substeps than this in one coupling step (with coupling.substeps unset) means the fast
 * module's stable step has collapsed: the ratio of two stable modules' steps is 10-100. */
#define MULTIRATE_MAX_SUBSTEPS 1e4

/* A limit of 0 means none. */
static double limit(double h) {
  return h > 0 ? h : HUGE_VAL;
}

/* The coupling step from the two modules' CFL steps (before the stop time): the slow one's,
 * or m times the fast one's when coupling.substeps = m is smaller; with shared nodes at most
 * the gas's (it takes one step per coupling step). */
static double coupling_step(const mpm_partitioned *pp, double h_solid, double h_gas) {
  const double h_fast = fmin(h_solid, h_gas), h_slow = fmax(h_solid, h_gas);
  double H = pp->substeps > 0 ? fmin(h_slow, pp->substeps * h_fast) : h_slow;
  if (pp->shared) H = fmin(H, h_gas);
  return fmin(H, pp->dt_max);
}

/* The step loop's CFL step (its run budget and blow-up guard) is the coupling step. */
static int multirate_cfl_step(mpm_timescheme *ts, double *h) {
  double hs, hg;
  MPM_CALL(mpm_partitioned_cfl_steps(ts, &hs, &hg));
  hs = limit(hs), hg = limit(hg);
  const double H = coupling_step(ts->content, hs, hg);
  *h = isfinite(H) ? H : 0.0;
  return 0;
}

/* The substeps of the fast and slow modules in a coupling step from the current state, as
 * multirate_step takes them (m = 0 where the fast module's step collapsed: it refuses). */
static int multirate_work(mpm_timescheme *ts, double *advances, double *need, const char **key) {
  const mpm_partitioned *pp = ts->content;
  double hs, hg;
  MPM_CALL(mpm_partitioned_cfl_steps(ts, &hs, &hg));
  hs = limit(hs), hg = limit(hg);
  const double h_fast = fmin(hs, hg), H = coupling_step(pp, hs, hg);
  const double stable =
      isfinite(h_fast) && isfinite(H) ? fmax(ceil(H / h_fast * (1 - 1e-12)), 1.0) : 1.0;
  const double m = pp->substeps > 0 ? pp->substeps : stable;
  const double n = pp->slow_substeps > 0 ? pp->slow_substeps : m;
  *advances = fmax(m, n);
  /* the fast module needs what its stable step asks; the slow one, at most as many (its
   * substeps are an ablation of the coupling lag) */
  *need = n > m ? m : stable;
  *key = n > m ? "coupling.slow_substeps" : pp->substeps > 0 ? "coupling.substeps" : NULL;
  return 0;
}

static int multirate_step(mpm_timescheme *ts, double tstop, double *t, double *h) {
  const mpm_partitioned *pp = ts->content;
  double hs, hg;
  MPM_CALL(mpm_partitioned_cfl_steps(ts, &hs, &hg));
  hs = limit(hs), hg = limit(hg);
  const int solid_fast = hs < hg;
  const double h_fast = fmin(hs, hg);
  const double t0 = *t, rest = tstop - t0;
  const double H = fmin(coupling_step(pp, hs, hg), rest);
  int m = pp->substeps;
  if (m == 0) {
    const double need = isfinite(h_fast) ? fmax(1.0, ceil(H / h_fast * (1 - 1e-12))) : 1.0;
    if (need > MULTIRATE_MAX_SUBSTEPS)
      MPM_FAIL(MPM_ERR_UNPHYSICAL,
               "the run blew up at t = %.6g: the %s module's stable step %.3g s is %.3g times "
               "below the coupling step %.3g s (its particles have reached speeds no stable scene "
               "has); the blow-up guard sees coupling steps only. Reduce time.cfl, refine the "
               "grid, or check the scene near the interface",
               t0, solid_fast ? "solid" : "gas", h_fast, need, H);
    m = (int)need;
  }
  const int n = pp->slow_substeps > 0 ? pp->slow_substeps : m;
  mpm_log(
      MPM_LOG_TRACE,
      "multirate at t = %.9g: stable steps solid %.4g s, gas %.4g s; H %.4g s, %d + %d substeps",
      t0, hs, hg, H, solid_fast ? n : m, solid_fast ? m : n);
  const double t1 = H < rest ? t0 + H : tstop;
  if (pp->shared) { /* the solid first, then the gas pays what it received */
    MPM_CALL(mpm_partitioned_share(ts, t0));
    MPM_CALL(mpm_partitioned_advance_solid(ts, t0, t1, solid_fast ? m : n));
    MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, 1));
    MPM_CALL(mpm_interface_rehome(pp->ifc, ts->coupling->owned));
  } else {
    MPM_CALL(mpm_partitioned_hold(ts, t0));
    MPM_CALL(mpm_partitioned_advance_gas(ts, t0, t1, solid_fast ? n : m));
    MPM_CALL(mpm_partitioned_advance_solid(ts, t0, t1, solid_fast ? m : n));
  }
  MPM_CALL(mpm_partitioned_end(ts, t0, t1));
  *t = t1, *h = t1 - t0;
  return 0;
}

static const mpm_timescheme_ops multirate_ops = {
    .create = multirate_create,
    .destroy = mpm_partitioned_destroy,
    .start = mpm_partitioned_start,
    .step = multirate_step,
    .resize = mpm_partitioned_resize,
    .cfl_step = multirate_cfl_step,
    .work = multirate_work,
    .next_step = mpm_partitioned_next_step,
    .counts = mpm_partitioned_counts,
    .record = mpm_partitioned_record,
    .save = mpm_partitioned_save,
    .restore = mpm_partitioned_restore,
};

const mpm_timescheme_type timescheme_multirate = {
    .name = "multirate",
    .help = "each module at its own rate: the fast one substeps inside the slow one's step "
            "(coupling.substeps, coupling.load, coupling.slow_substeps; classic update only)",
    .keys = multirate_keys,
    .nkeys = (int)(sizeof multirate_keys / sizeof multirate_keys[0]),
    .ops = &multirate_ops,
};
