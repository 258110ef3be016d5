/* The coupling scheme object: keys, construction, hook dispatch and the interface balance (see
 * mpm_coupling.h). */
#include "mpm_coupling.h"

#include "mpm_bc.h"
#include "mpm_error.h"
#include "mpm_timer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* "none|velocity|...", built from the register when the schema is added. */
static char g_choices[256];
static char g_help[1024];

static mpm_key_spec g_scheme_key[] = {
    {"coupling.scheme", MPM_KEY_ENUM, "velocity", 0, 0, 0, 0, g_choices, g_help, 0, NULL},
};

/* Does type t declare key? */
static int declares(const mpm_coupling_type *t, const char *key) {
  for (int k = 0; k < t->nkeys; ++k)
    if (strcmp(t->keys[k].key, key) == 0) return 1;
  return 0;
}

int mpm_coupling_add_schema(mpm_config *cfg) {
  int n;
  const mpm_coupling_type *const *types = mpm_coupling_types(&n);
  const char *names[16], *helps[16];
  for (int k = 0; k < n && k < 16; ++k) names[k] = types[k]->name, helps[k] = types[k]->help;
  mpm_config_enum_text(g_choices, sizeof g_choices, g_help, sizeof g_help,
                       "how the solid and the gas interact where both have mass:", names, helps,
                       n < 16 ? n : 16);
  MPM_CALL(mpm_config_add_schema(cfg, g_scheme_key, 1));
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < types[k]->nkeys; ++j) { /* a key two schemes share, once */
      int earlier = 0;
      for (int i = 0; i < k && !earlier; ++i) earlier = declares(types[i], types[k]->keys[j].key);
      if (!earlier) MPM_CALL(mpm_config_add_schema(cfg, &types[k]->keys[j], 1));
    }
  return 0;
}

/* A key of another scheme (not also the chosen one's) is a mistake worth naming. */
static int check_foreign_keys(const mpm_config *cfg, const mpm_coupling_type *chosen) {
  int n;
  const mpm_coupling_type *const *types = mpm_coupling_types(&n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < types[k]->nkeys; ++j) {
      const char *key = types[k]->keys[j].key;
      if (types[k] != chosen && !declares(chosen, key) &&
          mpm_config_set_off_default(cfg, &types[k]->keys[j]))
        return mpm_config_fail(cfg, key,
                               "is a key of the %s scheme, and coupling.scheme = %s does not read "
                               "it; remove it or choose coupling.scheme = %s",
                               types[k]->name, chosen->name, types[k]->name);
    }
  return 0;
}

/* The first key under "coupling." given in the case (file or command line), at its default
 * value or not, or NULL: every key of the schema in that section, so a key of a time scheme
 * counts as one of a spatial scheme does. */
static const char *first_coupling_key(const mpm_config *cfg) {
  static const char prefix[] = "coupling.";
  const mpm_key_spec *sp;
  for (size_t k = 0; (sp = mpm_config_spec(cfg, k)) != NULL; ++k)
    if (strncmp(sp->key, prefix, sizeof prefix - 1) == 0 && mpm_config_has(cfg, sp->key))
      return sp->key;
  return NULL;
}

static const mpm_coupling_type *find_type(const char *name) {
  int n;
  const mpm_coupling_type *const *types = mpm_coupling_types(&n);
  for (int k = 0; k < n; ++k)
    if (strcmp(types[k]->name, name) == 0) return types[k];
  return NULL;
}

/* The modules by role; two of one role cannot be coupled by these schemes. */
static int find_roles(mpm_coupling *c, const mpm_config *cfg, mpm_module **mods, int nmod) {
  for (int k = 0; k < nmod; ++k) {
    const mpm_role r = mods[k]->role;
    if (c->module[r])
      return mpm_config_fail(cfg, "coupling.scheme",
                             "the scene has two %s modules; a coupling scheme joins one solid "
                             "and one gas",
                             r == MPM_ROLE_SOLID ? "solid" : "fluid");
    c->module[r] = mods[k];
    c->phase[r] = mods[k]->phase;
  }
  return 0;
}

