/* Where the particles sit in the refinement hierarchy (mpm_hier.h): each particle's level, for
 * the gas's transfers, stable step and relevel, the output and the diagnostics, and the particle
 * count of every level.
 *
 * Invariants: a particle's level is mpm_hier_level_of at its position (the particle field "x"),
 * the level it deposits on and reads; the counts are those levels tallied, so they sum to p->n.
 * mpm_hier_levels remembers the points it last saw, their levels and the box of each level
 * (h->census; a few sets, each keyed by the address of its positions). The box is that of
 * mpm_hier_level_box: a table span's interior, where every point has the level found, or the
 * point alone where the walk answered. A point inside the box remembered at its index takes the
 * remembered level, which is the one mpm_hier_level_of gives (a pure function of the point and
 * of h, which does not change: a regrid builds a new hierarchy). So the answers are those of
 * mpm_hier_level_of whatever the callers' order; the memory only spares the search where
 * points stayed in their boxes (a point that did not move always does), and elsewhere gives
 * the lookup its first guess. */
#include "mpm_hier_impl.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* One remembered set of points, keyed by the address of its first component array: the gas's
 * positions between steps, an integrator's stage positions, a solid's. */
typedef struct census_set {
  const double *key;                         /* x[0] of the set's last call (NULL: unused) */
  unsigned long used;                        /* the census clock at its last call */
  mpm_lidx cap, n;                           /* points the arrays hold, points remembered */
  uint64_t *x[MPM_MAX_DIM];                  /* the remembered points' bits, component-major */
  double *lo[MPM_MAX_DIM], *hi[MPM_MAX_DIM]; /* the boxes of their levels */
  unsigned char *lev;                        /* their levels */
} census_set;

/* A few sets, so that callers alternating between sets (a gas and a solid counted for the
 * diagnostics, the stages and the step's end) do not make each other look everything up again;
 * the least recently used one makes room for a new set. */
#define CENSUS_SETS 4
/* Points compared at once before one by one (mpm_hier_levels). */
#define CENSUS_BLOCK 64
typedef struct hier_census {
  census_set set[CENSUS_SETS];
  unsigned long clock;
} hier_census;

void mpm_hier_census_free(void *census) {
  hier_census *c = census;
  if (!c) return;
  for (int k = 0; k < CENSUS_SETS; ++k) {
    for (int d = 0; d < MPM_MAX_DIM; ++d)
      free(c->set[k].x[d]), free(c->set[k].lo[d]), free(c->set[k].hi[d]);
    free(c->set[k].lev);
  }
  free(c);
}

/* The set remembered for key (or the least recently used one, emptied), with room for n points
 * (NULL when out of memory: nothing is remembered). */
static census_set *room(mpm_hier *h, const double *key, mpm_lidx n) {
  hier_census *c = h->census;
  if (!c && !(c = h->census = calloc(1, sizeof *c))) return NULL;
  census_set *s = NULL;
  for (int k = 0; k < CENSUS_SETS && !s; ++k)
    if (c->set[k].key == key) s = &c->set[k];
  if (!s) {
    s = &c->set[0];
    for (int k = 1; k < CENSUS_SETS; ++k)
      if (c->set[k].used < s->used) s = &c->set[k];
    s->key = key, s->n = 0;
  }
  s->used = ++c->clock;
  if (n <= s->cap) return s;
  const mpm_lidx cap = n + n / 4 + 16;
  unsigned char *lev = realloc(s->lev, (size_t)cap);
  if (lev) s->lev = lev;
  for (int d = 0; d < h->dim && lev; ++d) {
    uint64_t *x = realloc(s->x[d], sizeof(uint64_t) * (size_t)cap);
    if (x) s->x[d] = x;
    double *lo = x ? realloc(s->lo[d], sizeof(double) * (size_t)cap) : NULL;
    if (lo) s->lo[d] = lo;
    double *hi = lo ? realloc(s->hi[d], sizeof(double) * (size_t)cap) : NULL;
    if (hi) s->hi[d] = hi;
    lev = hi ? lev : NULL;
  }
  if (!lev)
    return s->n = 0, s->cap = 0, s->key = NULL, NULL; /* (the arrays kept are freed with h) */
  s->cap = cap;
  return s;
}

/* Point i of x, new or out of its box: its level (asking level hint first) and its box. */
static void look_up(const mpm_hier *h, census_set *c, const double *const *x, mpm_lidx i,
                    int hint) {
  double xp[MPM_MAX_DIM] = {0, 0, 0}, lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
  for (int d = 0; d < h->dim; ++d) xp[d] = x[d][i];
  c->lev[i] = (unsigned char)mpm_hier_level_box(h, xp, hint, lo, hi);
  for (int d = 0; d < h->dim; ++d) c->lo[d][i] = lo[d], c->hi[d][i] = hi[d];
}

