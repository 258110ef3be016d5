/* Solid module: its case keys, seeding, and the module phases of an MPM right-hand side. The
 * constraints (walls, clamps, rigid bodies) and surface tractions are in solid_constraints.c.
 *
 * Invariants: particle field order is x, v, F, [sigma], [C], [divv] | m, V0, body, [hist],
 * [fixed], [fext], [pending_divv, divv] (see solid_particles_new; bracketed fields exist only
 * when a body's model, the APIC transfer, a bulk viscosity, a clamp or a traction needs them;
 * divv is in the state under usl and musl, after fext under the method of lines). body holds a
 * small integer stored as a double. The per-body index lists used for batched stress evaluation are
 * rebuilt at each P2G, so they never go stale after migration, sorting or injection. A rigid body's
 * particles keep F = I, C = 0 and their seeded velocity, and its region moves rigidly with that
 * velocity: at time t it is the seeded region translated by v t (wrapped through periodic faces). A
 * body with an initial stress is seeded at its state of solid_prestress.h: F = F0 (and sigma =
 * sigma0 for a rate-form model), V0 = seeded volume / det F0. On a refinement hierarchy (m->hier)
 * the P2G and G2P go through it and the finer levels are seeded by solid_refine.c; without one they
 * are the plain kernel calls. */
#include "solid_dilatation.h"
#include "solid_internal.h"
#include "solid_module.h"
#include "solid_tensor.h"

#include "mpm_bc.h"
#include "mpm_error.h"
#include "mpm_expr.h"
#include "mpm_geometry.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"
#include "mpm_timer.h"
#include "mpm_transfer.h"
#include "solid_material.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static mpm_key_spec solid_keys[] = {
    {"solid.*.geometry", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "name of the [geometry.NAME] region the body fills", 0, NULL},
    {"solid.*.material", MPM_KEY_ENUM, NULL, 0, 0, 0, 0, NULL, /* set from the registry */
     "material model of the body", 0, NULL},
    {"solid.*.density", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL, "mass density, kg/m^3", 0,
     "kg/m^3"},
    {"solid.*.E", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "Young's modulus, Pa (elastic models)", 1, "Pa"},
    {"solid.*.nu", MPM_KEY_REAL, "0.3", 0, 0.4999, 0, 0, NULL, "Poisson's ratio, [0, 0.5)", 0, "-"},
    {"solid.*.velocity", MPM_KEY_REALS, "0 0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "initial velocity, m/s (dim values; extra values are ignored)", 0, "m/s"},
    {"solid.*.velocity_field", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "initial velocity as expressions in x, y, z, one per component separated by ';' "
     "(e.g. 0.1*sin(pi*x/50); 0), instead of velocity",
     1, "m/s"},
    {"solid.*.ppc", MPM_KEY_INT, "2", 1, 8, 0, 0, NULL, "particles per cell per direction", 0, "-"},
    {"solid.*.sigma_y", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "initial yield stress, Pa (plastic models)", 1, "Pa"},
    {"solid.*.hardening", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "linear isotropic hardening modulus H, Pa (plastic models)", 0, "Pa"},
    {"solid.*.initial_stress", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 9, NULL,
     "Cauchy stress of the body as seeded, Pa: dim x dim values row by row (xx xy yx yy in "
     "2-D), symmetric; realised in the model's terms (an elastic stretch, or the rate form's "
     "stress state), so a gas at the same pressure beside the body starts in equilibrium",
     1, "Pa"},
    {"solid.*.initial_pressure", MPM_KEY_REAL, NULL, -HUGE_VAL, HUGE_VAL, 0, 0, NULL,
     "uniform pressure of the body as seeded, Pa: the initial stress -p I (instead of "
     "initial_stress)",
     1, "Pa"},
    {"solid.*.bulk_viscosity_linear", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "linear coefficient c1 of the bulk (shock) viscosity q = rho l (c1 c |tr D| + c2 l "
     "(tr D)^2) in compression (l the cell size, c the elastic wave speed), sigma -= q I; "
     "LS-DYNA's default is 0.06; usl and musl lag tr D by a step, the other methods take the "
     "current rate (docs/solid.md)",
     0, "-"},
    {"solid.*.bulk_viscosity_quadratic", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "quadratic coefficient c2 of the bulk viscosity (see bulk_viscosity_linear); LS-DYNA's "
     "default is 1.5 (Abaqus/Explicit's 1.2)",
     0, "-"},
    {"solid.*.dilatation", MPM_KEY_ENUM, "particle", 0, 0, 0, 0, "particle|projected",
     "the rate of volume change the deformation gradient takes: particle (tr L at the particle, "
     "classic MPM) or projected (tr L projected onto the grid's nodes, weighted by the "
     "particles' volumes, and interpolated back, the deviatoric part the particle's own: an "
     "F-bar for MPM; removes particle-scale alternations of the volume that the grid's forces "
     "do not see, such as a coupling face leaves; one scalar deposit and gather more per RHS; "
     "not with refinement; docs/solid.md)",
     0, NULL},
    {"clamp.*.geometry", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "region whose nodes and particles are held fixed (a [geometry.NAME])", 0, NULL},
    {"traction.*.geometry", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "region (a [geometry.NAME]) covering the outermost particle layer of the loaded face; "
     "particles of deformable bodies inside it at seeding carry the traction",
     0, NULL},
    {"traction.*.value", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "nominal traction, Pa (force per unit reference area; per unit depth in 2-D), dim values", 0,
     "Pa"},
};

int solid_add_schema(mpm_config *cfg) {
  for (size_t k = 0; k < sizeof solid_keys / sizeof solid_keys[0]; ++k)
    if (solid_keys[k].type == MPM_KEY_ENUM && !solid_keys[k].choices)
      solid_keys[k].choices = solid_material_names();
  return mpm_config_add_schema(cfg, solid_keys, (int)(sizeof solid_keys / sizeof solid_keys[0]));
}