static int build(mpm_coupling *c, const mpm_config *cfg, mpm_module **mods, int nmod) {
  mpm_grid *g = c->grid;
  MPM_CALL(find_roles(c, cfg, mods, nmod));
  MPM_ALLOC(c->owned, g->nnodes);
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    c->owned[l] = (unsigned char)mpm_grid_node_is_owned(g, l);
  if (c->type->needs & MPM_COUPLING_NORMALS) { /* the schemes read the solid's normal only */
    g->phase[c->phase[MPM_ROLE_SOLID]].normals = 1;
    mpm_walls w;
    MPM_CALL(mpm_walls_from_config(&w, cfg, g->dim));
    MPM_ALLOC(c->wall_axes, g->nnodes);
    for (mpm_lidx l = 0; l < g->nnodes; ++l) {
      int gi[MPM_MAX_DIM];
      mpm_grid_node_global(g, l, gi);
      c->wall_axes[l] = 0;
      for (int d = 0; d < g->dim; ++d)
        for (int side = 0; side < 2; ++side) {
          const mpm_wall k = w.face[d][side];
          if ((k == MPM_WALL_SLIP || k == MPM_WALL_NO_SLIP) && gi[d] == (side ? g->ncells[d] : 0))
            c->wall_axes[l] |= (unsigned char)(1u << d);
        }
    }
  }
  const mpm_module *solid = c->module[MPM_ROLE_SOLID];
  const int nb =
      solid->ops->bodies ? solid->ops->bodies(solid, c->body_name, MPM_COUPLING_MAX_BODIES) : 1;
  if (nb > 1 && nb <= MPM_COUPLING_MAX_BODIES && solid->ops->body_loads) {
    c->nbodies = nb;
    for (int d = 0; d < g->dim; ++d) MPM_ALLOC(c->da[d], g->nnodes);
  }
  for (int d = 0; c->type->needs & (MPM_COUPLING_HOLDS | MPM_COUPLING_RELAXES) && d < g->dim; ++d) {
    MPM_ALLOC(c->held_v[d], g->nnodes);
    MPM_ALLOC(c->held_a[d], g->nnodes);
  }
  if (c->type->needs & (MPM_COUPLING_RELAXES | MPM_COUPLING_RATE))
    MPM_CALL(mpm_config_get_real(cfg, "coupling.mol_rate", &c->relax_share));
  if (c->type->ops->create) MPM_CALL(c->type->ops->create(c, cfg));
  if (c->type->ops->setup) MPM_CALL(c->type->ops->setup(c));
  return 0;
}

/* No particle of one module may sit in space another keeps to itself (a solid inside a static
 * obstacle of the gas). The lowest rank with an offender reports it. */
static int check_reserved(const mpm_config *cfg, mpm_grid *grid, mpm_module **mods, int nmod) {
  for (int k = 0; k < nmod; ++k) {
    if (!mods[k]->ops->reserved) continue;
    for (int j = 0; j < nmod; ++j) {
      const mpm_particles *p = mods[j]->particles;
      const char *key = NULL;
      double x[3] = {0, 0, 0};
      for (mpm_lidx i = 0; j != k && i < p->n && !key; ++i) {
        for (int d = 0; d < p->dim; ++d) x[d] = mpm_particles_comp(p, 0, d)[i];
        key = mods[k]->ops->reserved(mods[k], x);
      }
      int mine = key ? grid->rank : grid->size, who;
      MPM_CALL_MPI(MPI_Allreduce(&mine, &who, 1, MPI_INT, MPI_MIN, grid->comm));
      if (who == grid->size) continue;
      char msg[256] = "";
      if (grid->rank == who)
        snprintf(msg, sizeof msg, "%s|a %s particle at (%g, %g%s) lies inside this obstacle", key,
                 mods[j]->name, x[0], x[1], grid->dim == 3 ? ", ..." : "");
      MPM_CALL_MPI(MPI_Bcast(msg, sizeof msg, MPI_CHAR, who, grid->comm));
      char *bar = strchr(msg, '|');
      *bar = '\0';
      return mpm_config_fail(cfg, msg,
                             "%s; a solid must not overlap a static obstacle: move one of them, or "
                             "make the obstacle a [solid.NAME] with material = rigid",
                             bar + 1);
    }
  }
  return 0;
}

