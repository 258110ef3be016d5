/* The gas on a static refinement hierarchy (mpm_hier.h; docs/refinement.md): what of the gas
 * this slice carries to the finer levels, the transfers that go through the hierarchy, and the
 * seeding of the finer levels.
 *
 * Carried: the plain transfers of the method-of-lines RHS (the ERK pairs): the deposit of mass,
 * momentum, pressure, gravity and the viscous stresses (fluid.strain_rate = current's preview
 * and fluid.mol_damping's filter included) goes through mpm_hier_p2g, every gather of v, a and L
 * through mpm_hier_g2p; the coupler restricts, solves on every level and prolongs
 * (coupler/mpm_cycle.c). The artificial viscosity of a particle takes the spacing of the level
 * it deposits on (its position's) as its length, as on a uniform grid of that spacing, and the
 * stable step is the smallest over the particles of that spacing over their signal speed
 * (fluid_module.c). Slip and no-slip walls act on every level (mpm_hier.h, walls: the finer levels
 * fold and mirror their nodes beyond a wall in fluid_module.c's forces and constrain); the sim
 * keeps every box three level-0 cells from the other non-periodic faces (coupler/mpm_refine.c).
 * Open faces (inflow, outflow, subsonic, far field with its sponge) therefore act on level 0
 * alone: their particles are injected and removed within two level-0 cells of the face, on
 * level 0's lattice and size, and the grid pressure that the hierarchy needs takes their
 * exterior pressure as an exact face integral on level 0 (fluid_open_grid_forces); the sponge
 * acts on each particle, of any level. The classic update (usl, musl): its transfer forms the
 * time-centred nodal velocity and the heat shares' scalars on every level and gathers through
 * the hierarchy, and weighs its wall rule at the particle's level spacing (fluid_transfer.c);
 * MUSL's remap deposits through the hierarchy (fluid_module.c) and the coupler restricts it; the
 * grid pressure runs with both (fluid_gridp.c). Obstacles (ghost treatment) act on every level:
 * the constraint on each level's active nodes and the ghosts through the grid pressure's spans
 * (fluid_obstacle_levels.c).
 *
 * Regularisation, refill, the light merges and the neighbourhood stable step count particles in
 * each level's cells (fluid_regularise.c, fluid_stable.c; mpm_cells_count_levels).
 *
 * Refused (fluid_refine_check), each naming its key: everything that reads or writes the gas's
 * nodal fields or the grid otherwise: the domain volume rate, the riemann viscosity's limiter,
 * shifting, the least-squares wall treatment. The light-node threshold compares each level's nodes
 * with the mean at that level's spacing (mpm_grid_phase_update_many). An odd fluid.ppc puts level-0
 * particles on the span faces that bound the finer regions, so it is refused too.
 *
 * Invariant: with m->hier NULL every call here is the plain kernel call (the refined path costs
 * one pointer test per transfer). */
#include "fluid_eos.h"
#include "fluid_internal.h"
#include "fluid_module.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

void fluid_p2g_any(mpm_module *m, int phase, const mpm_p2g_args *a, int *rc) {
  if (m->hier) {
    if (!*rc) *rc = mpm_hier_p2g(m->hier, phase, a);
    return;
  }
  mpm_kernels_get(m->grid->dim)->p2g(m->grid, phase, a);
}

int fluid_g2p_phase(mpm_module *m, const double *y, double *const *v_out, double *const *a_out,
                    double *L_out, const mpm_hier_scalars *s, double *const *s_out, int ns) {
  const mpm_particles *p = m->particles;
  const mpm_grid_phase *ph = &m->grid->phase[m->phase];
  mpm_g2p_args a = {.n = p->n, .lp = ((fluid_content *)m->content)->lp, .L_out = L_out};
  for (int d = 0; d < p->dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * p->n;
    a.v_i[d] = ph->v_i[d], a.a_i[d] = ph->a_i[d];
    a.v_out[d] = v_out[d], a.a_out[d] = a_out[d];
  }
  for (int j = 0; j < ns; ++j) a.s_i[j] = s->s_i[0][j], a.s_out[j] = s_out[j];
  a.nscalar = ns;
  if (!m->hier) {
    mpm_kernels_get(p->dim)->g2p(m->grid, &a);
    return 0;
  }
  return mpm_hier_g2p(m->hier, m->phase, &a, ns > 0 ? s : NULL);
}