int solid_particles_new(mpm_particles **p, int dim, solid_layout *lay, int has_rate, int apic,
                        int bulkq, int nhist, int fixed, int fext) {
  mpm_field_desc fields[MPM_PARTICLES_MAX_FIELDS] = {{"x", dim}, {"v", dim}, {"F", dim * dim}};
  int nf = 3;
  lay->f_sigma = has_rate ? nf : -1;
  if (has_rate) fields[nf++] = (mpm_field_desc){"sigma", dim * dim};
  lay->f_C = apic ? nf : -1;
  if (apic) fields[nf++] = (mpm_field_desc){"C", dim * dim};
  lay->f_divv = lay->f_pending = -1;
  if (bulkq == SOLID_BULKQ_STATE) lay->f_divv = nf, fields[nf++] = (mpm_field_desc){"divv", 1};
  const int nstate = nf;
  lay->f_m = nf, fields[nf++] = (mpm_field_desc){"m", 1};
  lay->f_V0 = nf, fields[nf++] = (mpm_field_desc){"V0", 1};
  lay->f_body = nf, fields[nf++] = (mpm_field_desc){"body", 1};
  lay->f_hist = nhist > 0 ? nf : -1;
  lay->nhist = nhist;
  if (nhist > 0) fields[nf++] = (mpm_field_desc){"hist", nhist};
  lay->f_fixed = fixed ? nf : -1;
  if (fixed) fields[nf++] = (mpm_field_desc){"fixed", 1};
  lay->f_fext = fext ? nf : -1;
  if (fext) fields[nf++] = (mpm_field_desc){"fext", dim};
  if (bulkq == SOLID_BULKQ_PENDING) {
    lay->f_pending = nf, fields[nf++] = (mpm_field_desc){"pending_divv", 1};
    lay->f_divv = nf, fields[nf++] = (mpm_field_desc){"divv", 1};
  }
  MPM_CALL(mpm_particles_new(p, dim, fields, nf, nstate));
  /* Every RHS writes the pending rate before the step commits it (as the gas's). */
  if (lay->f_pending >= 0) mpm_particles_set_scratch(*p, lay->f_pending);
  return 0;
}

/* What a checkpoint may hold in the fields that are not plain reals: positive masses and
 * volumes, a body index among this run's bodies, a 0/1 clamp flag. */