int mpm_coupling_new(mpm_coupling **cp, const mpm_config *cfg, mpm_grid *grid, mpm_module **mods,
                     int nmod) {
  const char *name;
  *cp = NULL;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.scheme", &name));
  const mpm_coupling_type *type = find_type(name);
  if (!type) return mpm_config_fail(cfg, "coupling.scheme", "unknown scheme '%s'", name);
  if (nmod < 2) {
    const char *key = first_coupling_key(cfg);
    if (key)
      return mpm_config_fail(cfg, key,
                             "%s has no effect: the scene has no %s, so there is nothing to "
                             "couple; remove it",
                             key, nmod == 1 && mods[0]->role == MPM_ROLE_SOLID ? "gas" : "solid");
    return 0;
  }
  MPM_CALL(check_foreign_keys(cfg, type));
  MPM_CALL(check_reserved(cfg, grid, mods, nmod));
  if (strcmp(type->name, "none") == 0) return 0;
  mpm_coupling *c;
  MPM_ALLOC(c, 1);
  *cp = c;
  c->type = type, c->grid = grid;
  const int rc = build(c, cfg, mods, nmod);
  if (rc) {
    mpm_coupling_destroy(cp);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  mpm_log(MPM_LOG_INFO, "coupling: %s", type->name);
  return 0;
}

void mpm_coupling_destroy(mpm_coupling **cp) {
  if (!cp || !*cp) return;
  mpm_coupling *c = *cp;
  if (c->type->ops->destroy) c->type->ops->destroy(c);
  free(c->owned), free(c->wall_axes);
  mpm_coupling_levels_free(c);
  for (int d = 0; d < MPM_MAX_DIM; ++d) free(c->da[d]), free(c->held_v[d]), free(c->held_a[d]);
  free(c);
  *cp = NULL;
}

/* ---- hooks ------------------------------------------------------------------------------ */

/* A first pass starts a record: a new time a new one, the same time (a re-evaluation) replaces
 * the latest. */
static void begin_record(mpm_coupling *c, double t, double h) {
  mpm_coupling_record *cur = &c->rec[mpm_rhs_records_begin(&c->which, t, h)];
  memset(cur, 0, sizeof *cur);
  for (int d = 0; c->nbodies && d < c->grid->dim; ++d)
    memset(c->da[d], 0, sizeof(double) * (size_t)c->grid->nnodes);
}

typedef int (*hook_fn)(mpm_coupling *c, double t, double h, mpm_pass pass);

static int run_hook(mpm_coupling *c, hook_fn fn, double t, double h, mpm_pass pass) {
  if (!fn) return 0;
  mpm_timer_start(MPM_T_COUPLING);
  c->recording = pass == MPM_PASS_FIRST;
  const int rc = mpm_coupling_each_level(c, fn, t, h, pass);
  c->recording = 0;
  mpm_timer_stop(MPM_T_COUPLING);
  return rc;
}

int mpm_coupling_before_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  if (!c) return 0;
  if (pass == MPM_PASS_FIRST) begin_record(c, t, h);
  return run_hook(c, c->type->ops->before_solve, t, h, pass);
}

/* MPM_COUPLING_HOLDS: the solid's nodal v and a as the scheme's after_solve left them. */
static int save_held(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)h, (void)pass;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const size_t bytes = sizeof(double) * (size_t)c->grid->nnodes;
  for (int d = 0; d < c->grid->dim; ++d)
    memcpy(c->held_v[d], s->v_i[d], bytes), memcpy(c->held_a[d], s->a_i[d], bytes);
  return 0;
}

/* The hybrid pressure beside a solid (fluid/fluid_gridp_solid.c) continues the gas's pressure
 * through the solid, and its span integrals put forces on the nodes where the gas has no mass
 * and the solid has: the solid's quadrature of its defect from the gas's pressure, which at rest
 * cancels its prestress node by node. The gas's solve drops them; here the solid takes them,
 * booked as an interface exchange (the gas's record the opposite force at the power the solid's
 * takes), so that momentum stays exact. Before the scheme's exchange: these nodes are not
 * shared. */
