/* The solid on a static refinement hierarchy (mpm_hier.h; docs/refinement.md): the transfers
 * that go through the hierarchy, what the slice refuses, and the seeding of the finer levels.
 *
 * Carried: every deposit of the solid's RHS (mass, momentum, the stress's internal force,
 * gravity and the tractions' external force) goes through mpm_hier_p2g and every gather (v, a,
 * L, dF/dt = L F, the APIC C) through mpm_hier_g2p; the coupler restricts, solves on every
 * level and prolongs (coupler/mpm_cycle.c). Time methods: the ERK pairs and ssprk2 (method of
 * lines) and usl. physics.damping acts on every level. The stable step takes the finest level's
 * spacing. Slip and no-slip walls act on every level (mpm_hier.h, walls; solid_module.c folds and
 * mirrors), clamps hold every level's nodes (solid_clamp_levels); the sim keeps every box three
 * level-0 cells from the other non-periodic faces (coupler/mpm_refine.c).
 *
 * Seeding: the level-0 particles inside the finer regions go, and each level l >= 1 seeds each
 * body's region less the finer ones on its own lattice (mpm_hier_lattice: ppc points per axis
 * and level-l span, volume (h_l / ppc)^dim, the body's initial state). Solid particles never
 * split or merge: one that moves into another level's region later keeps its mass and volume
 * and deposits on, and reads from, the level of its position.
 *
 * Refused (refine_check), each naming its key: a body with a bulk viscosity (its length
 * scale and lagged rate are level 0's) or the projected dilatation (its deposit is level 0's),
 * a rigid body (it holds level-0 nodes), an
 * odd ppc (a level-0 particle would sit on a face of the refined region), time.method = musl
 * (the remap deposits on level 0), and a traction whose region reaches a refined region (the
 * tractions load level-0 particles only). Dynamic regrids are refused by coupler/mpm_refine.c,
 * which also asks a solid beside a gas to lie on the finest level (solid_refine_inside). On
 * several ranks every rank walks a finer level's whole lattice and keeps its own points
 * (mpm_hier_keep_owned), so a particle's id does not depend on the ranks; the hierarchy sums
 * the deposits over the ranks (mpm_hier.h, ranks).
 *
 * Invariant: with m->hier NULL every call here is the plain kernel call, so an unrefined run is
 * bit for bit what it was. */
#include "solid_internal.h"
#include "solid_module.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_hier_seed.h"
#include "mpm_kernels.h"
#include "mpm_log.h"

#include <stdlib.h>
#include <string.h>

int solid_deposit(mpm_module *m, const mpm_p2g_args *a) {
  if (m->hier) return mpm_hier_p2g(m->hier, m->phase, a);
  mpm_kernels_get(m->grid->dim)->p2g(m->grid, m->phase, a);
  return 0;
}

int solid_gather(mpm_module *m, const mpm_g2p_args *a) {
  if (m->hier) return mpm_hier_g2p(m->hier, m->phase, a, NULL);
  mpm_kernels_get(m->grid->dim)->g2p(m->grid, a);
  return 0;
}

double solid_finest_dx(const mpm_module *m) {
  const mpm_hier *h = m->hier;
  return h ? h->level[h->nlevels - 1].grid->dx : m->grid->dx;
}

/* ---- what the slice refuses ------------------------------------------------------------------ */

static int refuse(const mpm_config *cfg, const char *key, const char *why) {
  return mpm_config_fail(cfg, key,
                         "not carried to the refined levels (refine.levels > 1): %s; remove the "
                         "key or set refine.levels = 1 (docs/refinement.md)",
                         why);
}

