/* Seeding the gas: each [gas.NAME] section fills its [geometry.NAME] region with particles on
 * the cell-centred lattice of fluid.ppc points per cell and direction, in the state the
 * section gives (density, pressure, velocity; constants or expressions in x, y, z).
 *
 * Overlaps: a lattice point belongs to the first section, in case-file order, whose region
 * contains it; later sections skip it. So a uniform background region listed last fills
 * whatever the others leave. Each section takes a fresh block of ids as wide as the seeding
 * lattice, so an id does not depend on the number of ranks. No particle is seeded inside an
 * obstacle (phi < 0).
 *
 * Refinement (fluid_seed_refined, after the sim built the hierarchy): the level-0 particles
 * inside the finer regions go, and each level l >= 1 seeds its own region less the finer ones
 * on its lattice: ppc points per axis in each level-l span, of volume (h_l / ppc)^dim, with the
 * same first-section-wins rule. A level-0 span is whole for an even ppc, so the region's
 * level-0 particles leave no part behind. On more than one rank every rank walks the level's
 * whole lattice (the ids follow its order, whatever the ranks) and keeps the points it owns. */
#include "fluid_eos.h"
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_expr.h"
#include "mpm_geometry.h"
#include "mpm_hier.h"
#include "mpm_hier_seed.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The initial state of one section. A field expression, when given, replaces the constant. */
typedef struct gas_state {
  const char *section; /* "gas.NAME" */
  mpm_region *region;
  double rho, p, v[3];
  mpm_expr *rho_f, *p_f, *v_f;
} gas_state;

static void key_of(char *key, size_t size, const char *section, const char *name) {
  snprintf(key, size, "%s.%s", section, name);
}

/* A quantity given either as a constant (key NAME) or as an expression (NAME_field). */
static int read_either(const mpm_config *cfg, const char *section, const char *name, int ncomp,
                       double *value, mpm_expr **field) {
  char key[160], fkey[160];
  key_of(key, sizeof key, section, name);
  snprintf(fkey, sizeof fkey, "%s.%s_field", section, name);
  const int has = mpm_config_has(cfg, key), has_f = mpm_config_has(cfg, fkey);
  if (has && has_f)
    return mpm_config_fail(cfg, fkey, "give either %s or %s_field, not both", name, name);
  if (has_f) return mpm_expr_from_config(field, cfg, fkey, ncomp);
  if (ncomp == 1 && !has)
    return mpm_config_fail(cfg, key, "[%s] needs %s (a constant) or %s_field (an expression)",
                           section, name, name);
  if (ncomp == 1) return mpm_config_get_real(cfg, key, value);
  int count;
  MPM_CALL(mpm_config_get_reals(cfg, key, value, 3, &count));
  if (count < ncomp) return mpm_config_fail(cfg, key, "needs %d values, got %d", ncomp, count);
  return 0;
}

static int read_state(gas_state *s, const mpm_config *cfg, int dim) {
  char key[160];
  const char *geom;
  MPM_CALL(read_either(cfg, s->section, "density", 1, &s->rho, &s->rho_f));
  MPM_CALL(read_either(cfg, s->section, "pressure", 1, &s->p, &s->p_f));
  MPM_CALL(read_either(cfg, s->section, "velocity", dim, s->v, &s->v_f));
  key_of(key, sizeof key, s->section, "geometry");
  MPM_CALL(mpm_config_get_string(cfg, key, &geom));
  MPM_CALL(mpm_region_from_config(&s->region, cfg, dim, geom));
  return 0;
}

static void state_free(gas_state *s) {
  mpm_region_destroy(&s->region);
  mpm_expr_destroy(&s->rho_f);
  mpm_expr_destroy(&s->p_f);
  mpm_expr_destroy(&s->v_f);
}