static int hand_over(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  mpm_grid_phase *s = &c->grid->phase[c->phase[MPM_ROLE_SOLID]];
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    if (g->m_i[l] > g->m_empty || !(s->m_i[l] > s->m_empty)) continue;
    double v[MPM_MAX_DIM], a[MPM_MAX_DIM], f[MPM_MAX_DIM], vc[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) {
      const double da = g->f_i[d][l] / s->m_i[l];
      v[d] = s->v_i[d][l] + h * da, a[d] = s->a_i[d][l] + da;
      vc[d] = h > 0 ? 0.5 * (s->v_i[d][l] - h * s->a_i[d][l] + v[d]) : s->v_i[d][l];
    }
    mpm_coupling_exchange_force(c, MPM_ROLE_SOLID, l, v, a, h, f);
    for (int d = 0; d < dim; ++d) f[d] = -f[d];
    mpm_coupling_record_force(c, MPM_ROLE_FLUID, l, f, vc);
  }
  return 0;
}

/* Does this pass relax the phases' own velocities at the shared nodes (mpm_coupling.h)? */
static int relaxes(const mpm_coupling *c, double h, mpm_pass pass) {
  return c->type->needs & MPM_COUPLING_RELAXES && h == 0 && pass == MPM_PASS_FIRST &&
         c->relax_rate > 0;
}

/* The method of lines' relaxation of the phases' own velocities (mpm_coupling.h, relax_rate):
 * at a shared node, in each component no constraint has set since after_solve, the phases
 * exchange the force k mu (u_g - u_s), u their deposited velocities mv / m and mu = m_s m_g /
 * (m_s + m_g), or its part along the normal where the scheme ties the phases along it alone
 * (relax_normal); it conserves momentum node by node and removes k mu |u_g - u_s|^2 (its
 * normal part) of the particles' kinetic energy, which is the power it books. */
static int relax(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)h, (void)pass;
  mpm_grid_phase *s = &c->grid->phase[c->phase[MPM_ROLE_SOLID]];
  mpm_grid_phase *g = &c->grid->phase[c->phase[MPM_ROLE_FLUID]];
  const int dim = c->grid->dim;
  const double k = c->relax_rate;
  int (*along)(const mpm_coupling *, mpm_lidx, double *) = c->type->ops->relax_normal;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    if (!mpm_coupling_shared(c, l)) continue;
    const double ms = s->m_i[l], mg = g->m_i[l], mu = ms * mg / (ms + mg);
    double f[MPM_MAX_DIM], us[MPM_MAX_DIM], ug[MPM_MAX_DIM], n[MPM_MAX_DIM], un = 0.0;
    for (int d = 0; d < dim; ++d) us[d] = s->mv_i[d][l] / ms, ug[d] = g->mv_i[d][l] / mg;
    const int normal = along && along(c, l, n);
    for (int d = 0; normal && d < dim; ++d) un += (ug[d] - us[d]) * n[d];
    int any = 0;
    for (int d = 0; d < dim; ++d) {
      f[d] = 0.0;
      if (s->v_i[d][l] != c->held_v[d][l] || s->a_i[d][l] != c->held_a[d][l]) continue;
      f[d] = k * mu * (normal ? un * n[d] : ug[d] - us[d]);
      s->a_i[d][l] += f[d] / ms, g->a_i[d][l] -= f[d] / mg;
      any = 1;
    }
    if (!any) continue;
    mpm_coupling_record_force(c, MPM_ROLE_SOLID, l, f, us);
    for (int d = 0; d < dim; ++d) f[d] = -f[d];
    mpm_coupling_record_force(c, MPM_ROLE_FLUID, l, f, ug);
  }
  return 0;
}

int mpm_coupling_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  if (!c) return 0;
  if (c->hand_over) MPM_CALL(run_hook(c, hand_over, t, h, pass));
  MPM_CALL(run_hook(c, c->type->ops->after_solve, t, h, pass));
  if (c->type->needs & MPM_COUPLING_HOLDS || relaxes(c, h, pass))
    MPM_CALL(run_hook(c, save_held, t, h, pass));
  return 0;
}