static void solid_set_ranges(mpm_particles *p, const solid_layout *lay, int nbodies) {
  mpm_particles_set_range(p, lay->f_m, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  mpm_particles_set_range(p, lay->f_V0, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  mpm_particles_set_range(p, lay->f_body, 0.0, nbodies - 1, MPM_FIELD_INTEGER);
  if (lay->f_fixed >= 0) mpm_particles_set_range(p, lay->f_fixed, 0.0, 1.0, MPM_FIELD_INTEGER);
}

/* A batch over particles `idx` of component-major arrays with stride n (state from y). */
static solid_batch batch_of(const solid_content *sc, const mpm_particles *p, const double *y,
                            mpm_lidx count, const mpm_lidx *idx, double *out) {
  const mpm_lidx n = p->n;
  return (solid_batch){
      .dim = p->dim,
      .n = n,
      .count = count,
      .idx = idx,
      .F = y + (size_t)p->offset[F_F] * n,
      .V0 = mpm_particles_comp(p, sc->lay.f_V0, 0),
      .sigma = sc->lay.f_sigma >= 0 ? y + (size_t)p->offset[sc->lay.f_sigma] * n : NULL,
      .hist = sc->lay.f_hist >= 0 ? mpm_particles_comp(p, sc->lay.f_hist, 0) : NULL,
      .out = out,
  };
}

/* Initial history of n new particles of body b (arrays with stride n). */
static void init_history(const solid_content *sc, int b, int dim, mpm_lidx n, const double *F,
                         double *hist) {
  const solid_material *mat = sc->body[b].mat;
  if (!hist || !mat->ops->init_history || n == 0) return;
  mpm_lidx *idx = malloc(sizeof *idx * (size_t)n);
  if (!idx) return;
  for (mpm_lidx i = 0; i < n; ++i) idx[i] = i;
  const solid_batch batch = {.dim = dim, .n = n, .count = n, .idx = idx, .F = F, .hist = hist};
  mat->ops->init_history(mat, &batch);
  free(idx);
}

/* A body's `velocity` key: dim values. */
int solid_body_velocity(const mpm_config *cfg, const char *section, int dim, double v[3]) {
  char key[160];
  int nv;
  solid_key(key, sizeof key, section, "velocity");
  MPM_CALL(mpm_config_get_reals(cfg, key, v, 3, &nv));
  if (nv < dim) return mpm_config_fail(cfg, key, "needs %d values, got %d", dim, nv);
  return 0;
}

int solid_seed_open(mpm_module *m, const mpm_config *cfg, int b, solid_seed *s) {
  const solid_content *sc = m->content;
  const int dim = m->grid->dim;
  char key[160];
  memset(s, 0, sizeof *s);
  s->b = b;
  solid_key(key, sizeof key, sc->body[b].section, "geometry");
  MPM_CALL(mpm_config_get_string(cfg, key, &s->geom));
  solid_key(key, sizeof key, sc->body[b].section, "ppc");
  MPM_CALL(mpm_config_get_int(cfg, key, &s->ppc));
  MPM_CALL(solid_body_velocity(cfg, sc->body[b].section, dim, s->v0));
  solid_key(key, sizeof key, sc->body[b].section, "velocity");
  solid_key(s->vkey, sizeof s->vkey, sc->body[b].section, "velocity_field");
  if (mpm_config_has(cfg, s->vkey)) {
    if (mpm_config_has(cfg, key))
      return mpm_config_fail(cfg, s->vkey, "give either velocity or velocity_field, not both");
    MPM_CALL(mpm_expr_from_config(&s->vfield, cfg, s->vkey, dim));
  }
  return mpm_region_from_config(&s->region, cfg, dim, s->geom);
}

void solid_seed_close(solid_seed *s) {
  mpm_expr_destroy(&s->vfield);
  mpm_region_destroy(&s->region);
}

int solid_seed_append(mpm_module *m, const mpm_config *cfg, const solid_seed *s, mpm_lidx n,
                      const double *x, const mpm_gidx *id, double spacing) {
  solid_content *sc = m->content;
  mpm_particles *p = m->particles;
  const int dim = m->grid->dim, b = s->b;
  /* A velocity_field must be finite at every particle (1/0, sqrt(-1) and log(0) are not). */
  if (s->vfield)
    MPM_CALL(mpm_expr_check_finite(s->vfield, cfg, s->vkey, m->grid->comm, dim, n, x, NULL));
  double *data;
  MPM_ALLOC(data, (size_t)p->ncomp * (size_t)(n ? n : 1));
  const double vol = pow(spacing, dim);
  const solid_prestress *pre = &sc->body[b].pre;
  for (mpm_lidx i = 0; i < n; ++i) {
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[(size_t)d * n + i];
    /* A clamped particle is held in place: at rest, whatever its body's velocity. */
    const int fixed = sc->lay.f_fixed >= 0 && solid_in_clamp(sc, xp);
    for (int d = 0; d < dim; ++d) {
      data[(size_t)(p->offset[F_X] + d) * n + i] = xp[d];
      data[(size_t)(p->offset[F_V] + d) * n + i] = fixed       ? 0.0
                                                   : s->vfield ? mpm_expr_eval(s->vfield, d, xp)
                                                               : s->v0[d];
    }
    for (int rc = 0; rc < dim * dim; ++rc) {
      data[(size_t)(p->offset[F_F] + rc) * n + i] = pre->F0[rc];
      if (sc->lay.f_sigma >= 0)
        data[(size_t)(p->offset[sc->lay.f_sigma] + rc) * n + i] = pre->sigma0[rc];
    }
    if (sc->lay.f_divv >= 0) data[(size_t)p->offset[sc->lay.f_divv] * n + i] = 0.0;
    if (sc->lay.f_pending >= 0) data[(size_t)p->offset[sc->lay.f_pending] * n + i] = 0.0;
    /* Seeded where it is: the current volume V0 det F0 is the seeding volume. */
    data[(size_t)p->offset[sc->lay.f_m] * n + i] = sc->body[b].rho * vol;
    data[(size_t)p->offset[sc->lay.f_V0] * n + i] = vol / pre->J0;
    data[(size_t)p->offset[sc->lay.f_body] * n + i] = b;
    if (sc->lay.f_fixed >= 0) data[(size_t)p->offset[sc->lay.f_fixed] * n + i] = fixed;
    if (sc->lay.f_fext >= 0 && !sc->body[b].mat->ops->rigid) {
      double f[3] = {0, 0, 0};
      solid_traction_force(sc, s->region, dim, spacing, xp, id[i], f);
      for (int d = 0; d < dim; ++d) data[(size_t)(p->offset[sc->lay.f_fext] + d) * n + i] = f[d];
    }
  }
  init_history(sc, b, dim, n, data + (size_t)p->offset[F_F] * n,
               sc->lay.f_hist >= 0 ? data + (size_t)p->offset[sc->lay.f_hist] * n : NULL);
  const int rc = mpm_particles_edit(p, NULL, n, id, data);
  free(data);
  return rc;
}

/* Seed one body and append it to the particle set. */
static int seed_body(mpm_module *m, const mpm_config *cfg, int b, double *lp) {
  solid_content *sc = m->content;
  mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = g->dim;
  char key[160];
  solid_seed s;
  int rc = solid_seed_open(m, cfg, b, &s);
  if (rc) solid_seed_close(&s);
  MPM_CALL(rc);
  *lp = fmin(*lp, 0.5 / s.ppc);

  double rlo[3], rhi[3];
  mpm_region_bounds(s.region, rlo, rhi);
  for (int d = 0; d < dim; ++d)
    if (rlo[d] < g->lo[d] || rhi[d] > g->hi[d]) {
      solid_seed_close(&s);
      solid_key(key, sizeof key, sc->body[b].section, "geometry");
      return mpm_config_fail(cfg, key,
                             "region '%s' spans [%g, %g] along axis %d, outside the domain "
                             "[%g, %g]; move the region or enlarge [domain]",
                             s.geom, rlo[d], rhi[d], d, g->lo[d], g->hi[d]);
    }
  mpm_lidx n;
  double *x;
  mpm_gidx *id;
  /* Each body takes a fresh block of ids as wide as its seeding lattice. */
  const mpm_gidx id_base = p->id_next;
  rc = mpm_region_seed(s.region, g, s.ppc, id_base, &n, &x, &id);
  if (!rc) {
    rc = solid_seed_append(m, cfg, &s, n, x, id, g->dx / s.ppc);
    free(x), free(id);
  }
  solid_seed_close(&s);
  MPM_CALL(rc);
  p->id_next = id_base + mpm_region_seed_span(g, s.ppc);
  mpm_gidx local = n, total;
  MPM_CALL_MPI(MPI_Allreduce(&local, &total, 1, MPM_MPI_GIDX, MPI_SUM, g->comm));
  if (total == 0) {
    solid_key(key, sizeof key, sc->body[b].section, "geometry");
    return mpm_config_fail(cfg, key,
                           "body '%s' has no particles: region '%s' is thinner than "
                           "the particle spacing %g; refine grid.dx or raise ppc",
                           sc->body[b].section, s.geom, g->dx / s.ppc);
  }
  mpm_log(MPM_LOG_INFO, "solid body %s: %lld particles, material %s", sc->body[b].section,
          (long long)total, sc->body[b].mat->ops->name);
  return 0;
}

/* A body whose seeded volume is off its geometry's by more than this share draws a warning. */
#define SEED_VOLUME_WARN 0.02

int solid_seed_report(mpm_module *m, const mpm_config *cfg) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const double *mass = mpm_particles_comp(p, sc->lay.f_m, 0);
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  for (int b = 0; b < sc->nbodies; ++b) {
    double seeded = 0.0;
    for (mpm_lidx i = 0; i < p->n; ++i)
      if ((int)body[i] == b) seeded += mass[i];
    seeded /= sc->body[b].rho;
    MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &seeded, 1, MPI_DOUBLE, MPI_SUM, g->comm));
    solid_seed s;
    MPM_CALL(solid_seed_open(m, cfg, b, &s));
    const double spacing = g->dx / s.ppc;
    const double exact = mpm_region_volume(s.region, spacing / 8.0, 4e6);
    solid_seed_close(&s);
    const double rel = exact > 0.0 ? seeded / exact - 1.0 : 0.0;
    mpm_log(MPM_LOG_INFO, "solid body %s: seeded volume %.6g, its geometry's %.6g (%+.2f %%)",
            sc->body[b].section, seeded, exact, 100.0 * rel);
    if (fabs(rel) > SEED_VOLUME_WARN)
      mpm_log(MPM_LOG_WARN,
              "solid body %s: its particles' volume is %+.1f %% off its geometry's: faces off "
              "the particle lattice (spacing %g) move by up to half a spacing, and the body's "
              "mass and stiffness with them; a grid.dx whose particle spacing (grid.dx / ppc) "
              "divides the body's extents seeds it whole (docs/solid.md, \"Seeding\")",
              sc->body[b].section, 100.0 * rel, spacing);
  }
  return 0;
}