/* The region must lie in the domain, like a solid body's. */
static int check_inside(const gas_state *s, const mpm_config *cfg, const mpm_grid *g) {
  double lo[3], hi[3];
  mpm_region_bounds(s->region, lo, hi);
  for (int d = 0; d < g->dim; ++d)
    if (lo[d] < g->lo[d] || hi[d] > g->hi[d]) {
      char key[160];
      key_of(key, sizeof key, s->section, "geometry");
      return mpm_config_fail(cfg, key,
                             "the region spans [%g, %g] along axis %d, outside the domain "
                             "[%g, %g]; move the region or enlarge [domain]",
                             lo[d], hi[d], d, g->lo[d], g->hi[d]);
    }
  return 0;
}

/* A density or pressure expression must be positive and finite at every particle: the
 * smallest value over all ranks is reported with its place (HUGE_VAL: this rank seeded no
 * point, as a finer level's on a rank that holds none of it). Collective. */
static int check_positive(const mpm_config *cfg, const mpm_grid *g, const char *section,
                          const char *name, double value, const double *x) {
  struct {
    double v;
    int rank;
  } mine = {isfinite(value) || value == HUGE_VAL ? value : -HUGE_VAL, g->rank}, worst;
  MPM_CALL_MPI(MPI_Allreduce(&mine, &worst, 1, MPI_DOUBLE_INT, MPI_MINLOC, g->comm));
  if (worst.v > 0) return 0;
  double at[3] = {x[0], x[1], x[2]};
  MPM_CALL_MPI(MPI_Bcast(at, 3, MPI_DOUBLE, worst.rank, g->comm));
  char key[160];
  snprintf(key, sizeof key, "%s.%s_field", section, name);
  return mpm_config_fail(cfg, key, "gives %s = %g at (%g, %g, %g); it must be positive and finite",
                         name, worst.v, at[0], at[1], at[2]);
}

/* Every field expression of s must be finite at the kept points (1/0, sqrt(-1) and log(0)
 * are not); the first bad point is reported with the value as it is. Collective. */
static int check_finite(const mpm_config *cfg, const mpm_grid *g, const gas_state *s, mpm_lidx n,
                        const double *x, const unsigned char *keep) {
  const mpm_expr *f[3] = {s->rho_f, s->p_f, s->v_f};
  static const char *const name[3] = {"density", "pressure", "velocity"};
  for (int c = 0; c < 3; ++c) {
    if (!f[c]) continue;
    char key[160];
    snprintf(key, sizeof key, "%s.%s_field", s->section, name[c]);
    MPM_CALL(mpm_expr_check_finite(f[c], cfg, key, g->comm, g->dim, n, x, keep));
  }
  return 0;
}

/* The lattice points of section k not claimed by an earlier section and outside every
 * obstacle: keep[i] = 1. */
static mpm_lidx claim(const gas_state *s, int k, const fluid_obstacles *obs, int dim, mpm_lidx n,
                      const double *x, unsigned char *keep) {
  mpm_lidx kept = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[(size_t)d * n + i];
    keep[i] = !fluid_obstacles_inside(obs, xp);
    for (int j = 0; j < k && keep[i]; ++j) keep[i] = !mpm_region_contains(s[j].region, xp);
    kept += keep[i];
  }
  return kept;
}

/* Fill the particle data of the kept points; returns the smallest density and pressure (and
 * where) so that the caller can check them collectively. */
