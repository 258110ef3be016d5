/* The run's budget: a run whose step count or output volume is absurd (a mistyped t_end,
 * interval or dx) is refused before it starts, with the estimate and the key to change, not
 * once the disk is full or after years of steps. `check` applies it too.
 *
 * Estimates: steps = (t_end - t) / h0, with h0 the step the time scheme plans from the
 * starting state (time.cfl of its stable step, capped by time.dt_max), plus a step to each
 * output and checkpoint time (they end steps); files = the snapshots and the checkpoints (and
 * the final one); bytes = files times the size of one (every particle's fields, and the grid
 * fields where written). run.max_steps bounds the advances of the busiest module: the steps
 * times its substeps in each (multirate) or the most sub-iterations a step may take (strong
 * coupling), so that coupling.substeps = 1e4 is not counted as one step. Limits:
 * run.max_steps, output.max_files, output.max_gb; a user who means it raises them. A refusal
 * names the key that drives the count: time.dt_max when it sets the step, the substep or
 * sub-iteration key when they multiply a count that fits, else time.t_end.
 *
 * The starting stable step is all that is known before the run, and often not the step the
 * run settles to: the artificial viscosity that limits the step at a shock appears only with
 * the first step, and an adaptive pair's error control may hold it lower (measured: Sod 0.27,
 * the main job 0.5 of it). The run refines its estimate after its first steps
 * (mpm_sim.c, refine_estimate); the budget keeps this one, which counts fewer steps than the
 * run takes, so it never refuses a run that would fit, except by counting every sub-iteration
 * strong coupling may take (a step that never converges takes them all). */
#ifndef MPM_BUDGET_H
#define MPM_BUDGET_H

#include "mpm_config.h"

extern const mpm_key_spec mpm_budget_keys[];
extern const int mpm_budget_nkeys;

typedef struct mpm_budget {
  int restart;          /* from a checkpoint: keys outside time.*, run.*, output.* are fixed */
  double t, t_end;      /* the time to run */
  double h0;            /* planned step of the starting state (0 or inf: nothing limits it) */
  double work;          /* advances of the busiest module per step (>= 1; mpm_timescheme_work) */
  double need;          /* of those, the advances stability needs (<= work) */
  const char *work_key; /* the key that sets work, or NULL */
  double out_interval;  /* time between snapshots (> 0) */
  double ckpt_interval; /* time between checkpoints (inf: only the final one) */
  int snapshots;        /* are snapshots written? */
  double bytes;         /* size of one snapshot or checkpoint */
} mpm_budget;

/* 0, the estimated step count (steps of the time scheme, without their substeps) in *estimate
 * and an "estimate:" log line, or an input error naming the key to change. Every rank must
 * pass the same values. */
int mpm_budget_check(const mpm_config *cfg, const mpm_budget *b, double *estimate);

#endif
