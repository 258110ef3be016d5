/* Composite P2G and G2P over the hierarchy (mpm_hier.h): particles are sorted by the level of
 * their position, and each level's particles run through the unchanged kernel
 * (mpm_kernels_get) on that level's grid, a chunk at a time: their fields are gathered into
 * contiguous scratch columns, and G2P's outputs scattered back.
 *
 * Invariants: the scratch (h->scratch) grows and never shrinks, so a steady run allocates
 * nothing per step; a chunk holds at most CHUNK particles, so the gathered columns stay in
 * cache and their memory is bounded whatever the particle count; when every particle lies on
 * level 0 the kernel runs on the caller's arrays directly (the plain kernel call); levels a
 * caller vouches for (mpm_hier_levels_known) are taken as given for its positions alone, and
 * their grouping by level is made once for all the transfers of those positions. On a level
 * that stores a whole period along an axis (mpm_hier.h) the gathered positions are wrapped
 * into the domain along it, so every stencil lies in the level's box. */
#include "mpm_hier_impl.h"

#include "mpm_error.h"

#include <stdlib.h>

enum {
  CHUNK = 4096,
  /* Most columns a chunk needs: G2P's x, F, v, a, L, C, LF, div and scalars in 3-D. */
  MAX_COLS = 3 + 9 + 3 + 3 + 9 + 9 + 9 + 1 + MPM_KERNELS_MAX_SCALARS
};

typedef struct hier_scratch {
  mpm_lidx cap_n;        /* particles lev and order hold */
  unsigned char *lev;    /* level of each particle */
  mpm_lidx *order;       /* particle indices, level 0's first, then level 1's, ... */
  size_t cap_buf;        /* doubles in buf */
  double *buf;           /* gathered columns of one chunk */
  const double *known_x; /* mpm_hier_levels_known: positions, count and their levels */
  mpm_lidx known_n;
  const unsigned char *known;
  int sorted; /* lev, order and first hold the known levels' grouping (classify) */
  mpm_lidx first[MPM_HIER_MAX_LEVELS + 1];
} hier_scratch;