/* Grow the scratch arrays to the current particle count. */
static int ensure_scratch(mpm_module *m) {
  solid_content *sc = m->content;
  const mpm_lidx n = m->particles->n;
  const int dim = m->grid->dim;
  if (n <= sc->cap && sc->vsig && (!sc->pts_on || sc->pts_buf)) return 0;
  free(sc->vsig);
  free(sc->scratch);
  free(sc->idx);
  free(sc->vnew);
  sc->vnew = NULL;
  free(sc->zero);
  sc->zero = NULL;
  sc->cap = n + n / 4 + 16;
  MPM_ALLOC(sc->vsig, (size_t)dim * dim * sc->cap);
  MPM_ALLOC(sc->scratch, (size_t)(2 * dim + dim * dim) * sc->cap);
  MPM_ALLOC(sc->idx, sc->cap);
  if (sc->tr.musl) MPM_ALLOC(sc->vnew, (size_t)dim * sc->cap);
  if (sc->lay.f_pending >= 0) {
    sc->zero = calloc((size_t)sc->cap, sizeof(double));
    if (!sc->zero) MPM_FAIL(MPM_ERR_MEMORY, "out of memory for %lld particles", (long long)sc->cap);
  }
  free(sc->pts_buf);
  sc->pts_buf = NULL;
  if (sc->pts_on) MPM_ALLOC(sc->pts_buf, (size_t)sc->cap);
  return 0;
}

/* The points view (mpm_points) at state y: the positions and the volumes V0 det F. */
static void fill_points(solid_content *sc, const mpm_particles *p, const double *y) {
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *F = y + (size_t)p->offset[F_F] * n, *V0 = mpm_particles_comp(p, sc->lay.f_V0, 0);
  double *V = sc->pts_buf;
  for (mpm_lidx i = 0; i < n; ++i) V[i] = V0[i] * solid_det(dim, F, n, i);
  sc->pts.n = n, sc->pts.V = V;
  for (int d = 0; d < dim; ++d) sc->pts.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
}

static const mpm_points *solid_points(mpm_module *m) {
  solid_content *sc = m->content;
  sc->pts_on = 1; /* the next p2g's ensure_scratch allocates pts_buf */
  return &sc->pts;
}

/* Group particle indices by body (a counting sort of the body field). */
static void group_by_body(mpm_module *m) {
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  mpm_lidx start[64] = {0};
  memset(sc->count, 0, sizeof(mpm_lidx) * (size_t)sc->nbodies);
  for (mpm_lidx i = 0; i < p->n; ++i) sc->count[(int)body[i]]++;
  for (int b = 1; b < sc->nbodies; ++b) start[b] = start[b - 1] + sc->count[b - 1];
  for (mpm_lidx i = 0; i < p->n; ++i) sc->idx[start[(int)body[i]]++] = i;
}

/* The APIC affine velocities in state y, or NULL without APIC. */
static const double *state_C(const solid_content *sc, const mpm_particles *p, const double *y) {
  return sc->lay.f_C >= 0 ? y + (size_t)p->offset[sc->lay.f_C] * p->n : NULL;
}

/* The gauge pressure p_g (physics.gauge_pressure, fluid/fluid_gauge.c): V sigma + V p_g I in the
 * forces; the stored energy stays sigma's. */
static void add_gauge(solid_content *sc, const mpm_particles *p, const double *y) {
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *F = y + (size_t)p->offset[F_F] * n, *V0 = mpm_particles_comp(p, sc->lay.f_V0, 0);
  for (mpm_lidx i = 0; i < n; ++i) {
    const double pV = sc->gauge * V0[i] * solid_det(dim, F, n, i);
    for (int d = 0; d < dim; ++d) sc->vsig[(size_t)(d * dim + d) * n + i] += pV;
  }
}

static int solid_p2g(mpm_module *m, double t, const double *y) {
  (void)t;
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  MPM_CALL(ensure_scratch(m));
  mpm_timer_start(MPM_T_STRESS);
  group_by_body(m);
  const mpm_lidx *idx = sc->idx;
  const double *mass = mpm_particles_comp(p, sc->lay.f_m, 0);
  for (int b = 0; b < sc->nbodies; ++b) {
    const solid_batch batch = batch_of(sc, p, y, sc->count[b], idx, sc->vsig);
    sc->body[b].mat->ops->stress(sc->body[b].mat, &batch);
    if (solid_bulkq_on(&sc->body[b].q) && sc->lay.f_pending < 0) /* lagged: from the state */
      solid_bulkq_add(&sc->body[b].q, dim, n, sc->count[b], idx, mass,
                      y + (size_t)p->offset[sc->lay.f_divv] * n, sc->vsig);
    idx += sc->count[b];
  }
  if (sc->gauge != 0.0) add_gauge(sc, p, y);
  mpm_timer_stop(MPM_T_STRESS);
  if (sc->pts_on) fill_points(sc, p, y);

  mpm_timer_start(MPM_T_P2G);
  mpm_p2g_args a = {.n = n,
                    .m = mpm_particles_comp(p, sc->lay.f_m, 0),
                    .vsig = sc->vsig,
                    .C = state_C(sc, p, y),
                    .lp = sc->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
    a.v[d] = y + (size_t)(p->offset[F_V] + d) * n;
    a.gravity[d] = sc->gravity[d];
    a.fext[d] = sc->lay.f_fext >= 0 ? mpm_particles_comp(p, sc->lay.f_fext, d) : NULL;
  }
  const int rc = solid_deposit(m, &a);
  mpm_timer_stop(MPM_T_P2G);
  return rc;
}

