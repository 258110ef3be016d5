/* Where the particles sit in the refinement hierarchy (mpm_hier.h): each particle's level, for
 * the gas's transfers, stable step and relevel, the output and the diagnostics, and the particle
 * count of every level.
 *
 * Invariants: a particle's level is mpm_hier_level_of at its position (the particle field "x"),
 * the level it deposits on and reads; the counts are those levels tallied, so they sum to p->n.
 * mpm_hier_levels remembers the points it last saw and their levels (h->census): a point equal
 * bit for bit to the one remembered at its index takes the remembered level, which is the one
 * mpm_hier_level_of gives (a pure function of the point and of h, which does not change: a
 * regrid builds a new hierarchy). So the answers are those of mpm_hier_level_of whatever the
 * callers' order; the memory only spares the search where positions did not move, and where
 * they moved it gives the lookup its first guess (mpm_hier_level_from). */
#include "mpm_hier_impl.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct hier_census {
  mpm_lidx cap, n;          /* points the arrays hold, points remembered */
  uint64_t *x[MPM_MAX_DIM]; /* the remembered points' bits, component-major */
  unsigned char *lev;       /* their levels */
} hier_census;

void mpm_hier_census_free(void *census) {
  hier_census *c = census;
  if (!c) return;
  for (int d = 0; d < MPM_MAX_DIM; ++d) free(c->x[d]);
  free(c->lev), free(c);
}

/* The memory, with room for n points (NULL when out of memory: nothing is remembered). */
static hier_census *room(mpm_hier *h, mpm_lidx n) {
  hier_census *c = h->census;
  if (!c && !(c = h->census = calloc(1, sizeof *c))) return NULL;
  if (n <= c->cap) return c;
  const mpm_lidx cap = n + n / 4 + 16;
  unsigned char *lev = realloc(c->lev, (size_t)cap);
  if (lev) c->lev = lev;
  for (int d = 0; d < h->dim && lev; ++d) {
    uint64_t *x = realloc(c->x[d], sizeof(uint64_t) * (size_t)cap);
    if (x) c->x[d] = x;
    lev = x ? lev : NULL;
  }
  if (!lev) return c->n = 0, c->cap = 0, NULL; /* (the arrays kept are freed with h) */
  c->cap = cap;
  return c;
}

const unsigned char *mpm_hier_levels(mpm_hier *h, const double *const *x, mpm_lidx n) {
  hier_census *c = room(h, n);
  if (!c) return NULL;
  /* Most calls of a step ask again at the points that did not move: one comparison of the
   * whole arrays answers them. */
  int moved = c->n != n;
  for (int d = 0; d < h->dim && !moved; ++d)
    moved = n > 0 && memcmp(c->x[d], x[d], sizeof(uint64_t) * (size_t)n) != 0;
  if (!moved) return c->lev;
  for (mpm_lidx i = 0; i < n; ++i) {
    uint64_t b[MPM_MAX_DIM] = {0, 0, 0};
    int same = i < c->n;
    for (int d = 0; d < h->dim; ++d) {
      memcpy(&b[d], &x[d][i], sizeof b[d]);
      same &= b[d] == c->x[d][i];
    }
    if (same) continue;
    double xp[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < h->dim; ++d) xp[d] = x[d][i], c->x[d][i] = b[d];
    c->lev[i] = (unsigned char)mpm_hier_level_from(h, xp, i < c->n ? c->lev[i] : -1);
  }
  c->n = n;
  return c->lev;
}

void mpm_hier_levels_keep(mpm_hier *h, const unsigned char *keep, mpm_lidx n) {
  hier_census *c = h ? h->census : NULL;
  if (!c) return;
  if (c->n != n) {
    c->n = 0;
    return;
  }
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    for (int d = 0; d < h->dim; ++d) c->x[d][k] = c->x[d][i];
    c->lev[k++] = c->lev[i];
  }
  c->n = k;
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
  for (mpm_lidx i = 0; i < p->n; ++i) count[lev ? lev[i] : level_at(h, x, i)] += 1.0;
}