/* MPM_COUPLING_HOLDS: the gas takes the solid's velocity in the components the solid's own
 * constraints changed since after_solve. */
static int follow_held(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    if (!mpm_coupling_shared(c, l)) continue;
    unsigned held = 0;
    for (int d = 0; d < c->grid->dim; ++d)
      if (s->v_i[d][l] != c->held_v[d][l] || (h == 0 && s->a_i[d][l] != c->held_a[d][l]))
        held |= 1u << d;
    if (held) mpm_coupling_follow_solid(c, l, h, held);
  }
  return 0;
}

int mpm_coupling_after_constrain(mpm_coupling *c, double t, double h, mpm_pass pass) {
  if (!c) return 0;
  if (c->type->needs & MPM_COUPLING_HOLDS) MPM_CALL(run_hook(c, follow_held, t, h, pass));
  MPM_CALL(run_hook(c, c->type->ops->after_constrain, t, h, pass));
  if (relaxes(c, h, pass)) MPM_CALL(run_hook(c, relax, t, h, pass));
  if (pass == MPM_PASS_FIRST) mpm_coupling_record_inside(c);
  return 0;
}

/* Add the gas mass on this level's owned nodes inside the solid to the latest record. */
static int add_inside(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)h, (void)pass;
  const mpm_grid *g = c->grid;
  const double *ms = g->phase[c->phase[MPM_ROLE_SOLID]].m_i;
  const double *mf = g->phase[c->phase[MPM_ROLE_FLUID]].m_i;
  const double mmax = g->phase[c->phase[MPM_ROLE_SOLID]].m_max;
  double inside = 0.0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    if (c->owned[l] && ms[l] >= 0.9 * mmax && mmax > 0) inside += mf[l];
  c->rec[c->which.latest].gas_inside += inside;
  return 0;
}

void mpm_coupling_record_inside(mpm_coupling *c) {
  /* Interpenetration: gas mass on the owned nodes inside the solid, those with at least 90 %
   * of the largest solid nodal mass of the grid (full support: the stencil is covered); on a
   * hierarchy, of every level (the largest over all levels, mpm_hier_phase_update: the finest
   * level's when the solid lies on it, mpm_refine.h). */
  mpm_timer_start(MPM_T_COUPLING);
  c->rec[c->which.latest].gas_inside = 0.0;
  mpm_coupling_each_level(c, add_inside, 0.0, 0.0, MPM_PASS_FIRST);
  mpm_timer_stop(MPM_T_COUPLING);
}

/* ---- for the schemes ---------------------------------------------------------------------- */

void mpm_coupling_exchange(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *v,
                           const double *a, double h) {
  mpm_coupling_exchange_force(c, role, l, v, a, h, NULL);
}

void mpm_coupling_exchange_force(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *v,
                                 const double *a, double h, double *f) {
  mpm_grid_phase *ph = &c->grid->phase[c->phase[role]];
  const int dim = c->grid->dim;
  const double m = ph->m_i[l];
  double force[MPM_MAX_DIM], parts[MPM_MAX_DIM], power = 0.0;
  mpm_impulse_apply_parts(ph, dim, l, v, a, h, force, parts);
  for (int d = 0; d < dim; ++d) power += parts[d];
  for (int d = 0; f && d < dim; ++d) f[d] = force[d];
  if (c->capture && role == MPM_ROLE_SOLID)
    for (int d = 0; d < dim; ++d)
      c->capture->capture[d][l] += force[d], c->capture->booked[d][l] += parts[d];
  if (c->recording && c->nbodies && role == MPM_ROLE_SOLID)
    for (int d = 0; d < dim; ++d) c->da[d][l] += force[d] / m;
  if (!c->recording || !c->owned[l]) return;
  mpm_coupling_record *r = &c->rec[c->which.latest];
  for (int d = 0; d < dim; ++d) r->force[role][d] += force[d];
  r->power[role] += power;
}