/* Mass-proportional damping, a force -alpha m v on every node: each mode's amplitude decays
 * as exp(-alpha t / 2). For quasi-static problems; off by default. */
static void damp(mpm_grid *grid, int phase, double alpha) {
  mpm_grid_phase *ph = &grid->phase[phase];
  for (int d = 0; d < grid->dim; ++d)
    for (mpm_lidx l = 0; l < grid->nnodes; ++l) ph->f_i[d][l] -= alpha * ph->mv_i[d][l];
}

/* The damping on every level of a hierarchy (restricted: the inactive nodes hold nothing). */
static void damp_all(const mpm_module *m, double alpha) {
  if (!m->hier) {
    damp(m->grid, m->phase, alpha);
    return;
  }
  for (int l = 0; l < m->hier->nlevels; ++l) damp(m->hier->level[l].grid, m->phase, alpha);
}

/* Before the nodal solve: mirrored pad nodes folded into the walls, and damping (first pass
 * only: after MUSL's remap no force acts). */
static int solid_forces(mpm_module *m, double t, double h, mpm_pass pass) {
  (void)t, (void)h;
  solid_content *sc = m->content;
  mpm_constraints_fold(&sc->cons, m->grid, m->phase);
  for (int l = 1; m->hier && l < m->hier->nlevels; ++l) /* the clamps' pads before the walls' */
    mpm_constraints_fold(&sc->lcons[l], m->hier->level[l].grid, m->phase);
  if (m->hier) mpm_hier_walls_fold(m->hier, m->phase);
  if (sc->damping > 0 && pass == MPM_PASS_FIRST) damp_all(m, sc->damping);
  return 0;
}

/* After the nodal solve. Rigid bodies act before the walls and clamps: the pad nodes beyond a
 * wall mirror what a rigid body set inside, and a wall or clamp keeps its own nodes. On a
 * hierarchy the finer levels' clamps hold their nodes before their walls' pad nodes copy their
 * mirrors (level 0's rules do the same in one list). */
static int solid_constrain(mpm_module *m, double t, double h, mpm_pass pass) {
  (void)h, (void)pass;
  solid_content *sc = m->content;
  for (int b = 0; b < sc->nbodies; ++b)
    if (sc->body[b].region) solid_hold_rigid_nodes(&sc->body[b], m->grid, m->phase, t);
  mpm_constraints_apply(&sc->cons, m->grid, m->phase);
  if (!m->hier) return 0;
  for (int l = 1; l < m->hier->nlevels; ++l) /* held nodes; the pads again after the walls' */
    mpm_constraints_apply(&sc->lcons[l], m->hier->level[l].grid, m->phase);
  mpm_hier_walls_apply(m->hier, m->phase);
  for (int l = 1; l < m->hier->nlevels; ++l)
    mpm_constraints_apply(&sc->lcons[l], m->hier->level[l].grid, m->phase);
  return 0;
}

static void solid_stress_rates(mpm_module *m, const double *y, double *ydot, const double *L);

/* G2P: v_out = sum S v_i, a_out = sum S a_i, and optionally L, the APIC C and dF/dt = L F
 * (NULL: not wanted). */
static int g2p_velocity(mpm_module *m, const double *y, double *const *v_out, double *const *a_out,
                        double *L_out, double *C_out, double *Fdot) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid_phase *ph = &m->grid->phase[m->phase];
  mpm_g2p_args a = {.n = p->n,
                    .lp = sc->lp,
                    .L_out = L_out,
                    .C_out = C_out,
                    .F = y + (size_t)p->offset[F_F] * p->n,
                    .LF_out = Fdot};
  for (int d = 0; d < p->dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[F_X] + d) * p->n;
    a.v_i[d] = ph->v_i[d];
    a.a_i[d] = ph->a_i[d];
    a.v_out[d] = v_out[d];
    a.a_out[d] = a_out[d];
  }
  return solid_gather(m, &a);
}

/* MUSL's second transfer (Sulsky, Zhou and Schreyer 1995): the particles take their new
 * velocities, v_p^+ = (1 - a)(v_p + h sum S a_i) + a sum S v_i^{n+1} (a = PIC fraction; APIC:
 * a = 1 with the new affine velocities), and deposit their mass and momentum again; the
 * positions and F then move with the nodal velocities of these momenta. Stress and gravity
 * are not deposited again. */
static int solid_remap(mpm_module *m, double t, const double *y, double h) {
  (void)t;
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  double *vg[MPM_MAX_DIM] = {NULL}, *ag[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d)
    vg[d] = sc->scratch + (size_t)d * n, ag[d] = sc->scratch + (size_t)(dim + d) * n;
  double *C = sc->tr.apic ? sc->scratch + (size_t)2 * dim * n : NULL; /* the L slot */
  MPM_CALL(g2p_velocity(m, y, vg, ag, NULL, C, NULL));
  const double pic = sc->tr.apic ? 1.0 : sc->tr.pic;
  for (int d = 0; d < dim; ++d) {
    const double *v = y + (size_t)(p->offset[F_V] + d) * n;
    double *vn = sc->vnew + (size_t)d * n;
    for (mpm_lidx i = 0; i < n; ++i) vn[i] = (1.0 - pic) * (v[i] + h * ag[d][i]) + pic * vg[d][i];
  }
  if (sc->nrigid) solid_rigid_velocity(sc, dim, n, sc->vnew);
  mpm_grid_phase_zero(m->grid, m->phase);
  mpm_p2g_args a = {.n = n, .m = mpm_particles_comp(p, sc->lay.f_m, 0), .C = C, .lp = sc->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
    a.v[d] = sc->vnew + (size_t)d * n;
  }
  mpm_kernels_get(dim)->p2g(m->grid, m->phase, &a);
  return 0;
}