double fluid_finest_dx(const mpm_module *m) {
  const mpm_hier *h = m->hier;
  return h ? h->level[h->nlevels - 1].grid->dx : m->grid->dx;
}

const unsigned char *fluid_position_levels(const mpm_module *m, const double *y) {
  const mpm_particles *p = m->particles;
  if (!m->hier) return NULL;
  const double *x[MPM_MAX_DIM];
  for (int d = 0; d < p->dim; ++d) x[d] = y + (size_t)(p->offset[FLUID_X] + d) * p->n;
  return mpm_hier_levels(m->hier, x, p->n);
}

int fluid_position_level_of(const mpm_module *m, const double *y, mpm_lidx i) {
  const mpm_particles *p = m->particles;
  double x[MPM_MAX_DIM] = {0, 0, 0};
  for (int d = 0; d < p->dim; ++d) x[d] = y[(size_t)(p->offset[FLUID_X] + d) * p->n + i];
  return mpm_hier_level_of(m->hier, x);
}

void fluid_av_lengths(mpm_module *m, const double *y) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  if (!fc->refined) return;
  if (!m->hier) {
    for (mpm_lidx i = 0; i < p->n; ++i) fc->av_l[i] = m->grid->dx;
    return;
  }
  const unsigned char *lev = fluid_position_levels(m, y);
  double h[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < m->hier->nlevels; ++l) h[l] = m->hier->level[l].grid->dx;
  if (lev && p->n > 0) memcpy(fc->lev, lev, (size_t)p->n);
  for (mpm_lidx i = 0; !lev && i < p->n; ++i)
    fc->lev[i] = (unsigned char)fluid_position_level_of(m, y, i);
  for (mpm_lidx i = 0; i < p->n; ++i) fc->av_l[i] = h[fc->lev[i]];
  mpm_hier_levels_known(m->hier, y + (size_t)p->offset[FLUID_X] * p->n, p->n, fc->lev);
}

/* ---- what the slice refuses ------------------------------------------------------------------ */

static int refuse(const mpm_config *cfg, const char *key, const char *why) {
  return mpm_config_fail(cfg, key,
                         "not carried to the refined levels (refine.levels > 1): %s; remove the "
                         "key or set refine.levels = 1 (docs/refinement.md)",
                         why);
}

/* A key set to a value other than off: an enum choice, or a number above zero. */
static int is_choice(const mpm_config *cfg, const char *key, const char *choice) {
  const char *v;
  return mpm_config_get_string(cfg, key, &v) == 0 && strcmp(v, choice) == 0;
}

static int is_positive(const mpm_config *cfg, const char *key) {
  double v = 0.0;
  return mpm_config_get_real(cfg, key, &v) == 0 && v > 0.0;
}

typedef struct refusal {
  const char *key, *choice; /* choice NULL: refused when > 0 */
  const char *why;
} refusal;

static const refusal g_refused[] = {
    {"fluid.volume_rate", "domain", "the domain rate samples the nodal velocity on level 0"},
    {"fluid.av_form", "riemann", "the riemann limiter reads the nodal velocity on level 0"},
    {"fluid.shift", NULL, "shifting reads the nodal volume fraction on level 0"},
    {"fluid.wall_treatment", "least_squares",
     "the least-squares wall fits the particles in level-0 cells and books heat on level 0's "
     "nodes"},
};

int fluid_refine_check(const mpm_module *m, const mpm_config *cfg) {
  const fluid_content *fc = m->content;
  for (size_t k = 0; k < sizeof g_refused / sizeof g_refused[0]; ++k) {
    const refusal *r = &g_refused[k];
    if (r->choice ? is_choice(cfg, r->key, r->choice) : is_positive(cfg, r->key))
      return refuse(cfg, r->key, r->why);
  }
  if (fc->ppc % 2)
    return mpm_config_fail(
        cfg, "fluid.ppc",
        "with refinement the gas needs an even count, so that no level-0 particle "
        "sits on the faces of the refined region (an odd lattice puts one "
        "there); use %d",
        fc->ppc + 1);
  return 0;
}