void mpm_coupling_record_force(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *f,
                               const double *v) {
  if (c->capture && role == MPM_ROLE_SOLID)
    for (int d = 0; d < c->grid->dim; ++d)
      c->capture->capture[d][l] += f[d], c->capture->booked[d][l] += f[d] * v[d];
  if (c->recording && c->nbodies && role == MPM_ROLE_SOLID)
    for (int d = 0; d < c->grid->dim; ++d)
      c->da[d][l] += f[d] / mpm_coupling_phase(c, role)->m_i[l];
  if (!c->recording || !c->owned[l]) return;
  mpm_coupling_record *r = &c->rec[c->which.latest];
  for (int d = 0; d < c->grid->dim; ++d) r->force[role][d] += f[d], r->power[role] += f[d] * v[d];
}

void mpm_coupling_follow_solid(mpm_coupling *c, mpm_lidx l, double h, unsigned axes) {
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  int differ = 0;
  double v[MPM_MAX_DIM], a[MPM_MAX_DIM], f[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) {
    const mpm_grid_phase *from = axes >> d & 1u ? s : g;
    v[d] = from->v_i[d][l], a[d] = from->a_i[d][l];
    differ |= v[d] != g->v_i[d][l] || (h == 0 && a[d] != g->a_i[d][l]);
  }
  if (!differ) return;
  mpm_coupling_exchange_force(c, MPM_ROLE_FLUID, l, v, a, h, f);
  for (int d = 0; d < dim; ++d) f[d] = -f[d];
  mpm_coupling_record_force(c, MPM_ROLE_SOLID, l, f, v);
}

int mpm_coupling_apply_load(mpm_coupling *c, double t, double h, const double *const *load,
                            const double *m_start) {
  mpm_timer_start(MPM_T_COUPLING);
  begin_record(c, t, h);
  c->recording = 1;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const int dim = c->grid->dim;
  MPM_PHASE_FOR(c->grid, s, l) {
    if (!mpm_coupling_has_mass(c, MPM_ROLE_SOLID, l)) continue;
    const double m = m_start[l] > s->m_i[l] ? m_start[l] : s->m_i[l];
    double v[MPM_MAX_DIM], a[MPM_MAX_DIM];
    int any = 0;
    for (int d = 0; d < dim; ++d) {
      const double q = load[d][l] / m;
      any |= q != 0.0;
      v[d] = s->v_i[d][l] + h * q, a[d] = s->a_i[d][l] + q;
    }
    if (any) mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, v, a, h);
  }
  c->recording = 0;
  mpm_timer_stop(MPM_T_COUPLING);
  return 0;
}

void mpm_coupling_apply_shared(mpm_coupling *c, double h, const double *m_gas,
                               const double *const *f_gas, const double *const *v_gas,
                               double *const *v_out, unsigned char *touched) {
  mpm_timer_start(MPM_T_COUPLING);
  c->recording = 1;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    const double mg = m_gas[l];
    touched[l] = 0;
    if (!(mg > 0.0)) continue;
    const int solid = mpm_coupling_has_mass(c, MPM_ROLE_SOLID, l);
    const double ms = solid ? s->m_i[l] : 0.0, inv = 1.0 / (ms + mg);
    double v[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d)
      v_out[d][l] = v[d] =
          ((solid ? ms * s->v_i[d][l] : 0.0) + mg * v_gas[d][l] + h * f_gas[d][l]) * inv;
    if (!solid) continue;
    touched[l] = 1;
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, v, NULL, h);
  }
  c->recording = 0;
  mpm_timer_stop(MPM_T_COUPLING);
}

void mpm_coupling_book_constrained(mpm_coupling *c, const mpm_interface *ifc, double h) {
  if (!(h > 0)) return;
  mpm_timer_start(MPM_T_COUPLING);
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  double *power = &c->rec[c->which.latest].power[MPM_ROLE_SOLID];
  for (int d = 0; d < c->grid->dim; ++d) MPM_PHASE_FOR(c->grid, s, l) {
      const double f = ifc->capture[d][l], v = s->v_i[d][l], v0 = ifc->v_solved[d][l];
      if (!c->owned[l] || (f == 0.0 && ifc->booked[d][l] == 0.0) || v == v0) continue;
      const double vn = v0 - h * ifc->a_solved[d][l]; /* the exchanges keep v - h a */
      *power += f * 0.5 * (vn + v) - ifc->booked[d][l];
    }
  mpm_timer_stop(MPM_T_COUPLING);
}

