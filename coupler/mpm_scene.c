/* No two bodies share space (see mpm_scene.h).
 *
 * Every seeded particle is tested against the regions of the bodies it does not belong to: a
 * solid particle (its body index in the field "body") against the other [solid.NAME] regions and
 * every [gas.NAME] region, a gas particle against every [solid.NAME] region. "Inside" means
 * inside and still inside when moved by eps along any axis, so a point on a boundary where two
 * bodies meet does not count. A bounding box skips most tests. */
#include "mpm_scene.h"

#include "mpm_error.h"
#include "mpm_geometry.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One region: its section ("solid.NAME" or "gas.NAME"), its geometry key, inside test, bounds. */
typedef struct scene_region {
  char *section, *key;
  const char *geometry; /* the [geometry.NAME] it fills (owned by the configuration) */
  mpm_region *region;
  double lo[3], hi[3];
} scene_region;

/* Regions [0, nsolid) are the solid bodies in file order (the index a solid particle holds in
 * its "body" field), then the gas regions in file order. */
typedef struct scene {
  int dim, nsolid, ngas;
  double eps;
  scene_region *r;
} scene;

static void scene_free(scene *s) {
  for (int k = 0; s->r && k < s->nsolid + s->ngas; ++k) {
    free(s->r[k].section), free(s->r[k].key);
    mpm_region_destroy(&s->r[k].region);
  }
  free(s->r);
  s->r = NULL;
}

static int read_region(scene_region *r, const mpm_config *cfg, int dim, const char *prefix,
                       const char *name) {
  const size_t n = strlen(prefix) + strlen(name) + 16;
  r->section = malloc(n), r->key = malloc(n);
  if (!r->section || !r->key) return MPM_ERR_MEMORY;
  snprintf(r->section, n, "%s.%s", prefix, name);
  snprintf(r->key, n, "%s.%s.geometry", prefix, name);
  MPM_CALL(mpm_config_get_string(cfg, r->key, &r->geometry));
  MPM_CALL(mpm_region_from_config(&r->region, cfg, dim, r->geometry));
  mpm_region_bounds(r->region, r->lo, r->hi);
  return 0;
}

static int scene_read(scene *s, const mpm_config *cfg, const mpm_grid *g) {
  const char *const *solids, *const *gases;
  MPM_CALL(mpm_config_instances(cfg, "solid", &solids, &s->nsolid));
  MPM_CALL(mpm_config_instances(cfg, "gas", &gases, &s->ngas));
  s->dim = g->dim;
  s->eps = 1e-6 * g->dx;
  s->r = calloc((size_t)(s->nsolid + s->ngas) + 1, sizeof *s->r);
  if (!s->r) return MPM_ERR_MEMORY;
  for (int k = 0; k < s->nsolid + s->ngas; ++k)
    MPM_CALL(k < s->nsolid ? read_region(&s->r[k], cfg, g->dim, "solid", solids[k])
                           : read_region(&s->r[k], cfg, g->dim, "gas", gases[k - s->nsolid]));
  return 0;
}

/* Is x inside r by more than eps along every axis? */
static int deep_inside(const scene *s, const scene_region *r, const double *x) {
  for (int d = 0; d < s->dim; ++d)
    if (x[d] < r->lo[d] || x[d] > r->hi[d]) return 0;
  if (!mpm_region_contains(r->region, x)) return 0;
  for (int d = 0; d < s->dim; ++d)
    for (int side = -1; side <= 1; side += 2) {
      double y[3] = {x[0], x[1], x[2]};
      y[d] += side * s->eps;
      if (!mpm_region_contains(r->region, y)) return 0;
    }
  return 1;
}

/* The region of another body that holds x, or -1. own: the particle's solid body, or -1 for a
 * gas particle (the gas regions are all its own). */
static int other_body(const scene *s, int own, const double *x) {
  for (int j = 0; j < s->nsolid; ++j)
    if (j != own && deep_inside(s, &s->r[j], x)) return j;
  for (int j = s->nsolid; own >= 0 && j < s->nsolid + s->ngas; ++j)
    if (deep_inside(s, &s->r[j], x)) return j;
  return -1;
}

/* The gas region that seeded x: the first in the file that contains it (fluid_seed.c). */
static int gas_region_of(const scene *s, const double *x) {
  for (int j = s->nsolid; j < s->nsolid + s->ngas; ++j)
    if (mpm_region_contains(s->r[j].region, x)) return j;
  return s->nsolid;
}