int fluid_module_refine(mpm_module *m, const mpm_config *cfg, mpm_hier *h, int seed) {
  MPM_CALL(fluid_refine_check(m, cfg));
  MPM_CALL(fluid_gridp_refine(m, cfg, h));
  ((fluid_content *)m->content)->refined = 1;
  fluid_module_rehier(m, h);
  return seed && h ? fluid_seed_refined(m, cfg) : 0;
}

int fluid_module_follow(mpm_module *m, int *changed) {
  return fluid_relevel(m, 1, changed);
}

void fluid_module_rehier(mpm_module *m, mpm_hier *h) {
  m->hier = h;
  fluid_gridp_reset(m->content);
  fluid_lnode_free(m->content);
}

void fluid_lnode_free(fluid_content *fc) {
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l) free(fc->lnode[l]), fc->lnode[l] = NULL;
}

/* ---- the refinement criteria (mpm_refine.c regrids with them) ---------------------------- */

/* The span of x along axis d: its nearest node, wrapped along a periodic axis, clamped. */
static int span_of(const mpm_grid *g, int d, double x, int n) {
  long i = lround((x - g->lo[d]) / g->dx);
  if (g->periodic[d]) i = ((i % n) + n) % n;
  return (int)(i < 0 ? 0 : i >= n ? n - 1 : i);
}

/* Sum a binning of the particles over the ranks, so that every rank flags the same cells (one
 * rank: nothing to do). */
static int sum_ranks(const mpm_grid *g, double *a, size_t n) {
  if (g->size == 1) return 0;
  if (n > (size_t)INT_MAX) MPM_FAIL(MPM_ERR_INTERNAL, "regrid: %zu level-0 cells to sum", n);
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, a, (int)n, MPI_DOUBLE, MPI_SUM, g->comm));
  return 0;
}

/* Does the face between spans s and t (t above s along d) ask for refinement? sums: mass,
 * volume, internal energy m e, then momentum per axis, each of total entries. */
static int face_flag(const fluid_gas *gas, fluid_refine_criterion criterion, double threshold,
                     const double *sums, size_t total, int dim, int d, size_t s, size_t t) {
  const double *mass = sums, *vol = sums + total, *me = sums + 2 * total;
  const double rs = mass[s] / vol[s], rt = mass[t] / vol[t];
  if (criterion == FLUID_REFINE_DENSITY) return fabs(rt - rs) > threshold * fmin(rt, rs);
  /* The velocities against threshold times the slower sound speed of the two. */
  const double cs =
      fluid_sound_speed(gas->gamma, rs, fluid_pressure(gas->gamma, rs, me[s] / mass[s]));
  const double ct =
      fluid_sound_speed(gas->gamma, rt, fluid_pressure(gas->gamma, rt, me[t] / mass[t]));
  const double bound = threshold * fmin(cs, ct);
  double jump = 0.0;
  for (int e = 0; e < dim; ++e) {
    const double *mv = sums + (size_t)(3 + e) * total;
    const double du = mv[t] / mass[t] - mv[s] / mass[s];
    if (criterion == FLUID_REFINE_COMPRESSION && e == d) return -du > bound; /* normal, falls */
    if (e != d) jump = fmax(jump, fabs(du)); /* vorticity: a tangential jump, h |omega| */
  }
  return jump > bound;
}

/* The span of particle i on the flag lattice (strides stride). */
static size_t span_index(const mpm_module *m, const int *n, const size_t *stride, mpm_lidx i) {
  size_t s = 0;
  for (int d = 0; d < m->grid->dim; ++d)
    s += stride[d] *
         (size_t)span_of(m->grid, d, mpm_particles_comp(m->particles, FLUID_X, d)[i], n[d]);
  return s;
}

/* Does every axis neighbour of span s hold gas (count > 0)? A neighbour past a non-periodic
 * end of the lattice does not. */
static int neighbours_hold_gas(const mpm_grid *g, const int *n, const size_t *stride,
                               const double *count, size_t s) {
  for (int d = 0; d < g->dim; ++d) {
    const int i = (int)(s / stride[d] % (size_t)n[d]);
    for (int side = -1; side <= 1; side += 2) {
      int j = i + side;
      if (g->periodic[d]) j = (j + n[d]) % n[d];
      if (j < 0 || j >= n[d] || !(count[s + ((size_t)j - (size_t)i) * stride[d]] > 0)) return 0;
    }
  }
  return 1;
}