/* The bulk viscosity's lagged rate: divv takes this step's tr L, as a rate over the step h
 * (the classic update only; solid_bulk_viscosity.h). */
static void lag_divv(const mpm_particles *p, int f_divv, const double *y, double *ydot,
                     const double *L, double h) {
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *divv = y + (size_t)p->offset[f_divv] * n;
  double *rate = ydot + (size_t)p->offset[f_divv] * n;
  for (mpm_lidx i = 0; i < n; ++i) {
    double tr = 0.0;
    for (int d = 0; d < dim; ++d) tr += L[(size_t)(d * dim + d) * n + i];
    rate[i] = h > 0 ? (tr - divv[i]) / h : 0.0;
  }
}

/* dx/dt = sum S v_i, dv/dt = sum S a_i, dF/dt = L F with L = sum v_i (x) grad S. */
static int solid_g2p(mpm_module *m, double t, const double *y, double *ydot, double h) {
  (void)t;
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  /* dF/dt = L F comes out of the kernel directly; L itself is kept only for rate-form
   * models, the bulk viscosity's lagged tr L and the projected dilatation. */
  const int lagged = sc->lay.f_divv >= 0 && sc->lay.f_pending < 0;
  double *L =
      sc->lay.f_sigma >= 0 || lagged || sc->dil.on ? sc->scratch + (size_t)2 * dim * n : NULL;
  double *xdot[MPM_MAX_DIM] = {NULL}, *vdot[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d) {
    xdot[d] = ydot + (size_t)(p->offset[F_X] + d) * n;
    vdot[d] = ydot + (size_t)(p->offset[F_V] + d) * n;
  }
  double *Cdot = sc->tr.apic ? ydot + (size_t)p->offset[sc->lay.f_C] * n : NULL;
  MPM_CALL(g2p_velocity(m, y, xdot, vdot, L, Cdot, ydot + (size_t)p->offset[F_F] * n));
  if (sc->tr.musl && !sc->tr.apic && h > 0)
    for (int d = 0; d < dim; ++d) { /* the velocity solid_remap gave the particles */
      const double *v = y + (size_t)(p->offset[F_V] + d) * n, *vn = sc->vnew + (size_t)d * n;
      for (mpm_lidx i = 0; i < n; ++i) vdot[d][i] = (vn[i] - v[i]) / h;
    }
  else if ((sc->tr.apic || sc->tr.pic > 0) && h > 0) /* APIC (also under MUSL): the final grid's */
    mpm_transfer_blend(p, y, ydot, sc->tr.apic ? 1.0 : sc->tr.pic, h);
  if (sc->tr.apic && h > 0) { /* C takes the new affine velocity over the step */
    const double *C = state_C(sc, p, y);
    for (size_t k = 0; k < (size_t)dim * dim * (size_t)n; ++k) Cdot[k] = (Cdot[k] - C[k]) / h;
  }
  if (lagged) lag_divv(p, sc->lay.f_divv, y, ydot, L, h); /* the particle's own rate */
  if (sc->dil.on) MPM_CALL(solid_dilatation_apply(m, y, L, ydot + (size_t)p->offset[F_F] * n));
  if (sc->lay.f_sigma >= 0) solid_stress_rates(m, y, ydot, L);
  if (sc->lay.f_fixed >= 0) solid_hold_fixed(p, sc->lay.f_fixed, ydot);
  if (sc->nrigid) solid_move_rigid(sc, p, ydot);
  return 0;
}

/* Rate-form models: d sigma/dt from L; the stress state of other bodies stays constant.
 * Particles are grouped by body as in this RHS's P2G. */
static void solid_stress_rates(mpm_module *m, const double *y, double *ydot, const double *L) {
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  double *sdot = ydot + (size_t)p->offset[sc->lay.f_sigma] * n;
  memset(sdot, 0, sizeof(double) * (size_t)(p->dim * p->dim) * (size_t)n);
  const mpm_lidx *idx = sc->idx;
  for (int b = 0; b < sc->nbodies; ++b) {
    const solid_material *mat = sc->body[b].mat;
    if (mat->ops->rate) {
      solid_batch batch = batch_of(sc, p, y, sc->count[b], idx, sdot);
      batch.L = L;
      mat->ops->rate(mat, &batch);
    }
    idx += sc->count[b];
  }
}

static int solid_bodies(const mpm_module *m, const char **names, int max) {
  const solid_content *sc = m->content;
  for (int b = 0; b < sc->nbodies && b < max; ++b) names[b] = sc->body[b].section;
  return sc->nbodies;
}

/* Interpolate a_i to the particles (this RHS's grouping by body from P2G), sum m_p a_p per body. */
static int solid_body_loads(mpm_module *m, const double *y, const double *const *a_i, double *F) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *mass = mpm_particles_comp(p, sc->lay.f_m, 0);
  if (m->hier) /* the coupling is refused on a hierarchy (solid_refine.c) */
    MPM_FAIL(MPM_ERR_INTERNAL, "solid body loads on a refinement hierarchy");
  mpm_g2p_args a = {.n = n, .lp = sc->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
    a.v_i[d] = a.a_i[d] = a_i[d];
    a.v_out[d] = sc->scratch + (size_t)d * n, a.a_out[d] = sc->scratch + (size_t)(dim + d) * n;
  }
  mpm_kernels_get(dim)->g2p(m->grid, &a);
  const mpm_lidx *idx = sc->idx;
  for (int b = 0; b < sc->nbodies; idx += sc->count[b++])
    for (int d = 0; d < dim; ++d) {
      double sum = 0.0;
      for (mpm_lidx k = 0; k < sc->count[b]; ++k) sum += mass[idx[k]] * a.v_out[d][idx[k]];
      F[b * MPM_MAX_DIM + d] = sum;
    }
  return 0;
}

