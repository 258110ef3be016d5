/* The run's budget (see mpm_budget.h). */
#include "mpm_budget.h"

#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

const mpm_key_spec mpm_budget_keys[] = {
    {"run.max_steps", MPM_KEY_REAL, "1e8", 1, HUGE_VAL, 0, 0, NULL,
     "refuse a run whose estimated step count (time to run / starting step, times the "
     "substeps or the most sub-iterations in each step) is larger; raise it for a run that "
     "really needs more",
     0, "-"},
    {"output.max_gb", MPM_KEY_REAL, "100", 0, HUGE_VAL, 0, 0, NULL,
     "refuse a run whose estimated snapshots and checkpoints exceed this many GB; raise it "
     "for a run that really writes more",
     0, "GB"},
    {"output.max_files", MPM_KEY_REAL, "100000", 1, HUGE_VAL, 0, 0, NULL,
     "refuse a run that would write more snapshots and checkpoints than this", 0, "-"},
};
const int mpm_budget_nkeys = (int)(sizeof mpm_budget_keys / sizeof mpm_budget_keys[0]);

/* What b->work counts, as a message says it. */
static const char *work_noun(const mpm_budget *b) {
  if (!b->work_key) return "substeps of the fast module, as many as its stable step needs";
  if (strcmp(b->work_key, "coupling.iterations") == 0) return "sub-iterations at most";
  if (strcmp(b->work_key, "coupling.slow_substeps") == 0) return "substeps of the slow module";
  return "substeps of the fast module";
}

/* Substeps beyond this many times what stability needs (and beyond this many in all) only
 * shrink the fast module's step far below its stable one: its time error was already below
 * the coupling's at the stable step (bench/results/multirate_substeps.md: 16 times the
 * substeps the ratio gives, 96 against 6, change the error by 1 % and cost 8 times as much).
 * Sweeps like that one stay well inside; at 10,000 on the shock panel each coupling step took
 * 20 s on a busy machine, the run about 46 hours. */
#define MPM_BUDGET_OVERSTEP 100.0

/* Refuse substeps that do nothing but cost (see MPM_BUDGET_OVERSTEP). Only before a new run: a
 * restart cannot change coupling.*, and the stable ratio moves as the flow develops, so a run
 * accepted at its start is never refused halfway. */
static int check_overstep(const mpm_config *cfg, const mpm_budget *b) {
  const double need = fmax(b->need, 1.0), most = MPM_BUDGET_OVERSTEP * need;
  if (b->restart || !b->work_key || b->work <= most || b->work <= MPM_BUDGET_OVERSTEP) return 0;
  return mpm_config_fail(cfg, b->work_key,
                         "%.6g substeps are %.3g times the %.3g that the fast module's stable "
                         "step needs; more than %.3g times only shrink a step below what "
                         "accuracy needs and multiply the cost: give at most %.6g",
                         b->work, b->work / need, need, MPM_BUDGET_OVERSTEP, floor(most));
}

/* Refuse a step count over run.max_steps (stable: steps at the planned step; all: with the
 * output times), naming the key that drives it. */