void mpm_coupling_follow_shared(mpm_coupling *c, double t, double h, const double *const *v,
                                const unsigned char *touched) {
  mpm_timer_start(MPM_T_COUPLING);
  begin_record(c, t, h);
  c->recording = 1;
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    if (!touched[l] || !mpm_coupling_has_mass(c, MPM_ROLE_FLUID, l)) continue;
    double vl[MPM_MAX_DIM], f[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) vl[d] = v[d][l];
    mpm_coupling_exchange_force(c, MPM_ROLE_FLUID, l, vl, NULL, h, f);
    for (int d = 0; c->capture && d < dim; ++d) c->capture->capture[d][l] -= f[d];
  }
  c->recording = 0;
  mpm_timer_stop(MPM_T_COUPLING);
}

int mpm_coupling_body_loads(mpm_coupling *c, const double *y_solid) {
  if (!c || !c->nbodies) return 0;
  mpm_timer_start(MPM_T_COUPLING);
  mpm_module *solid = c->module[MPM_ROLE_SOLID];
  int rc = mpm_grid_halo_forward(c->grid, c->da, c->grid->dim);
  if (!rc)
    rc = solid->ops->body_loads(solid, y_solid, (const double *const *)c->da,
                                &c->rec[c->which.latest].body[0][0]);
  mpm_timer_stop(MPM_T_COUPLING);
  return rc;
}

/* The unit normal from the solid's mass gradient at node l (less its component across a wall
 * the node lies on, if `walls`), or 0 where the gradient is below kappa m_s / dx. */
static int unit_normal(const mpm_coupling *c, mpm_lidx l, int walls, double kappa, double *n) {
  const mpm_grid_phase *ph = &c->grid->phase[c->phase[MPM_ROLE_SOLID]];
  const int dim = c->grid->dim;
  double g[MPM_MAX_DIM], len = 0.0;
  for (int d = 0; d < dim; ++d) {
    g[d] = walls && c->wall_axes[l] >> d & 1u ? 0.0 : ph->normal_i[d][l];
    len += g[d] * g[d];
  }
  len = sqrt(len);
  if (!(len > kappa * ph->m_i[l] / c->grid->dx)) return 0;
  for (int d = 0; d < dim; ++d) n[d] = g[d] / len;
  return 1;
}

int mpm_coupling_solid_surface(const mpm_coupling *c, mpm_lidx l, double kappa, double *n) {
  return unit_normal(c, l, 1, kappa, n);
}

int mpm_coupling_solid_normal(const mpm_coupling *c, mpm_lidx l, double *n) {
  /* A gradient below roundoff of m / dx: the node is deep inside or alone. */
  return unit_normal(c, l, 0, 1e-12, n);
}

int mpm_coupling_step_record(mpm_coupling *c, double t, mpm_coupling_record *out) {
  memset(out, 0, sizeof *out);
  if (!c) return 0;
  const mpm_coupling_record *use = &c->rec[mpm_rhs_records_pick(&c->which, t)];
  enum { N = 2 * MPM_MAX_DIM + 3 };
  double local[N], sum[N];
  memcpy(local, use->force, sizeof use->force);
  local[2 * MPM_MAX_DIM] = use->power[0], local[2 * MPM_MAX_DIM + 1] = use->power[1];
  local[2 * MPM_MAX_DIM + 2] = use->gas_inside;
  MPM_CALL_MPI(MPI_Allreduce(local, sum, N, MPI_DOUBLE, MPI_SUM, c->grid->comm));
  memcpy(out->force, sum, sizeof out->force);
  out->power[0] = sum[2 * MPM_MAX_DIM], out->power[1] = sum[2 * MPM_MAX_DIM + 1];
  out->gas_inside = sum[2 * MPM_MAX_DIM + 2];
  if (c->nbodies)
    MPM_CALL_MPI(MPI_Allreduce(use->body, out->body, MPM_COUPLING_MAX_BODIES * MPM_MAX_DIM,
                               MPI_DOUBLE, MPI_SUM, c->grid->comm));
  return 0;
}