/* After an accepted step (and migration): the ERK pairs' pending bulk-viscosity rate becomes the
 * stable step's, and models with history store the returned state. */
static int solid_post_step(mpm_module *m, double t, double h, int *changed) {
  (void)t, (void)h, (void)changed;
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  if (sc->lay.f_pending >= 0) solid_bulkq_commit(m);
  if (sc->lay.f_hist < 0) return 0;
  MPM_CALL(ensure_scratch(m));
  group_by_body(m);
  const mpm_lidx *idx = sc->idx;
  for (int b = 0; b < sc->nbodies; ++b) {
    const solid_material *mat = sc->body[b].mat;
    if (mat->ops->commit) {
      const solid_batch batch = batch_of(sc, p, p->data, sc->count[b], idx, NULL);
      mat->ops->commit(mat, &batch);
    }
    idx += sc->count[b];
  }
  return 0;
}

static double solid_stable_dt(const mpm_module *m, const double *y) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  const double *divv = sc->lay.f_pending >= 0 ? mpm_particles_comp(p, sc->lay.f_divv, 0)
                       : sc->lay.f_divv >= 0  ? y + (size_t)p->offset[sc->lay.f_divv] * p->n
                                              : NULL;
  const double dx = solid_finest_dx(m);
  double dt = HUGE_VAL;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double v2 = 0.0;
    for (int d = 0; d < p->dim; ++d) {
      const double v = y[(size_t)(p->offset[F_V] + d) * p->n + i];
      v2 += v * v;
    }
    const solid_body *bi = &sc->body[(int)body[i]];
    const double s = divv ? solid_bulkq_speed(&bi->q, divv[i], dx) : 0.0;
    dt = fmin(dt, dx / (bi->c + sqrt(v2) + s));
  }
  return dt;
}

static double solid_signal_speed(const mpm_module *m, const double *y) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  double smax = 0.0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double v2 = 0.0;
    for (int d = 0; d < p->dim; ++d) {
      const double v = y[(size_t)(p->offset[F_V] + d) * p->n + i];
      v2 += v * v;
    }
    smax = fmax(smax, sc->body[(int)body[i]].c + sqrt(v2));
  }
  return smax;
}

static int solid_check(const mpm_module *m, const double *y, mpm_fault *fault) {
  if (mpm_module_check_positions(m, y, fault)) return 1;
  const mpm_particles *p = m->particles;
  const double *F = y + (size_t)p->offset[F_F] * p->n;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const double J = solid_det(p->dim, F, p->n, i);
    if (J <= 0.0)
      return mpm_fault_at(fault, p, y, i, "the deformation gradient is inverted (J = %.3g <= 0)",
                          J);
  }
  return 0;
}

static void solid_sums(const mpm_module *m, mpm_module_sums *s) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const double *mass = mpm_particles_comp(p, sc->lay.f_m, 0),
               *V0 = mpm_particles_comp(p, sc->lay.f_V0, 0);
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  const solid_batch batch = batch_of(sc, p, p->data, 0, NULL, NULL);
  memset(s, 0, sizeof *s);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    s->mass += mass[i];
    for (int d = 0; d < dim; ++d) {
      const double v = mpm_particles_comp(p, F_V, d)[i];
      s->momentum[d] += mass[i] * v;
      s->kinetic += 0.5 * mass[i] * v * v;
    }
    const solid_body *b = &sc->body[(int)body[i]];
    s->internal += V0[i] * b->mat->ops->energy_density(b->mat, &batch, i);
  }
}

static void solid_destroy(mpm_module *m) {
  solid_content *sc = m->content;
  if (sc) {
    for (int b = 0; b < sc->nbodies; ++b) {
      solid_material_destroy(&sc->body[b].mat);
      mpm_region_destroy(&sc->body[b].region);
    }
    for (int k = 0; k < sc->ntractions; ++k) mpm_region_destroy(&sc->traction[k].region);
    free(sc->traction);
    for (int k = 0; k < sc->nclamps; ++k) mpm_region_destroy(&sc->clamp[k]);
    free(sc->clamp);
    mpm_constraints_free(&sc->cons);
    for (int l = 1; l < MPM_HIER_MAX_LEVELS; ++l) mpm_constraints_free(&sc->lcons[l]);
    free(sc->body);
    free(sc->vsig);
    free(sc->scratch);
    free(sc->pts_buf);
    free(sc->idx);
    free(sc->vnew);
    free(sc->zero);
    free(sc->count);
    solid_dilatation_free(&sc->dil);
    free(sc);
  }
  mpm_particles_destroy(&m->particles);
}

static const mpm_module_ops solid_ops = {
    .p2g = solid_p2g,
    .forces = solid_forces,
    .constrain = solid_constrain,
    .bodies = solid_bodies,
    .body_loads = solid_body_loads,
    .g2p = solid_g2p,
    .stable_dt = solid_stable_dt,
    .signal_speed = solid_signal_speed,
    .check = solid_check,
    .sums = solid_sums,
    .post_step = solid_post_step,
    .destroy = solid_destroy,
    .remap = solid_remap,
    .points = solid_points,
};

/* A body's bulk viscosity (solid_bulk_viscosity.h); the schema refuses negative values. */
static int read_bulkq(const mpm_module *m, const mpm_config *cfg, solid_body *body) {
  char key[160];
  solid_key(key, sizeof key, body->section, "bulk_viscosity_linear");
  MPM_CALL(mpm_config_get_real(cfg, key, &body->q.c1));
  solid_key(key, sizeof key, body->section, "bulk_viscosity_quadratic");
  MPM_CALL(mpm_config_get_real(cfg, key, &body->q.c2));
  body->q.c = body->c;
  body->q.l = m->grid->dx;
  if (!solid_bulkq_on(&body->q)) return 0;
  if (body->q.c1 > 0.0) /* errors name a key that is set */
    solid_key(key, sizeof key, body->section, "bulk_viscosity_linear");
  if (body->mat->ops->rigid)
    return mpm_config_fail(cfg, key, "a rigid body has no stress to damp; remove the key");
  return 0;
}