/* Starvation: each span's particles in level-0 particles (a particle of size level l counts
 * 2^(-dim l), so that a split, which keeps the gas's sampling of level 0, keeps the count and
 * the region stays while the gas is sparse), flagged below threshold where the gas surrounds
 * the span (a span on the gas's edge is not starved, and empty space is never flagged). */
static int starved_flags(const mpm_module *m, double threshold, const int *n, const size_t *stride,
                         size_t total, unsigned char *flag) {
  const fluid_content *fc = m->content;
  const int dim = m->grid->dim;
  const double V0_0 = pow(m->grid->dx / fc->ppc, dim);
  double *count = calloc(total, sizeof(double));
  if (!count) MPM_FAIL_OOM(total * sizeof(double));
  for (mpm_lidx i = 0; i < m->particles->n; ++i)
    count[span_index(m, n, stride, i)] += ldexp(1.0, -dim * fluid_size_level(m, V0_0, i));
  const int rc = sum_ranks(m->grid, count, total);
  for (size_t s = 0; s < total && !rc; ++s)
    flag[s] = count[s] < threshold && neighbours_hold_gas(m->grid, n, stride, count, s);
  free(count);
  return rc;
}

/* Proximity: the spans that come within `distance` of an obstacle (fluid_module.h). */
static void near_flags(const mpm_module *m, double distance, const int *n, const size_t *stride,
                       size_t total, unsigned char *flag) {
  const fluid_obstacles *o = &((const fluid_content *)m->content)->obs;
  const mpm_grid *g = m->grid;
  const double reach = distance + 0.5 * sqrt((double)g->dim) * g->dx;
  for (size_t s = 0; s < total; ++s) {
    double x[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < g->dim; ++d)
      x[d] = g->lo[d] + (double)(s / stride[d] % (size_t)n[d]) * g->dx;
    for (int k = 0; k < o->count && !flag[s]; ++k)
      flag[s] = fluid_obstacle_phi(&o->ob[k].sdf, g, x, NULL) < reach;
  }
}

int fluid_refine_flags(const mpm_module *m, fluid_refine_criterion criterion, double threshold,
                       const int *n, unsigned char *flag) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = g->dim;
  size_t total = 1, stride[MPM_MAX_DIM] = {1, 1, 1};
  for (int d = 0; d < dim; ++d) stride[d] = total, total *= (size_t)n[d];
  memset(flag, 0, total);
  if (criterion == FLUID_REFINE_STARVATION)
    return starved_flags(m, threshold, n, stride, total, flag);
  if (criterion == FLUID_REFINE_PROXIMITY) {
    near_flags(m, threshold, n, stride, total, flag);
    return 0;
  }
  const size_t nsums = 3 + (size_t)dim; /* mass, volume, m e, m v */
  double *sums = calloc(nsums * total, sizeof(double));
  if (!sums) MPM_FAIL_OOM(nsums * total * sizeof(double));
  const double *pm = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const double *J = mpm_particles_comp(p, FLUID_J, 0);
  const double *e = mpm_particles_comp(p, FLUID_E, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const size_t s = span_index(m, n, stride, i);
    sums[s] += pm[i], sums[total + s] += V0[i] * J[i], sums[2 * total + s] += pm[i] * e[i];
    for (int d = 0; d < dim; ++d)
      sums[(3 + (size_t)d) * total + s] += pm[i] * mpm_particles_comp(p, FLUID_V, d)[i];
  }
  const int rc = sum_ranks(g, sums, nsums * total);
  const double *vol = sums + total;
  for (size_t s = 0; s < total && !rc; ++s) {
    if (!(vol[s] > 0)) continue;
    for (int d = 0; d < dim; ++d) {
      const int i = (int)(s / stride[d] % (size_t)n[d]);
      int j = i + 1;
      if (j == n[d] && g->periodic[d]) j = 0;
      if (j >= n[d]) continue;
      const size_t t = s + ((size_t)j - (size_t)i) * stride[d];
      if (vol[t] > 0 && face_flag(&fc->gas, criterion, threshold, sums, total, dim, d, s, t))
        flag[s] = flag[t] = 1;
    }
  }
  free(sums);
  return rc;
}
