/* Composite P2G and G2P over the hierarchy (mpm_hier.h): particles are grouped by the level of
 * their position, and each level's particles run through the unchanged kernel
 * (mpm_kernels_get) on that level's grid, visited through the kernels' index list (the group's
 * indices, ascending): the kernels read the caller's arrays and write G2P's outputs in place,
 * so nothing is gathered or scattered.
 *
 * Invariants: the scratch (h->scratch) grows and never shrinks, so a steady run allocates
 * nothing per step; when every particle lies on level 0 the kernel runs on the caller's arrays
 * without a list (the plain kernel call); levels a caller vouches for (mpm_hier_levels_known)
 * are taken as given for its positions alone, and their grouping by level is made once for all
 * the transfers of those positions. On a level that stores a whole period along an axis
 * (mpm_hier.h) the kernels wrap its particles' positions into the domain along it
 * (mpm_kernels.h), so every stencil lies in the level's box. Each particle's operations are
 * those of a kernel call over its level's particles alone, in the same order, so the sums do
 * not depend on how the levels are visited. */
#include "mpm_hier_impl.h"

#include "mpm_error.h"

#include <assert.h>
#include <stdlib.h>

typedef struct hier_scratch {
  mpm_lidx cap_n;        /* particles lev and order hold */
  unsigned char *lev;    /* level of each particle */
  mpm_lidx *order;       /* particle indices, level 0's first, then level 1's, ... */
  const double *known_x; /* mpm_hier_levels_known: positions, count and their levels */
  mpm_lidx known_n;
  const unsigned char *known;
  int sorted; /* lev, order and first hold the known levels' grouping (classify) */
  mpm_lidx first[MPM_HIER_MAX_LEVELS + 1];
} hier_scratch;

void mpm_hier_scratch_free(void *scratch) {
  hier_scratch *s = scratch;
  if (!s) return;
  free(s->lev), free(s->order), free(s);
}

/* The scratch, made on first use. */
static int scratch_of(mpm_hier *h, hier_scratch **s) {
  if (!h->scratch) {
    hier_scratch *fresh;
    MPM_ALLOC(fresh, 1);
    h->scratch = fresh;
  }
  *s = h->scratch;
  return 0;
}

void mpm_hier_levels_known(mpm_hier *h, const double *x0, mpm_lidx n, const unsigned char *level) {
  hier_scratch *s = NULL;
  if (scratch_of(h, &s)) return; /* (out of memory: the transfers find the levels) */
  s->known_x = x0, s->known_n = x0 ? n : 0, s->known = x0 ? level : NULL;
  s->sorted = 0;
}

void mpm_hier_levels_vouched(const mpm_hier *h, const double **x0, mpm_lidx *n,
                             const unsigned char **level) {
  const hier_scratch *s = h->scratch;
  *x0 = s ? s->known_x : NULL, *n = s ? s->known_n : 0, *level = s ? s->known : NULL;
}

/* Room for n particles. */
static int reserve(mpm_hier *h, mpm_lidx n) {
  hier_scratch *s = NULL;
  MPM_CALL(scratch_of(h, &s));
  if (n <= s->cap_n) return 0;
  free(s->lev), free(s->order);
  s->lev = NULL, s->order = NULL, s->cap_n = 0;
  MPM_ALLOC(s->lev, n);
  MPM_ALLOC(s->order, n);
  s->cap_n = n;
  return 0;
}

/* Level of every particle and the particles grouped by level: level l's are
 * order[first[l] .. first[l + 1]). Returns 1 when all lie on level 0. The grouping of known
 * levels is kept for the next transfer of the same positions (a transfer of other positions
 * overwrites lev and order, so it drops it, as a new mpm_hier_levels_known does). */
static int classify(mpm_hier *h, mpm_lidx n, const double *const *x, mpm_lidx *first) {
  hier_scratch *s = h->scratch;
  mpm_lidx count[MPM_HIER_MAX_LEVELS + 1] = {0};
  const int known = s->known && s->known_x == x[0] && s->known_n == n;
  if (known && s->sorted) {
    for (int l = 0; l <= h->nlevels; ++l) first[l] = s->first[l];
    return first[1] == n;
  }
  s->sorted = known;
  const unsigned char *lev = known ? s->known : s->lev;
  for (mpm_lidx p = 0; !known && p < n; ++p) {
    double xp[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < h->dim; ++d) xp[d] = x[d][p];
    s->lev[p] = (unsigned char)mpm_hier_level_of(h, xp);
  }
  for (mpm_lidx p = 0; p < n; ++p) count[lev[p] + 1]++;
  first[0] = 0;
  for (int l = 0; l < h->nlevels; ++l) first[l + 1] = first[l] + count[l + 1];
  for (int l = 0; known && l <= h->nlevels; ++l) s->first[l] = first[l];
  if (first[1] == n) return 1;
  mpm_lidx next[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < h->nlevels; ++l) next[l] = first[l];
  mpm_lidx *order = s->order;
  for (mpm_lidx p = 0; p < n; ++p) order[next[lev[p]]++] = p;
  return 0;
}