static int check_steps(const mpm_config *cfg, const mpm_budget *b, double stable, double all,
                       double max_steps) {
  const double span = b->t_end - b->t, work = b->work;
  double dt_max;
  MPM_CALL(mpm_config_get_real(cfg, "time.dt_max", &dt_max));
  if (stable > max_steps && dt_max > 0 && b->h0 >= dt_max * (1 - 1e-12))
    return mpm_config_fail(cfg, "time.dt_max",
                           "this run would take about %.3g steps (%.6g s to run at time.dt_max = "
                           "%.3g s, which caps the step below the stable one), more than "
                           "run.max_steps = %.3g; raise time.dt_max (0: no cap) or shorten "
                           "time.t_end, or raise run.max_steps if you mean it",
                           stable, span, dt_max, max_steps);
  if (stable > max_steps)
    return mpm_config_fail(cfg, "time.t_end",
                           "this run would take about %.3g steps (%.6g s to run at the starting "
                           "stable step of %.3g s), more than run.max_steps = %.3g; shorten "
                           "time.t_end or coarsen grid.dx, or raise run.max_steps if you mean it",
                           stable, span, b->h0, max_steps);
  if (stable * work > max_steps)
    return mpm_config_fail(cfg, b->work_key ? b->work_key : "time.t_end",
                           "this run would take about %.3g steps of its busiest module: %.3g "
                           "steps of %.3g s, each with %.3g %s, more than run.max_steps = %.3g; "
                           "%s%s, or raise run.max_steps if you mean it",
                           stable * work, stable, b->h0, work, work_noun(b), max_steps,
                           b->work_key ? "lower " : "shorten time.t_end",
                           b->work_key ? b->work_key : "");
  if (all * work > max_steps) /* the outputs' times force the steps */
    return mpm_config_fail(cfg, "output.interval",
                           "this run would take about %.3g steps, %.3g of them to reach output "
                           "and checkpoint times%s, more than run.max_steps = %.3g; lengthen "
                           "output.interval or output.checkpoint_interval, or raise "
                           "run.max_steps if you mean it",
                           all * work, (all - stable) * work,
                           work > 1 ? " (counting the substeps or sub-iterations)" : "", max_steps);
  return 0;
}

int mpm_budget_check(const mpm_config *cfg, const mpm_budget *b, double *estimate) {
  double max_steps, max_gb, max_files;
  MPM_CALL(mpm_config_get_real(cfg, "run.max_steps", &max_steps));
  MPM_CALL(mpm_config_get_real(cfg, "output.max_gb", &max_gb));
  MPM_CALL(mpm_config_get_real(cfg, "output.max_files", &max_files));
  const double span = b->t_end - b->t, nout = floor(span / b->out_interval * (1 + 1e-12));
  const double nck = isfinite(b->ckpt_interval) ? floor(span / b->ckpt_interval * (1 + 1e-12)) : 0;
  const double stable = b->h0 > 0 && isfinite(b->h0) ? span / b->h0 : 0;
  const double steps = stable + nout + nck; /* every output time ends a step too */
  const double nsnap = b->snapshots ? nout + 1 : 0, nckpt = nck + 1; /* and the final one */
  const double gb = (nsnap + nckpt) * b->bytes / 1e9;
  const char *interval = nsnap > nckpt ? "output.interval" : "output.checkpoint_interval";
  if (stable > max_steps) return check_steps(cfg, b, stable, steps, max_steps);
  MPM_CALL(check_overstep(cfg, b));
  if (nsnap + nckpt > max_files)
    return mpm_config_fail(cfg, interval,
                           "this run would write about %.3g snapshots and %.3g checkpoints "
                           "(%.3g GB), more than output.max_files = %.3g; lengthen "
                           "output.interval or output.checkpoint_interval, or raise "
                           "output.max_files if you mean it",
                           nsnap, nckpt, gb, max_files);
  if (gb > max_gb)
    return mpm_config_fail(cfg, interval,
                           "this run would write about %.3g GB (%.3g snapshots and %.3g "
                           "checkpoints of %.3g MB), more than output.max_gb = %.3g; lengthen "
                           "output.interval or output.checkpoint_interval, or raise "
                           "output.max_gb if you mean it",
                           gb, nsnap, nckpt, b->bytes / 1e6, max_gb);
  MPM_CALL(check_steps(cfg, b, stable, steps, max_steps));
  *estimate = steps;
  char each[160] = "";
  if (b->work > 1)
    snprintf(each, sizeof each, ", each with %.3g %s (%.3g in all)", b->work, work_noun(b),
             steps * b->work);
  mpm_log(
      MPM_LOG_INFO,
      "estimate: about %.3g steps%s (starting stable step %.6g s; refined after the first steps), "
      "%.3g snapshot%s and %.3g checkpoint%s, %.3g GB",
      steps, each, b->h0, nsnap, nsnap == 1 ? "" : "s", nckpt, nckpt == 1 ? "" : "s", gb);
  return 0;
}