const unsigned char *mpm_hier_levels(mpm_hier *h, const double *const *x, mpm_lidx n) {
  census_set *c = room(h, n > 0 ? x[0] : NULL, n);
  if (!c) return NULL;
  /* Most calls of a step ask again at the points that did not move: one comparison of the
   * whole arrays answers them. */
  int moved = c->n != n;
  for (int d = 0; d < h->dim && !moved; ++d)
    moved = n > 0 && memcmp(c->x[d], x[d], sizeof(uint64_t) * (size_t)n) != 0;
  if (!moved) return c->lev;
  /* Otherwise most points are still in their boxes (a point that did not move always is, a
   * NaN never): four comparisons each in 2-D, after a block of points that did not move at all
   * (an edit's kept particles, a split's parents) is passed over at once. */
  const mpm_lidx kept = n < c->n ? n : c->n;
  for (mpm_lidx i0 = 0; i0 < kept; i0 += CENSUS_BLOCK) {
    const mpm_lidx i1 = kept - i0 < CENSUS_BLOCK ? kept : i0 + CENSUS_BLOCK;
    int same = i1 - i0 == CENSUS_BLOCK;
    for (int d = 0; d < h->dim && same; ++d)
      same = memcmp(c->x[d] + i0, x[d] + i0, sizeof(uint64_t) * CENSUS_BLOCK) == 0;
    if (same) continue;
    unsigned char out[CENSUS_BLOCK] = {0}; /* (a loop per axis without branches) */
    for (int d = 0; d < h->dim; ++d) {
      const double *xd = x[d] + i0, *lo = c->lo[d] + i0, *hi = c->hi[d] + i0;
      for (mpm_lidx i = 0; i < i1 - i0; ++i) out[i] |= !((lo[i] <= xd[i]) & (xd[i] <= hi[i]));
      memcpy(c->x[d] + i0, xd, sizeof(uint64_t) * (size_t)(i1 - i0)); /* (their bits) */
    }
    for (mpm_lidx i = i0; i < i1; ++i)
      if (out[i - i0]) look_up(h, c, x, i, c->lev[i]);
  }
  for (mpm_lidx i = kept; i < n; ++i) {
    for (int d = 0; d < h->dim; ++d) memcpy(&c->x[d][i], &x[d][i], sizeof(double));
    look_up(h, c, x, i, -1);
  }
  c->n = n;
  return c->lev;
}

void mpm_hier_levels_keep(mpm_hier *h, const double *from, const double *to,
                          const unsigned char *keep, mpm_lidx n) {
  hier_census *cs = h ? h->census : NULL;
  if (!cs) return;
  census_set *c = NULL;
  for (int q = 0; q < CENSUS_SETS && !c; ++q)
    if (from && cs->set[q].key == from) c = &cs->set[q];
  if (!c) return;
  if (c->n != n) { /* not the count held: forgotten */
    c->n = 0, c->key = NULL;
    return;
  }
  for (int q = 0; q < CENSUS_SETS; ++q) /* another set remembered at the new address is stale */
    if (&cs->set[q] != c && cs->set[q].key == to) cs->set[q].n = 0, cs->set[q].key = NULL;
  mpm_lidx k = n;
  if (keep) {
    k = 0;
    for (mpm_lidx i = 0; i < n; ++i) {
      if (!keep[i]) continue;
      for (int d = 0; d < h->dim; ++d)
        c->x[d][k] = c->x[d][i], c->lo[d][k] = c->lo[d][i], c->hi[d][k] = c->hi[d][i];
      c->lev[k++] = c->lev[i];
    }
  }
  c->n = k, c->key = to;
}

/* The position components of p (the field "x"). */
static void positions(const mpm_hier *h, const mpm_particles *p, const double **x) {
  const int fx = mpm_particles_find(p, "x");
  for (int d = 0; d < h->dim; ++d) x[d] = mpm_particles_comp(p, fx, d);
}

static int level_at(const mpm_hier *h, const double *const *x, mpm_lidx i) {
  double xp[MPM_MAX_DIM] = {0, 0, 0};
  for (int d = 0; d < h->dim; ++d) xp[d] = x[d][i];
  return mpm_hier_level_of(h, xp);
}

void mpm_hier_particle_levels(const mpm_hier *h, const mpm_particles *p, double *level) {
  const double *x[MPM_MAX_DIM];
  positions(h, p, x);
  for (mpm_lidx i = 0; i < p->n; ++i) level[i] = level_at(h, x, i);
}

void mpm_hier_count_levels(mpm_hier *h, const mpm_particles *p, double *count) {
  const double *x[MPM_MAX_DIM];
  positions(h, p, x);
  const unsigned char *lev = mpm_hier_levels(h, x, p->n);
  int64_t c[MPM_HIER_MAX_LEVELS] = {0}; /* (integers: no chain of dependent additions) */
  for (mpm_lidx i = 0; i < p->n; ++i) c[lev ? lev[i] : level_at(h, x, i)]++;
  for (int l = 0; l < h->nlevels; ++l) count[l] += (double)c[l];
}