static int check_body(const mpm_config *cfg, const solid_body *body, int projected) {
  char key[160];
  int ppc;
  if (body->mat->ops->rigid) {
    solid_key(key, sizeof key, body->section, "material");
    return refuse(cfg, key, "a rigid body holds the level-0 nodes inside it");
  }
  if (solid_bulkq_on(&body->q)) {
    solid_key(key, sizeof key, body->section,
              body->q.c1 > 0 ? "bulk_viscosity_linear" : "bulk_viscosity_quadratic");
    return refuse(cfg, key, "the bulk viscosity's length is level 0's cell");
  }
  if (projected) {
    solid_key(key, sizeof key, body->section, "dilatation");
    return refuse(cfg, key, "the projection deposits on level 0's nodes");
  }
  solid_key(key, sizeof key, body->section, "ppc");
  MPM_CALL(mpm_config_get_int(cfg, key, &ppc));
  if (ppc % 2)
    return mpm_config_fail(cfg, key,
                           "with refinement the solid needs an even count, so that no level-0 "
                           "particle sits on the faces of the refined region (an odd lattice "
                           "puts one there); use %d",
                           ppc + 1);
  return 0;
}

static int refine_check(const mpm_module *m, const mpm_config *cfg) {
  const solid_content *sc = m->content;
  if (sc->tr.musl) return refuse(cfg, "time.method", "MUSL's remap deposits on level 0's nodes");
  for (int b = 0; b < sc->nbodies; ++b) MPM_CALL(check_body(cfg, &sc->body[b], sc->dil.body[b]));
  return 0;
}

/* ---- beside a gas: the solid on the finest level -------------------------------------------- */

/* Is y beyond a wall the levels carry (where they mirror the nodes inside)? */
static int beyond_wall(const mpm_hier *h, const double *y) {
  const mpm_grid *g0 = h->level[0].grid;
  for (int d = 0; d < h->dim; ++d)
    if ((h->wall[d][0] && y[d] < g0->lo[d]) || (h->wall[d][1] && y[d] > g0->hi[d])) return 1;
  return 0;
}

/* Do the points of the cube of half-side cells h around x, a lattice of spacing h (the finest
 * region is a union of spans of side 2 h, so no gap escapes it), all lie on the finest level?
 * Points beyond a carried wall do not count: the region touches the wall, and the level
 * mirrors its nodes there. */
static int cube_on_finest(const mpm_hier *h, int dim, const double *x, int cells) {
  const int top = h->nlevels - 1, side = 2 * cells + 1;
  const double dx = h->level[top].grid->dx;
  int total = 1;
  for (int d = 0; d < dim; ++d) total *= side;
  for (int k = 0; k < total; ++k) {
    double y[3] = {x[0], dim > 1 ? x[1] : 0, dim > 2 ? x[2] : 0};
    for (int d = 0, r = k; d < dim; r /= side, ++d) y[d] += (r % side - cells) * dx;
    if (!beyond_wall(h, y) && mpm_hier_level_of(h, y) != top) return 0;
  }
  return 1;
}

int solid_refine_inside(const mpm_module *m, const mpm_config *cfg, int cells) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  if (!m->hier) return 0;
  const double *body = mpm_particles_comp(p, sc->lay.f_body, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double x[3] = {0, 0, 0};
    for (int d = 0; d < p->dim; ++d) x[d] = mpm_particles_comp(p, F_X, d)[i];
    if (cube_on_finest(m->hier, p->dim, x, cells)) continue;
    char key[160];
    solid_key(key, sizeof key, sc->body[(int)body[i]].section, "geometry");
    return mpm_config_fail(cfg, key,
                           "a solid beside a gas must lie on the finest refinement level with %d "
                           "of its cells to spare (every coupling node on that level), and a "
                           "particle at (%g, %g%s) does not; enlarge or add a [refine.NAME] box "
                           "of level %d around the body (docs/refinement.md)",
                           cells, x[0], x[1], p->dim == 3 ? ", ..." : "", m->hier->nlevels - 1);
  }
  return 0;
}

/* ---- regrids beside a gas ------------------------------------------------------------------ */

