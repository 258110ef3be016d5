/* `monolithic`: one ARKODE integrator over the MPIManyVector of every module, one step for all
 * of them; the joint MPM cycle is its RHS, so the spatial scheme acts inside every stage. The
 * default, and the reference the partitioned schemes are measured against. Its ops (all but
 * create) serve any scheme that is one mpm_integrator in ts->content: `multirate` with an ERK
 * pair, whose integrator is MRIStep's (timescheme_multirate.c). */
#include "mpm_integrator.h"
#include "mpm_timescheme.h"

static int mono_create(mpm_timescheme *ts, const mpm_config *cfg) {
  const mpm_cycle cycle = mpm_cycle_joint(ts->grid, ts->mod, ts->nmod, ts->coupling);
  mpm_integrator *it = NULL;
  const int rc = mpm_integrator_new(&it, cfg, &cycle);
  ts->content = it;
  return rc;
}

static void mono_destroy(mpm_timescheme *ts) {
  mpm_integrator *it = ts->content;
  mpm_integrator_destroy(&it);
}

static int mono_start(mpm_timescheme *ts, double t, double h0) {
  return mpm_integrator_start(ts->content, t, h0);
}

static int mono_step(mpm_timescheme *ts, double tstop, double *t, double *h) {
  return mpm_integrator_step(ts->content, tstop, t, h);
}

static int mono_resize(mpm_timescheme *ts, double t) {
  return mpm_integrator_resize(ts->content, t);
}

static int mono_cfl_step(mpm_timescheme *ts, double *h) {
  return mpm_integrator_cfl_step(ts->content, h);
}

/* MRIStep's fast substeps, when coupling.substeps sets them (otherwise counted as 1: the
 * budget's estimate is a lower bound). */
static int mono_work(mpm_timescheme *ts, double *advances, double *need, const char **key) {
  const int m = mpm_integrator_substeps(ts->content);
  *advances = m > 0 ? m : 1, *key = m > 0 ? "coupling.substeps" : NULL;
  *need = *advances; /* MRIStep's fast step is not planned here: no claim */
  return 0;
}

static double mono_next_step(const mpm_timescheme *ts) {
  return mpm_integrator_next_step(ts->content);
}

static void mono_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                        long *retries) {
  mpm_integrator_counts(ts->content, steps, rhs, fails, retries);
}

const mpm_timescheme_ops timescheme_monolithic_ops = {
    .create = mono_create,
    .destroy = mono_destroy,
    .start = mono_start,
    .step = mono_step,
    .resize = mono_resize,
    .cfl_step = mono_cfl_step,
    .work = mono_work,
    .next_step = mono_next_step,
    .counts = mono_counts,
};

const mpm_timescheme_type timescheme_monolithic = {
    .name = "monolithic",
    .help = "one integrator over both modules, one step for both; the default",
    .ops = &timescheme_monolithic_ops,
};