static void fill(const fluid_content *fc, const mpm_particles *p, const gas_state *s, double vol,
                 mpm_lidx n, const double *x, const unsigned char *keep, mpm_lidx nk, double *data,
                 double minv[2], double where[2][3]) {
  const int dim = p->dim;
  mpm_lidx k = 0;
  minv[0] = minv[1] = HUGE_VAL;
  for (mpm_lidx i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[(size_t)d * n + i];
    const double rho = s->rho_f ? mpm_expr_eval(s->rho_f, 0, xp) : s->rho;
    const double pr = s->p_f ? mpm_expr_eval(s->p_f, 0, xp) : s->p;
    const double q[2] = {rho, pr};
    for (int c = 0; c < 2; ++c)
      if (!(q[c] >= minv[c]))
        minv[c] = isfinite(q[c]) ? q[c] : -HUGE_VAL, memcpy(where[c], xp, sizeof xp);
    for (int d = 0; d < dim; ++d) {
      data[(size_t)(p->offset[FLUID_X] + d) * nk + k] = xp[d];
      data[(size_t)(p->offset[FLUID_V] + d) * nk + k] =
          s->v_f ? mpm_expr_eval(s->v_f, d, xp) : s->v[d];
    }
    data[(size_t)p->offset[FLUID_J] * nk + k] = 1.0;
    data[(size_t)p->offset[FLUID_E] * nk + k] = fluid_energy(fc->gas.gamma, rho, pr);
    data[(size_t)p->offset[fc->lay.f_m] * nk + k] = rho * vol;
    data[(size_t)p->offset[fc->lay.f_V0] * nk + k] = vol;
    ++k;
  }
}

/* Claim, fill and append the n points x (ids id) of section k as particles of volume vol; the
 * number kept over all ranks goes to *total. Collective. */
static int add_points(mpm_module *m, const mpm_config *cfg, gas_state *s, int k, mpm_lidx n,
                      const double *x, const mpm_gidx *id, double vol, mpm_gidx *total) {
  const fluid_content *fc = m->content;
  mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  unsigned char *keep = malloc((size_t)(n ? n : 1));
  mpm_gidx *kid = malloc(sizeof *kid * (size_t)(n ? n : 1));
  double *data = calloc((size_t)p->ncomp * (size_t)(n ? n : 1), sizeof *data);
  int rc = keep && kid && data ? 0 : MPM_ERR_MEMORY;
  if (rc) /* the one line that says what to change (test_run_safety) */
    mpm_log_all(MPM_LOG_ERROR, MPM_OOM_MESSAGE,
                (double)n * (1.0 + sizeof *kid + (double)p->ncomp * sizeof *data) / 1e6);
  double minv[2] = {HUGE_VAL, HUGE_VAL}, where[2][3] = {{0}};
  mpm_lidx nk = 0;
  if (!rc) {
    nk = claim(s, k, &fc->obs, g->dim, n, x, keep);
    for (mpm_lidx i = 0, j = 0; i < n; ++i)
      if (keep[i]) kid[j++] = id[i];
    fill(fc, p, &s[k], vol, n, x, keep, nk, data, minv, where);
  }
  /* Collective checks first, so that every rank takes the same path. */
  if (!rc) rc = check_finite(cfg, g, &s[k], n, x, keep);
  if (!rc && s[k].rho_f) rc = check_positive(cfg, g, s[k].section, "density", minv[0], where[0]);
  if (!rc && s[k].p_f) rc = check_positive(cfg, g, s[k].section, "pressure", minv[1], where[1]);
  if (!rc) rc = mpm_particles_edit(p, NULL, nk, kid, data);
  free(keep), free(kid), free(data);
  MPM_CALL(rc);
  mpm_gidx local = nk;
  MPM_CALL_MPI(MPI_Allreduce(&local, total, 1, MPM_MPI_GIDX, MPI_SUM, g->comm));
  return 0;
}

/* Seed section k into the particle set. */
static int seed_one(mpm_module *m, const mpm_config *cfg, gas_state *s, int k) {
  const fluid_content *fc = m->content;
  mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  MPM_CALL(check_inside(&s[k], cfg, g));
  mpm_lidx n;
  double *x;
  mpm_gidx *id, total = 0;
  const mpm_gidx id_base = p->id_next;
  MPM_CALL(mpm_region_seed(s[k].region, g, fc->ppc, id_base, &n, &x, &id));
  const int rc = add_points(m, cfg, s, k, n, x, id, pow(g->dx / fc->ppc, g->dim), &total);
  free(x), free(id);
  MPM_CALL(rc);
  p->id_next = id_base + mpm_region_seed_span(g, fc->ppc);
  if (total == 0) {
    char key[160];
    key_of(key, sizeof key, s[k].section, "geometry");
    return mpm_config_fail(
        cfg, key,
        "[%s] has no particles: its region is thinner than the particle "
        "spacing %g or lies inside earlier gas regions or obstacles; refine grid.dx, raise "
        "fluid.ppc or change the region",
        s[k].section, g->dx / fc->ppc);
  }
  mpm_log(MPM_LOG_INFO, "gas %s: %lld particles", s[k].section, (long long)total);
  return 0;
}