/* An offender: the two regions (the first a solid) and the point. */
typedef struct offence {
  int first, second;
  double x[3];
} offence;

/* The offender of module m with the smallest id on this rank: its id (INT64_MAX if none). */
static mpm_gidx scan(const scene *s, const mpm_module *m, offence *o) {
  const mpm_particles *p = m->particles;
  const int solid = m->role == MPM_ROLE_SOLID, f_body = solid ? mpm_particles_find(p, "body") : -1;
  const double *body = f_body >= 0 ? mpm_particles_comp(p, f_body, 0) : NULL;
  mpm_gidx best = INT64_MAX;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    if (p->id[i] >= best) continue;
    double x[3] = {0, 0, 0};
    for (int d = 0; d < p->dim; ++d) x[d] = mpm_particles_comp(p, 0, d)[i];
    const int own = body ? (int)body[i] : -1, j = other_body(s, own, x);
    if (j < 0) continue;
    best = p->id[i];
    *o = (offence){own >= 0 ? own : j, own >= 0 ? j : gas_region_of(s, x), {x[0], x[1], x[2]}};
  }
  return best;
}

/* The offender with the smallest id in module m over all ranks: 1 if there is one (then o is
 * the same on every rank), 0 if not. Collective. */
static int find_offence(const scene *s, const mpm_grid *g, const mpm_module *m, offence *o,
                        int *found) {
  const mpm_gidx mine = scan(s, m, o);
  mpm_gidx least;
  MPM_CALL_MPI(MPI_Allreduce(&mine, &least, 1, MPM_MPI_GIDX, MPI_MIN, g->comm));
  *found = least != INT64_MAX;
  if (!*found) return 0;
  int who_mine = mine == least ? g->rank : g->size, who;
  MPM_CALL_MPI(MPI_Allreduce(&who_mine, &who, 1, MPI_INT, MPI_MIN, g->comm));
  int which[2] = {o->first, o->second};
  MPM_CALL_MPI(MPI_Bcast(which, 2, MPI_INT, who, g->comm));
  MPM_CALL_MPI(MPI_Bcast(o->x, 3, MPI_DOUBLE, who, g->comm));
  o->first = which[0], o->second = which[1];
  return 0;
}

static int report(const mpm_config *cfg, const scene *s, const offence *o) {
  const scene_region *a = &s->r[o->first], *b = &s->r[o->second];
  const int gas = o->second >= s->nsolid;
  char at[128];
  if (s->dim == 3)
    snprintf(at, sizeof at, "(%g, %g, %g)", o->x[0], o->x[1], o->x[2]);
  else
    snprintf(at, sizeof at, "(%g, %g)", o->x[0], o->x[1]);
  char todo[512];
  if (gas)
    snprintf(todo, sizeof todo,
             "cut the solid out of the gas: a [geometry.NAME] with type = difference, of = %s %s, "
             "for the gas",
             b->geometry, a->geometry);
  else
    snprintf(todo, sizeof todo, "move or shrink one of the bodies so that they at most touch");
  return mpm_config_fail(cfg, a->key,
                         "[%s] overlaps [%s] (%s) at %s, where the mass of both would add up; %s",
                         a->section, b->section, mpm_config_where(cfg, b->key), at, todo);
}

int mpm_scene_check_overlaps(const mpm_config *cfg, const mpm_grid *grid, mpm_module **mods,
                             int nmod) {
  scene s = {0};
  int rc = scene_read(&s, cfg, grid), found = 0;
  /* a rank that could not read the scene must not leave the others in find_offence's
   * reductions */
  if (MPI_Allreduce(MPI_IN_PLACE, &rc, 1, MPI_INT, MPI_MAX, grid->comm) != MPI_SUCCESS)
    rc = rc ? rc : MPM_ERR_MPI;
  offence o = {0, 0, {0, 0, 0}};
  if (s.nsolid + s.ngas < 2 || s.nsolid == 0) { /* gas regions alone never overlap */
    scene_free(&s);
    return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
  }
  for (int k = 0; !rc && !found && k < nmod; ++k) rc = find_offence(&s, grid, mods[k], &o, &found);
  if (!rc && found) rc = report(cfg, &s, &o);
  scene_free(&s);
  return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
}
