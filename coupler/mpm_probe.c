/* Probes (see mpm_probe.h). */
#include "mpm_probe.h"

#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

const mpm_key_spec mpm_probe_keys[] = {
    {"probe.*.point", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "follow the particle nearest to this point at t = 0 (probes.csv: displacement, velocity)", 0,
     "m"},
    {"probe.*.phase", MPM_KEY_ENUM, "solid", 0, 0, 0, 0, "solid|fluid",
     "whose particle the probe follows", 0, NULL},
};
const int mpm_probe_nkeys = (int)(sizeof mpm_probe_keys / sizeof mpm_probe_keys[0]);

/* Global (distance, id) minimum: the nearest particle, ties to the lowest id. */
static int nearest(const mpm_module *m, const double *x, int dim, MPI_Comm comm, double *id) {
  const mpm_particles *p = m->particles;
  double best[2] = {HUGE_VAL, HUGE_VAL};
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double r2 = 0.0;
    for (int d = 0; d < dim; ++d) {
      const double u = mpm_particles_comp(p, 0, d)[i] - x[d];
      r2 += u * u;
    }
    if (r2 < best[0] || (r2 == best[0] && (double)p->id[i] < best[1]))
      best[0] = r2, best[1] = (double)p->id[i];
  }
  double all[2];
  MPM_CALL_MPI(MPI_Allreduce(&best[0], &all[0], 1, MPI_DOUBLE, MPI_MIN, comm));
  if (best[0] != all[0]) best[1] = HUGE_VAL;
  MPM_CALL_MPI(MPI_Allreduce(&best[1], &all[1], 1, MPI_DOUBLE, MPI_MIN, comm));
  *id = all[1];
  return 0;
}

/* Position and velocity of particle `id` (NaN if no rank holds it). */
static int locate(const mpm_module *m, double id, int dim, double *x, double *v) {
  const mpm_particles *p = m->particles;
  double local[2 * MPM_MAX_DIM + 1] = {0}, sum[2 * MPM_MAX_DIM + 1];
  for (mpm_lidx i = 0; i < p->n; ++i) {
    if ((double)p->id[i] != id) continue;
    for (int d = 0; d < dim; ++d) {
      local[d] = mpm_particles_comp(p, 0, d)[i];
      local[dim + d] = mpm_particles_comp(p, 1, d)[i];
    }
    local[2 * dim] = 1.0;
    break;
  }
  MPM_CALL_MPI(MPI_Allreduce(local, sum, 2 * dim + 1, MPI_DOUBLE, MPI_SUM, m->grid->comm));
  for (int d = 0; d < dim; ++d) {
    x[d] = sum[2 * dim] == 1.0 ? sum[d] : NAN;
    v[d] = sum[2 * dim] == 1.0 ? sum[dim + d] : NAN;
  }
  return 0;
}

int mpm_probes_new(mpm_probes *pr, const mpm_config *cfg, mpm_module **mod, int nmod) {
  const char *const *names;
  int n;
  memset(pr, 0, sizeof *pr);
  MPM_CALL(mpm_config_instances(cfg, "probe", &names, &n));
  if (n > MPM_PROBE_MAX) {
    char key[128];
    snprintf(key, sizeof key, "probe.%s.point", names[MPM_PROBE_MAX]);
    return mpm_config_fail(cfg, key, "at most %d probes", MPM_PROBE_MAX);
  }
  for (int k = 0; k < n; ++k) {
    char key[128], vkey[128];
    const char *phase;
    double x[3];
    int nx;
    snprintf(key, sizeof key, "probe.%s.point", names[k]);
    snprintf(vkey, sizeof vkey, "probe.%s.phase", names[k]);
    MPM_CALL(mpm_config_get_reals(cfg, key, x, 3, &nx));
    MPM_CALL(mpm_config_get_string(cfg, vkey, &phase));
    const mpm_role role = strcmp(phase, "fluid") == 0 ? MPM_ROLE_FLUID : MPM_ROLE_SOLID;
    int which = -1;
    for (int j = 0; j < nmod; ++j)
      if (mod[j]->role == role) which = j;
    if (which < 0)
      return mpm_config_fail(cfg, vkey, "the scene has no %s to probe; add one or change %s", phase,
                             vkey);
    pr->dim = mod[which]->grid->dim;
    if (nx != pr->dim)
      return mpm_config_fail(cfg, key, "needs %d coordinates, got %d", pr->dim, nx);
    snprintf(pr->name[k], sizeof pr->name[k], "%s", names[k]);
    pr->module[k] = which;
    MPM_CALL(nearest(mod[which], x, pr->dim, mod[which]->grid->comm, &pr->id[k]));
    if (!isfinite(pr->id[k]))
      return mpm_config_fail(cfg, key, "the %s has no particles to probe", phase);
    double v[MPM_MAX_DIM];
    MPM_CALL(locate(mod[which], pr->id[k], pr->dim, pr->x0[k], v));
    pr->n = k + 1;
  }
  return 0;
}

int mpm_probes_attrs(mpm_probes *pr, const char **names, double *values, int max) {
  int c = 0;
  for (int k = 0; k < pr->n && c + 1 + pr->dim <= max; ++k) {
    snprintf(pr->attr[c], sizeof pr->attr[c], "probe.%s.id", pr->name[k]);
    names[c] = pr->attr[c], values[c++] = pr->id[k];
    for (int d = 0; d < pr->dim; ++d) {
      snprintf(pr->attr[c], sizeof pr->attr[c], "probe.%s.x0_%c", pr->name[k], "xyz"[d]);
      names[c] = pr->attr[c], values[c++] = pr->x0[k][d];
    }
  }
  return c;
}

void mpm_probes_restore(mpm_probes *pr, const mpm_checkpoint *ck) {
  const char *names[MPM_PROBE_MAX * (1 + MPM_MAX_DIM)];
  double val[MPM_PROBE_MAX * (1 + MPM_MAX_DIM)];
  const int na = mpm_probes_attrs(pr, names, val, MPM_PROBE_MAX * (1 + MPM_MAX_DIM));
  for (int a = 0; a < na; ++a) {
    if (!mpm_checkpoint_attr_optional(ck, names[a], &val[a])) continue;
    const int k = a / (1 + pr->dim), q = a % (1 + pr->dim);
    if (q == 0)
      pr->id[k] = val[a];
    else
      pr->x0[k][q - 1] = val[a];
  }
}

int mpm_probes_columns(mpm_probes *pr, const char **cols) {
  int c = 0;
  cols[c++] = "t";
  for (int k = 0; k < pr->n; ++k)
    for (int q = 0; q < 2 * pr->dim; ++q) {
      char *s = pr->col[c];
      snprintf(s, sizeof pr->col[c], "%s_%c%c", pr->name[k], q < pr->dim ? 'u' : 'v',
               "xyz"[q % pr->dim]);
      cols[c++] = s;
    }
  return c;
}

int mpm_probes_row(const mpm_probes *pr, mpm_module **mod, double t, double *row) {
  int c = 0;
  row[c++] = t;
  for (int k = 0; k < pr->n; ++k) {
    double x[MPM_MAX_DIM], v[MPM_MAX_DIM];
    MPM_CALL(locate(mod[pr->module[k]], pr->id[k], pr->dim, x, v));
    for (int d = 0; d < pr->dim; ++d) row[c++] = x[d] - pr->x0[k][d];
    for (int d = 0; d < pr->dim; ++d) row[c++] = v[d];
  }
  return 0;
}
