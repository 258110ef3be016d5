/* The temporal coupling scheme object: its key, construction and dispatch (see
 * mpm_timescheme.h). */
#include "mpm_timescheme.h"

#include "mpm_error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* "monolithic|staggered|...", built from the register when the schema is added. */
static char g_choices[256];
static char g_help[1024];
static mpm_key_spec g_time_key[] = {
    {"coupling.time", MPM_KEY_ENUM, "monolithic", 0, 0, 0, 0, g_choices, g_help, 0, NULL},
};

int mpm_timescheme_add_schema(mpm_config *cfg) {
  int n;
  const mpm_timescheme_type *const *types = mpm_timescheme_types(&n);
  const char *names[16], *helps[16];
  for (int k = 0; k < n && k < 16; ++k) names[k] = types[k]->name, helps[k] = types[k]->help;
  mpm_config_enum_text(g_choices, sizeof g_choices, g_help, sizeof g_help,
                       "how the modules advance in time together:", names, helps, n < 16 ? n : 16);
  MPM_CALL(mpm_config_add_schema(cfg, g_time_key, 1));
  for (int k = 0; k < n; ++k)
    if (types[k]->nkeys) MPM_CALL(mpm_config_add_schema(cfg, types[k]->keys, types[k]->nkeys));
  return 0;
}

/* A key of a scheme not chosen, set away from its default, is a mistake worth naming. */
static int check_foreign_keys(const mpm_config *cfg, const mpm_timescheme_type *chosen) {
  int n;
  const mpm_timescheme_type *const *types = mpm_timescheme_types(&n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; types[k] != chosen && j < types[k]->nkeys; ++j)
      if (mpm_config_set_off_default(cfg, &types[k]->keys[j]))
        return mpm_config_fail(cfg, types[k]->keys[j].key,
                               "is a key of the %s time scheme, and coupling.time = %s does not "
                               "read it; remove it or choose coupling.time = %s",
                               types[k]->name, chosen->name, types[k]->name);
  return 0;
}

int mpm_timescheme_new(mpm_timescheme **tsp, const mpm_config *cfg, mpm_grid *grid,
                       mpm_module **modules, int nmodules, mpm_coupling *coupling) {
  const char *name;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &name));
  int n;
  const mpm_timescheme_type *const *types = mpm_timescheme_types(&n), *type = NULL;
  for (int k = 0; k < n; ++k)
    if (strcmp(types[k]->name, name) == 0) type = types[k];
  if (!type) return mpm_config_fail(cfg, "coupling.time", "unknown time scheme '%s'", name);
  MPM_CALL(check_foreign_keys(cfg, type));
  mpm_timescheme *ts;
  MPM_ALLOC(ts, 1);
  *tsp = ts;
  *ts = (mpm_timescheme){
      .type = type, .grid = grid, .mod = modules, .nmod = nmodules, .coupling = coupling};
  int rc = mpm_config_get_real(cfg, "time.dt_max", &ts->dt_max);
  if (!rc) rc = type->ops->create(ts, cfg);
  if (rc) {
    mpm_timescheme_destroy(tsp);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  return 0;
}

void mpm_timescheme_destroy(mpm_timescheme **tsp) {
  if (!tsp || !*tsp) return;
  if ((*tsp)->type->ops->destroy) (*tsp)->type->ops->destroy(*tsp);
  free(*tsp);
  *tsp = NULL;
}

int mpm_timescheme_start(mpm_timescheme *ts, double t, double h0) {
  return ts->type->ops->start(ts, t, h0);
}

int mpm_timescheme_step(mpm_timescheme *ts, double tstop, double *t, double *h) {
  return ts->type->ops->step(ts, tstop, t, h);
}

int mpm_timescheme_resize(mpm_timescheme *ts, double t) {
  return ts->type->ops->resize(ts, t);
}

/* Every scheme caps its steps by time.dt_max; a CFL step that did not would make a small
 * dt_max look like a collapse to the blow-up guard and hide it from the budget. */
int mpm_timescheme_cfl_step(mpm_timescheme *ts, double *h) {
  MPM_CALL(ts->type->ops->cfl_step(ts, h));
  if (ts->dt_max > 0 && !(*h > 0 && *h <= ts->dt_max)) *h = ts->dt_max;
  return 0;
}

int mpm_timescheme_work(mpm_timescheme *ts, double *advances, double *need, const char **key) {
  *advances = 1, *key = NULL;
  MPM_CALL(ts->type->ops->work ? ts->type->ops->work(ts, advances, need, key) : 0);
  if (!ts->type->ops->work) *need = 1;
  return 0;
}

double mpm_timescheme_next_step(const mpm_timescheme *ts) {
  return ts->type->ops->next_step(ts);
}

void mpm_timescheme_counts(const mpm_timescheme *ts, long *steps, long *rhs, long *fails,
                           long *retries) {
  ts->type->ops->counts(ts, steps, rhs, fails, retries);
}

int mpm_timescheme_record(mpm_timescheme *ts, double t, mpm_coupling_record *out) {
  if (ts->type->ops->record) return ts->type->ops->record(ts, t, out);
  return mpm_coupling_step_record(ts->coupling, t, out);
}

int mpm_timescheme_save(mpm_timescheme *ts, mpm_particles **p, const char **name) {
  *p = NULL, *name = NULL;
  return ts->type->ops->save ? ts->type->ops->save(ts, p, name) : 0;
}

int mpm_timescheme_restore(mpm_timescheme *ts, mpm_checkpoint *ck) {
  return ts->type->ops->restore ? ts->type->ops->restore(ts, ck) : 0;
}
