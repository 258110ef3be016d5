/* Temporal coupling schemes: how the modules advance in time together. An object with an ops
 * table, registered by name (mpm_timescheme_register.c) and chosen with
 * `[coupling] time = NAME`, like the spatial schemes (mpm_coupling.h): a new scheme is one file
 * that exports its type plus one line in the register.
 *
 * The ops are the integrator's public face, what the step loop (mpm_sim.c) calls: start, step,
 * resize, the CFL step, the next step, the counters, and the interface record of the step just
 * taken. A scheme owns one ARKODE integrator (mpm_integrator.h) or more, each over the MPM cycle
 * of a subset of the modules (mpm_cycle.h), and decides the order of their advances and what
 * they exchange (mpm_interface.h). Built-in:
 *   monolithic  one integrator over every module, one step for both (joint cycle);
 *   staggered   one integrator per module, exchanging once per coupling step;
 *   multirate   the fast module substeps inside the slow one's step: with the classic update
 *               one integrator per module (mpm_partitioned.h), with an ERK pair one MRIStep
 *               integrator over both. */
#ifndef MPM_TIMESCHEME_H
#define MPM_TIMESCHEME_H

#include "mpm_config.h"
#include "mpm_coupling.h"
#include "mpm_module.h"
#include "mpm_output.h"

typedef struct mpm_timescheme mpm_timescheme;

typedef struct mpm_timescheme_ops {
  /* Read the scheme's keys, check what it is combined with, build its integrators. */
  int (*create)(mpm_timescheme *ts, const mpm_config *cfg);
  void (*destroy)(mpm_timescheme *ts);
  /* (Re)start at (t, current particle state) with first step h0 (0: the scheme chooses). */
  int (*start)(mpm_timescheme *ts, double t, double h0);
  /* Take one accepted (coupling) step, not past tstop. *t is the new time, *h the step. */
  int (*step)(mpm_timescheme *ts, double tstop, double *t, double *h);
  /* The particle sets changed (count, order or storage). Collective. */
  int (*resize)(mpm_timescheme *ts, double t);
  /* time.cfl times the stability limit of the current state (0: no limit). Collective. */
  int (*cfl_step)(mpm_timescheme *ts, double *h);
  /* The advances the busiest module makes in one coupling step from the current state: its
   * substeps, or the most sub-iterations a step may take (the run's budget counts them), and
   * the key that sets that number (NULL: the scene's own stable steps do); and how many of
   * those advances stability needs (*need, as many as *advances unless a key asks for more).
   * Optional: 1, 1, NULL. Collective. */
  int (*work)(mpm_timescheme *ts, double *advances, double *need, const char **key);
  double (*next_step)(const mpm_timescheme *ts);
  void (*counts)(const mpm_timescheme *ts, long *steps, long *rhs, long *fails, long *retries);
  /* The interface record of the step that reached t, reduced over the ranks. Optional: the
   * coupling's own record of its latest RHS (mpm_coupling_step_record). Collective. */
  int (*record)(mpm_timescheme *ts, double t, mpm_coupling_record *out);
  /* The scheme's own state for a checkpoint, as a particle set to store under *name (the
   * caller destroys it). Optional: none. Collective. */
  int (*save)(mpm_timescheme *ts, mpm_particles **p, const char **name);
  /* Read back what save stored. Optional. Collective. */
  int (*restore)(mpm_timescheme *ts, mpm_checkpoint *ck);
} mpm_timescheme_ops;

typedef struct mpm_timescheme_type {
  const char *name;
  const char *help;         /* one line for the key's documentation */
  const mpm_key_spec *keys; /* the scheme's own [coupling] keys (may be NULL) */
  int nkeys;
  const mpm_timescheme_ops *ops;
} mpm_timescheme_type;

/* Between the substeps of one module inside a coupling step (multirate): what the step loop
 * does between steps for that module alone, particles entering and leaving through open faces
 * and migrating to their owners, so that a module substepping many times keeps its particles in
 * their boxes. Sets *changed when the module's particle set changed on this rank. */
typedef int (*mpm_timescheme_between)(void *ctx, mpm_module *m, double t, double h, int *changed);

struct mpm_timescheme {
  const mpm_timescheme_type *type;
  void *content;
  mpm_grid *grid;
  mpm_module **mod;
  int nmod;
  mpm_coupling *coupling;         /* NULL: one phase, or the modules do not interact */
  mpm_timescheme_between between; /* set by the step loop (may be NULL) */
  void *between_ctx;
  double dt_max; /* time.dt_max (0: none), which caps the CFL step */
};

/* The ops of a scheme that is one integrator (mpm_integrator.h) in ts->content
 * (timescheme_monolithic.c); their create builds the monolithic one. */
extern const mpm_timescheme_ops timescheme_monolithic_ops;

/* The registered types, monolithic first; count in *n. */
const mpm_timescheme_type *const *mpm_timescheme_types(int *n);

/* coupling.time and every registered scheme's keys. */
int mpm_timescheme_add_schema(mpm_config *cfg);

/* Build the scheme the case names over these modules and coupling (kept alive by the caller).
 * A scheme that needs two coupled phases, or a key of a scheme not chosen, is an input error. */
int mpm_timescheme_new(mpm_timescheme **ts, const mpm_config *cfg, mpm_grid *grid,
                       mpm_module **modules, int nmodules, mpm_coupling *coupling);
void mpm_timescheme_destroy(mpm_timescheme **ts);

/* The ops, dispatched (see mpm_timescheme_ops). */
int mpm_timescheme_start(mpm_timescheme *ts, double t, double h0);
int mpm_timescheme_step(mpm_timescheme *ts, double tstop, double *t, double *h);
int mpm_timescheme_resize(mpm_timescheme *ts, double t);
/* The scheme's CFL step capped by time.dt_max: the step it plans from the current state (the
 * run's budget and the blow-up guard measure against it). 0: nothing limits it. */
int mpm_timescheme_cfl_step(mpm_timescheme *ts, double *h);
/* See mpm_timescheme_ops.work. */
int mpm_timescheme_work(mpm_timescheme *ts, double *advances, double *need, const char **key);
double mpm_timescheme_next_step(const mpm_timescheme *ts);
void mpm_timescheme_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                           long *retries);
int mpm_timescheme_record(mpm_timescheme *ts, double t, mpm_coupling_record *out);
/* *p is NULL for a scheme without state of its own. */
int mpm_timescheme_save(mpm_timescheme *ts, mpm_particles **p, const char **name);
int mpm_timescheme_restore(mpm_timescheme *ts, mpm_checkpoint *ck);

#endif