/* Read every [gas.NAME] section into *sp (count of them in *count); free with states_free. */
static int states_read(const mpm_module *m, const mpm_config *cfg, gas_state **sp,
                       char (**secp)[96], int *count) {
  const char *const *names;
  MPM_CALL(mpm_config_instances(cfg, "gas", &names, count));
  gas_state *s = calloc((size_t)*count + 1, sizeof *s);
  char(*sections)[96] = calloc((size_t)*count + 1, sizeof *sections);
  *sp = s, *secp = sections;
  if (!s || !sections) MPM_FAIL(MPM_ERR_MEMORY, "out of memory reading the gas sections");
  for (int k = 0; k < *count; ++k) {
    snprintf(sections[k], sizeof sections[k], "gas.%s", names[k]);
    s[k].section = sections[k];
    MPM_CALL(read_state(&s[k], cfg, m->grid->dim));
  }
  return 0;
}

static void states_free(gas_state *s, char (*sections)[96], int count) {
  for (int k = 0; s && k < count; ++k) state_free(&s[k]);
  free(s);
  free(sections);
}

int fluid_seed(mpm_module *m, const mpm_config *cfg) {
  gas_state *s = NULL;
  char(*sections)[96] = NULL;
  int count = 0;
  int rc = states_read(m, cfg, &s, &sections, &count);
  for (int k = 0; !rc && k < count; ++k) rc = seed_one(m, cfg, s, k);
  states_free(s, sections, count);
  return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
}

/* ---- the finer levels of a refinement hierarchy ---------------------------------------------- */

/* Seed section k on level l. */
static int seed_level(mpm_module *m, const mpm_config *cfg, gas_state *s, int k, int l) {
  const fluid_content *fc = m->content;
  mpm_particles *p = m->particles;
  const mpm_grid *lg = m->hier->level[l].grid;
  double *x = NULL;
  mpm_lidx n = 0;
  mpm_gidx span = 0, total = 0, *id = NULL;
  MPM_CALL(mpm_hier_lattice(m->hier, l, fc->ppc, s[k].region, &x, &n, &span));
  int rc = 0;
  if (!(id = malloc(sizeof *id * (size_t)(n ? n : 1)))) rc = MPM_ERR_MEMORY;
  for (mpm_lidx i = 0; !rc && i < n; ++i) id[i] = p->id_next + i;
  if (!rc) n = mpm_hier_keep_owned(m->grid, x, id, n);
  if (!rc) rc = add_points(m, cfg, s, k, n, x, id, pow(lg->dx / fc->ppc, lg->dim), &total);
  free(x), free(id);
  MPM_CALL(rc);
  p->id_next += span;
  mpm_log(MPM_LOG_INFO, "gas %s: %lld particles on level %d", s[k].section, (long long)total, l);
  return 0;
}

int fluid_seed_refined(mpm_module *m, const mpm_config *cfg) {
  gas_state *s = NULL;
  char(*sections)[96] = NULL;
  int count = 0;
  int rc = states_read(m, cfg, &s, &sections, &count);
  if (!rc) rc = mpm_hier_drop_refined(m->hier, m->particles, FLUID_X);
  for (int l = 1; !rc && l < m->hier->nlevels; ++l)
    for (int k = 0; !rc && k < count; ++k) rc = seed_level(m, cfg, s, k, l);
  states_free(s, sections, count);
  return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
}