void mpm_hier_scratch_free(void *scratch) {
  hier_scratch *s = scratch;
  if (!s) return;
  free(s->lev), free(s->order), free(s->buf), free(s);
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

/* Room for n particles (and a chunk of columns for them). */
static int reserve(mpm_hier *h, mpm_lidx n) {
  hier_scratch *s = NULL;
  MPM_CALL(scratch_of(h, &s));
  if (n > s->cap_n) {
    free(s->lev), free(s->order);
    s->lev = NULL, s->order = NULL, s->cap_n = 0;
    MPM_ALLOC(s->lev, n);
    MPM_ALLOC(s->order, n);
    s->cap_n = n;
  }
  const size_t need = (size_t)MAX_COLS * (size_t)MPM_MIN(n, CHUNK);
  if (need > s->cap_buf) {
    free(s->buf);
    s->buf = NULL, s->cap_buf = 0;
    MPM_ALLOC(s->buf, need);
    s->cap_buf = need;
  }
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
  for (mpm_lidx p = 0; p < n; ++p) {
    double xp[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < h->dim && !known; ++d) xp[d] = x[d][p];
    s->lev[p] = known ? s->known[p] : (unsigned char)mpm_hier_level_of(h, xp);
    count[s->lev[p] + 1]++;
  }
  first[0] = 0;
  for (int l = 0; l < h->nlevels; ++l) first[l + 1] = first[l] + count[l + 1];
  for (int l = 0; known && l <= h->nlevels; ++l) s->first[l] = first[l];
  if (first[1] == n) return 1;
  mpm_lidx next[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < h->nlevels; ++l) next[l] = first[l];
  for (mpm_lidx p = 0; p < n; ++p) s->order[next[s->lev[p]]++] = p;
  return 0;
}

/* A chunk's columns: nc particles order[0 .. nc) of arrays with n entries per component. */
typedef struct chunk {
  const mpm_lidx *order;
  mpm_lidx nc, n;
  double *next; /* the next free column of the scratch */
} chunk;

/* Gather ncomp components (stride n in src) into fresh columns (stride nc); NULL stays NULL. */
static const double *gather(chunk *c, const double *src, int ncomp) {
  if (!src) return NULL;
  double *dst = c->next;
  for (int k = 0; k < ncomp; ++k) {
    const double *s = src + (size_t)k * c->n;
    double *o = dst + (size_t)k * c->nc;
    for (mpm_lidx i = 0; i < c->nc; ++i) o[i] = s[c->order[i]];
  }
  c->next += (size_t)ncomp * c->nc;
  return dst;
}

/* Gather the positions of a chunk on level l, wrapped into the domain along every axis where
 * the level (>= 1) stores a whole period. */
static void gather_x(const mpm_hier *h, int l, chunk *c, const double *const *x,
                     const double **out) {
  const mpm_grid *g0 = h->level[0].grid;
  for (int d = 0; d < h->dim; ++d) {
    double *o = c->next;
    out[d] = gather(c, x[d], 1);
    if (l > 0 && h->level[l].period[d]) /* level 0's halo takes its images */
      for (mpm_lidx i = 0; i < c->nc; ++i) o[i] = hier_wrap_coord(o[i], g0->lo[d], g0->hi[d]);
  }
}

/* Fresh output columns for ncomp components. */
static double *column(chunk *c, int ncomp) {
  double *dst = c->next;
  c->next += (size_t)ncomp * c->nc;
  return dst;
}

/* Scatter ncomp components of src (stride nc) back into dst (stride n), unless dst is NULL. */
static void scatter(const chunk *c, const double *src, double *dst, int ncomp) {
  if (!dst) return;
  for (int k = 0; k < ncomp; ++k) {
    const double *s = src + (size_t)k * c->nc;
    double *o = dst + (size_t)k * c->n;
    for (mpm_lidx i = 0; i < c->nc; ++i) o[c->order[i]] = s[i];
  }
}

/* ---- P2G -------------------------------------------------------------------------------- */

static void p2g_chunk(mpm_hier *h, int l, int phase, const mpm_p2g_args *a, chunk *c) {
  const int D = h->dim;
  mpm_p2g_args b = *a;
  b.n = c->nc;
  gather_x(h, l, c, a->x, b.x);
  for (int d = 0; d < D; ++d) b.v[d] = gather(c, a->v[d], 1);
  b.m = gather(c, a->m, 1);
  b.vsig = gather(c, a->vsig, D * D);
  b.viso = gather(c, a->viso, 1);
  b.s = gather(c, a->s, 1);
  b.C = gather(c, a->C, D * D);
  for (int d = 0; d < D && a->fext[0]; ++d) b.fext[d] = gather(c, a->fext[d], 1);
  mpm_kernels_get(D)->p2g(h->level[l].grid, phase, &b);
}

int mpm_hier_p2g(mpm_hier *h, int phase, const mpm_p2g_args *a) {
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
  for (int l = 0; l < h->nlevels; ++l)
    for (mpm_lidx i = first[l]; i < first[l + 1]; i += CHUNK) {
      chunk c = {s->order + i, MPM_MIN(CHUNK, first[l + 1] - i), a->n, s->buf};
      p2g_chunk(h, l, phase, a, &c);
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

static void g2p_chunk(mpm_hier *h, int l, const mpm_g2p_args *lv, const mpm_g2p_args *a, chunk *c) {
  const int D = h->dim, DD = D * D;
  mpm_g2p_args b = *lv;
  b.n = c->nc;
  gather_x(h, l, c, a->x, b.x);
  for (int d = 0; d < D && a->v_out[0]; ++d) b.v_out[d] = column(c, 1), b.a_out[d] = column(c, 1);
  b.div_out = a->div_out ? column(c, 1) : NULL;
  b.F = a->LF_out ? gather(c, a->F, DD) : NULL;
  b.L_out = a->L_out ? column(c, DD) : NULL;
  b.C_out = a->C_out ? column(c, DD) : NULL;
  b.LF_out = a->LF_out ? column(c, DD) : NULL;
  for (int j = 0; j < a->nscalar; ++j) b.s_out[j] = column(c, 1);
  mpm_kernels_get(D)->g2p(h->level[l].grid, &b);
  for (int d = 0; d < D; ++d) {
    scatter(c, b.v_out[d], a->v_out[d], 1);
    scatter(c, b.a_out[d], a->a_out[d], 1);
  }
  if (a->L_out) scatter(c, b.L_out, a->L_out, DD);
  if (a->C_out) scatter(c, b.C_out, a->C_out, DD);
  if (a->LF_out) scatter(c, b.LF_out, a->LF_out, DD);
  if (a->div_out) scatter(c, b.div_out, a->div_out, 1);
  for (int j = 0; j < a->nscalar; ++j) scatter(c, b.s_out[j], a->s_out[j], 1);
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
    const mpm_g2p_args lv = level_args(h, l, phase, a, v, s);
    for (mpm_lidx i = first[l]; i < first[l + 1]; i += CHUNK) {
      chunk c = {sc->order + i, MPM_MIN(CHUNK, first[l + 1] - i), a->n, sc->buf};
      g2p_chunk(h, l, &lv, a, &c);
    }
  }
  return 0;
}