int solid_refine_spans(const mpm_module *m, const int *n, unsigned char *flag) {
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  size_t total = 1, stride[MPM_MAX_DIM] = {1, 1, 1};
  for (int d = 0; d < g->dim; ++d) stride[d] = total, total *= (size_t)n[d];
  memset(flag, 0, total);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    size_t s = 0;
    for (int d = 0; d < g->dim; ++d) {
      long k = lround((mpm_particles_comp(p, F_X, d)[i] - g->lo[d]) / g->dx);
      k = g->periodic[d] ? ((k % n[d]) + n[d]) % n[d] : k < 0 ? 0 : k >= n[d] ? n[d] - 1 : k;
      s += stride[d] * (size_t)k;
    }
    flag[s] = 1;
  }
  if (g->size > 1) {
    const int mrc = total > (size_t)INT_MAX ? MPI_ERR_COUNT
                                            : MPI_Allreduce(MPI_IN_PLACE, flag, (int)total,
                                                            MPI_UNSIGNED_CHAR, MPI_MAX, g->comm);
    if (mrc != MPI_SUCCESS)
      MPM_FAIL(MPM_ERR_MPI, "regrid: the solid's spans over %zu spans: MPI error %d", total, mrc);
  }
  return 0;
}

int solid_module_rehier(mpm_module *m, struct mpm_hier *h) {
  m->hier = h;
  return solid_clamp_levels(m);
}

/* ---- seeding the finer levels ---------------------------------------------------------------- */

/* Refuse a traction whose region holds one of the n points x (component-major, stride n) that
 * lie on a finer level. */
static int check_tractions(const mpm_module *m, const mpm_config *cfg, mpm_lidx n,
                           const double *x) {
  const solid_content *sc = m->content;
  for (mpm_lidx i = 0; i < n && sc->ntractions > 0; ++i) {
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < m->grid->dim; ++d) xp[d] = x[(size_t)d * n + i];
    if (mpm_hier_level_of(m->hier, xp) == 0) continue;
    for (int k = 0; k < sc->ntractions; ++k)
      if (mpm_region_contains(sc->traction[k].region, xp)) {
        char key[160];
        snprintf(key, sizeof key, "traction.%s.geometry", sc->traction[k].name);
        return refuse(cfg, key,
                      "the traction's region reaches a refined region, and tractions load "
                      "level-0 particles only; keep the region outside the [refine.NAME] boxes "
                      "(and their snapping to level-0 cells)");
      }
  }
  return 0;
}

/* Seed body b on level l. */
static int seed_level(mpm_module *m, const mpm_config *cfg, int b, int l) {
  const solid_content *sc = m->content;
  mpm_particles *p = m->particles;
  const mpm_grid *lg = m->hier->level[l].grid;
  solid_seed s;
  double *x = NULL;
  mpm_gidx *id = NULL, span = 0;
  mpm_lidx n = 0;
  int rc = solid_seed_open(m, cfg, b, &s);
  if (!rc) rc = mpm_hier_lattice(m->hier, l, s.ppc, s.region, &x, &n, &span);
  if (!rc) rc = check_tractions(m, cfg, n, x);
  if (!rc && !(id = malloc(sizeof *id * (size_t)(n ? n : 1)))) rc = MPM_ERR_MEMORY;
  for (mpm_lidx i = 0; !rc && i < n; ++i) id[i] = p->id_next + i;
  const mpm_lidx all = n;
  if (!rc) n = mpm_hier_keep_owned(m->grid, x, id, n);
  if (!rc) rc = solid_seed_append(m, cfg, &s, n, x, id, lg->dx / s.ppc);
  free(x), free(id);
  solid_seed_close(&s);
  MPM_CALL(rc);
  p->id_next += span;
  mpm_log(MPM_LOG_INFO, "solid body %s: %lld particles on level %d", sc->body[b].section,
          (long long)all, l);
  return 0;
}

int solid_module_refine(mpm_module *m, const mpm_config *cfg, mpm_hier *h, int seed) {
  MPM_CALL(refine_check(m, cfg));
  m->hier = h;
  MPM_CALL(solid_clamp_levels(m));
  if (!seed || !h) return 0;
  mpm_particles *p = m->particles;
  MPM_CALL(check_tractions(m, cfg, p->n, mpm_particles_comp(p, F_X, 0)));
  MPM_CALL(mpm_hier_drop_refined(h, p, F_X));
  const solid_content *sc = m->content;
  for (int l = 1; l < h->nlevels; ++l)
    for (int b = 0; b < sc->nbodies; ++b) MPM_CALL(seed_level(m, cfg, b, l));
  return solid_seed_report(m, cfg);
}