/* Level l's wrap (mpm_kernels.h): along every axis where the level (>= 1) stores a whole
 * period, the domain's period (level 0's halo takes its images). */
static void level_wrap(const mpm_hier *h, int l, double *lo, double *hi) {
  const mpm_grid *g0 = h->level[0].grid;
  for (int d = 0; d < h->dim; ++d) {
    const int wraps = l > 0 && h->level[l].period[d];
    lo[d] = wraps ? g0->lo[d] : 0.0, hi[d] = wraps ? g0->hi[d] : 0.0;
  }
}

/* ---- P2G -------------------------------------------------------------------------------- */

int mpm_hier_p2g(mpm_hier *h, int phase, const mpm_p2g_args *a) {
  assert(!a->idx); /* (mpm_hier.h) */
  const int normals = h->level[0].grid->phase[phase].normals;
  for (int l = 1; l < h->nlevels; ++l) h->level[l].grid->phase[phase].normals = normals;
  if (h->nlevels > 1) mpm_hier_own_share(h, phase);
  mpm_lidx first[MPM_HIER_MAX_LEVELS + 1];
  if (h->nlevels > 1) MPM_CALL(reserve(h, a->n));
  if (h->nlevels == 1 || classify(h, a->n, a->x, first)) {
    mpm_kernels_get(h->dim)->p2g(h->level[0].grid, phase, a);
    return 0;
  }
  const hier_scratch *s = h->scratch;
  for (int l = 0; l < h->nlevels; ++l) {
    if (first[l + 1] == first[l]) continue;
    mpm_p2g_args b = *a;
    b.idx = s->order + first[l], b.nidx = first[l + 1] - first[l];
    level_wrap(h, l, b.wrap_lo, b.wrap_hi);
    mpm_kernels_get(h->dim)->p2g(h->level[l].grid, phase, &b);
  }
  return 0;
}

/* ---- G2P -------------------------------------------------------------------------------- */

/* The G2P arguments of level l: its own nodal fields, and the caller's outputs (a level-0 run
 * on the caller's arrays). */
static mpm_g2p_args level_args(const mpm_hier *h, int l, int phase, const mpm_g2p_args *a,
                               const mpm_hier_nodal *v, const mpm_hier_scalars *s) {
  const mpm_grid_phase *ph = &h->level[l].grid->phase[phase];
  mpm_g2p_args b = *a;
  for (int d = 0; d < h->dim; ++d) {
    b.v_i[d] = v ? v->v_i[l][d] : l == 0 && a->v_i[d] ? a->v_i[d] : ph->v_i[d];
    b.a_i[d] = l == 0 && a->a_i[d] ? a->a_i[d] : ph->a_i[d];
  }
  for (int j = 0; j < a->nscalar && l > 0; ++j) b.s_i[j] = s->s_i[l][j];
  return b;
}

/* Every finer level's scalars are given when the caller interpolates scalars. */
static int check_scalars(const mpm_hier *h, const mpm_g2p_args *a, const mpm_hier_scalars *s) {
  for (int l = 1; l < h->nlevels; ++l)
    for (int j = 0; j < a->nscalar; ++j)
      if (!s || !s->s_i[l][j])
        MPM_FAIL(MPM_ERR_INTERNAL, "hierarchy G2P: scalar %d of level %d is not given", j, l);
  return 0;
}

int mpm_hier_g2p(mpm_hier *h, int phase, const mpm_g2p_args *a, const mpm_hier_scalars *s) {
  return mpm_hier_g2p_from(h, phase, a, NULL, s);
}

int mpm_hier_g2p_from(mpm_hier *h, int phase, const mpm_g2p_args *a, const mpm_hier_nodal *v,
                      const mpm_hier_scalars *s) {
  assert(!a->idx); /* (mpm_hier.h) */
  MPM_CALL(check_scalars(h, a, s));
  mpm_lidx first[MPM_HIER_MAX_LEVELS + 1];
  if (h->nlevels > 1) MPM_CALL(reserve(h, a->n));
  if (h->nlevels == 1 || classify(h, a->n, a->x, first)) {
    const mpm_g2p_args b = level_args(h, 0, phase, a, v, s);
    mpm_kernels_get(h->dim)->g2p(h->level[0].grid, &b);
    return 0;
  }
  const hier_scratch *sc = h->scratch;
  for (int l = 0; l < h->nlevels; ++l) {
    if (first[l + 1] == first[l]) continue;
    mpm_g2p_args b = level_args(h, l, phase, a, v, s);
    b.idx = sc->order + first[l], b.nidx = first[l + 1] - first[l];
    level_wrap(h, l, b.wrap_lo, b.wrap_hi);
    mpm_kernels_get(h->dim)->g2p(h->level[l].grid, &b);
  }
  return 0;
}