/* Read the bodies' sections and build their materials. */
static int read_bodies(mpm_module *m, const mpm_config *cfg) {
  solid_content *sc = m->content;
  const char *const *names;
  int count, nv;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &count));
  if (count > 64) return mpm_config_fail(cfg, "solid", "at most 64 solid bodies are supported");
  MPM_ALLOC(sc->body, count);
  MPM_ALLOC(sc->count, count);
  sc->nbodies = count;
  for (int b = 0; b < count; ++b) {
    char key[160];
    const char *type;
    snprintf(sc->body[b].section, sizeof sc->body[b].section, "solid.%s", names[b]);
    solid_key(key, sizeof key, sc->body[b].section, "density");
    MPM_CALL(mpm_config_get_real(cfg, key, &sc->body[b].rho));
    solid_key(key, sizeof key, sc->body[b].section, "material");
    MPM_CALL(mpm_config_get_string(cfg, key, &type));
    MPM_CALL(solid_material_create(&sc->body[b].mat, type, cfg, sc->body[b].section, m->grid->dim));
    MPM_CALL(solid_prestress_read(&sc->body[b].pre, cfg, sc->body[b].section, sc->body[b].mat,
                                  m->grid->dim));
    /* Constant per body: evaluated once, not per particle in every stable-step scan. At the
     * reference density: a body pre-compressed to J0 < 1 is denser than its unstressed state
     * (rho J0 is the reference density), so the step shrinks with it; the stiffening of the
     * tangent at F0 is not included. */
    sc->body[b].c =
        sc->body[b].mat->ops->wave_speed(sc->body[b].mat, sc->body[b].rho * sc->body[b].pre.J0);
    if (sc->body[b].mat->ops->rigid) MPM_CALL(solid_read_rigid(m, cfg, &sc->body[b]));
  }
  double g[3] = {0, 0, 0};
  MPM_CALL(mpm_config_get_reals(cfg, "physics.gravity", g, 3, &nv));
  memcpy(sc->gravity, g, sizeof g);
  MPM_CALL(mpm_config_get_real(cfg, "physics.damping", &sc->damping));
  MPM_CALL(mpm_config_get_real(cfg, "physics.gauge_pressure", &sc->gauge));
  const char *const *gases;
  int ngas;
  MPM_CALL(mpm_config_instances(cfg, "gas", &gases, &ngas));
  if (sc->gauge != 0.0 && ngas == 0)
    return mpm_config_fail(cfg, "physics.gauge_pressure",
                           "is a pressure taken out of a gas's and a solid's stress alike, and "
                           "this scene has no gas: its solids would carry it on their free "
                           "surfaces; remove the key");
  MPM_CALL(mpm_transfer_from_config(&sc->tr, cfg, NULL));
  for (int b = 0; b < count; ++b) MPM_CALL(read_bulkq(m, cfg, &sc->body[b]));
  return solid_dilatation_read(m, cfg);
}

int solid_module_create(mpm_module **mp, const mpm_config *cfg, mpm_grid *grid, int seed) {
  const char *const *names;
  int count;
  *mp = NULL;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &count));
  if (count == 0) return 0;
  mpm_module *m;
  MPM_ALLOC(m, 1);
  *mp = m;
  snprintf(m->name, sizeof m->name, "solid");
  m->ops = &solid_ops;
  m->role = MPM_ROLE_SOLID;
  m->grid = grid;
  solid_content *sc;
  MPM_ALLOC(sc, 1);
  m->content = sc;
  sc->lp = 0.5;
  int rc = mpm_grid_add_phase(grid, "solid", &m->phase);
  if (!rc) rc = read_bodies(m, cfg);
  if (!rc) {
    int has_rate = 0, nhist = 0, bulkq = SOLID_BULKQ_NONE;
    for (int b = 0; b < sc->nbodies; ++b) {
      const solid_material_ops *ops = sc->body[b].mat->ops;
      has_rate |= ops->rate != NULL;
      if (solid_bulkq_on(&sc->body[b].q))
        bulkq = sc->tr.classic ? SOLID_BULKQ_STATE : SOLID_BULKQ_PENDING;
      if (ops->nhistory) nhist = MPM_MAX(nhist, ops->nhistory(grid->dim));
    }
    if (!rc) rc = solid_read_constraints(m, cfg);
    if (!rc) rc = solid_read_tractions(m, cfg);
    if (!rc)
      rc = solid_particles_new(&m->particles, grid->dim, &sc->lay, has_rate, sc->tr.apic, bulkq,
                               nhist, sc->nclamps > 0, sc->ntractions > 0);
    if (!rc) solid_set_ranges(m->particles, &sc->lay, sc->nbodies);
  }
  for (int b = 0; !rc && b < sc->nbodies; ++b) {
    double lp = sc->lp;
    if (seed)
      rc = seed_body(m, cfg, b, &lp);
    else {
      char key[160];
      int ppc;
      solid_key(key, sizeof key, sc->body[b].section, "ppc");
      rc = mpm_config_get_int(cfg, key, &ppc);
      lp = fmin(lp, 0.5 / ppc);
    }
    sc->lp = lp;
  }
  if (!rc && seed) rc = solid_check_tractions(m, cfg);
  int levels = 1; /* on a hierarchy the bodies are seeded again, level by level */
  if (!rc && seed) rc = mpm_config_get_int(cfg, "refine.levels", &levels);
  if (!rc && seed && levels <= 1) rc = solid_seed_report(m, cfg);
  if (rc) {
    mpm_module_destroy(mp);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  m->commits_history = sc->lay.f_hist >= 0; /* the materials' commit (solid_post_step) */
  sc->ops = solid_ops;
  if (sc->lay.f_pending >= 0) sc->ops.p2g_rate = solid_bulkq_p2g_rate; /* the current rate */
  m->ops = &sc->ops;
  return 0;
}
