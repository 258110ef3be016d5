/* The composite basis of the hierarchy (mpm_hier.h): the two-scale relation between levels,
 * restriction (fine inactive nodes onto their parents) and its transpose, prolongation, and
 * the composite weights of one point.
 *
 * Invariants: restriction and prolongation visit every inactive node of a level box near its
 * region (mpm_hier_level.near: every node a deposit on the level reaches), ghost layer
 * included, and read or write only its 2^dim parents, which lie in the coarser box (see
 * mpm_hier.c); restriction leaves every inactive node at exactly zero (the others, which no
 * deposit reaches, are zero already, and the prolongation leaves them so). mpm_hier_eval pushes
 * weights down exactly as P2G followed by restriction does, so the two agree to roundoff.
 * On a level that stores a whole period (mpm_hier.h, periodic axes) the restriction first
 * folds every image into its node and the prolongation ends by copying every node into its
 * images; both skip the images otherwise (their parents may lie outside the coarser box), and
 * mpm_hier_eval moves every node onto its image before it looks it up.
 * On more than one rank (mpm_hier.h, ranks) level 1's parents are read and written through the
 * parents box, and a restriction first sums the finer level over the ranks.
 * Every call of the per-level restriction and prolongation is timed (MPM_T_RESTRICT and
 * MPM_T_PROLONG, mpm_timer.h), whoever calls it. */
#include "mpm_hier_impl.h"
#include "mpm_timer.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

int mpm_hier_parents(const mpm_grid *c, const int *gi, mpm_lidx *idx, double *w) {
  int p[MPM_MAX_DIM][2] = {{0, 0}, {0, 0}, {0, 0}}, q[MPM_MAX_DIM] = {0, 0, 0};
  for (int d = 0; d < c->dim; ++d) hier_parents_1d(gi[d], p[d]);
  const int np = 1 << c->dim;
  for (int k = 0; k < np; ++k) {
    w[k] = hier_parent_k(c->dim, (const int(*)[2])p, k, q);
    idx[k] = mpm_grid_local_index(c, q);
  }
  return np;
}

/* Add every image of level lv into its node and zero it, for nf arrays. */
static void fold_images(const mpm_hier_level *lv, double *const *a, int nf) {
  for (int k = 0; k < nf; ++k)
    for (mpm_lidx q = 0; q < lv->nimage; ++q) {
      a[k][lv->canon[q]] += a[k][lv->image[q]];
      a[k][lv->image[q]] = 0.0;
    }
}

/* Copy every node of level lv into its images, for nf arrays. */
static void copy_images(const mpm_hier_level *lv, double *const *a, int nf) {
  for (int k = 0; k < nf; ++k)
    for (mpm_lidx q = 0; q < lv->nimage; ++q) a[k][lv->image[q]] = a[k][lv->canon[q]];
}

/* Sum nf arrays of level l >= 1 over the ranks (mpm_hier.h, ranks): one MPI_Allreduce of them
 * packed together (per array when the room cannot be had). MPI's errors abort (the default
 * handler). */
static void sum_ranks(mpm_hier *h, int l, double *const *a, int nf) {
  const size_t nn = (size_t)h->level[l].grid->nnodes, need = nn * (size_t)nf;
  const MPI_Comm comm = h->level[0].grid->comm;
  if (need > h->sum_cap) {
    free(h->sum_buf);
    h->sum_buf = malloc(sizeof(double) * need);
    h->sum_cap = h->sum_buf ? need : 0;
  }
  if (!h->sum_buf || need > (size_t)INT_MAX) {
    for (int k = 0; k < nf; ++k)
      MPI_Allreduce(MPI_IN_PLACE, a[k], (int)nn, MPI_DOUBLE, MPI_SUM, comm);
    return;
  }
  for (int k = 0; k < nf; ++k) memcpy(h->sum_buf + (size_t)k * nn, a[k], sizeof(double) * nn);
  MPI_Allreduce(MPI_IN_PLACE, h->sum_buf, (int)need, MPI_DOUBLE, MPI_SUM, comm);
  for (int k = 0; k < nf; ++k) memcpy(a[k], h->sum_buf + (size_t)k * nn, sizeof(double) * nn);
}

/* Restrict the inactive nodes of level l (fine, nf arrays) onto their parents in the arrays
 * `to` over the lattice the level's parents index (level l - 1, or the parents box), zeroing
 * them; add 0: only zero them (a rank other than 0 whose sum rank 0 adds). Only the nodes near
 * the region (mpm_hier_level.near) can hold a value; a node holding zeros adds nothing. */
static void restrict_into(const mpm_hier *h, int l, double *const *fine, double *const *to, int nf,
                          int add) {
  const mpm_hier_level *lv = &h->level[l];
  const int np = 1 << h->dim;
  for (mpm_lidx k = 0; k < lv->nnear; ++k) {
    const mpm_lidx n = lv->near[k];
    const mpm_lidx *idx = lv->near_idx + (size_t)k * np;
    const double *w = lv->near_w + (size_t)k * np;
    for (int f = 0; f < nf; ++f) {
      const double v = fine[f][n];
      if (v == 0.0) continue;
      fine[f][n] = 0.0;
      for (int q = 0; add && q < np; ++q) to[f][idx[q]] += w[q] * v;
    }
  }
}

/* Level 1 onto level 0 on more than one rank: onto the parents box (the same on every rank),
 * then each of its nodes into the level-0 node this rank owns there, so that every
 * contribution lands once over the ranks (level 0's ghosts get none). */
static void restrict_ranks(mpm_hier *h, double *const *fine, double *const *coarse, int nf) {
  const mpm_hier_parents_box *pb = &h->pbox;
  const mpm_lidx nn = pb->grid->nnodes;
  double *to[1 + 3 * MPM_MAX_DIM] = {NULL};
  for (int k = 0; k < nf; ++k) to[k] = pb->buf + (size_t)k * nn;
  memset(pb->buf, 0, sizeof(double) * (size_t)nf * (size_t)nn);
  restrict_into(h, 1, fine, to, nf, 1);
  for (int k = 0; k < nf; ++k)
    for (mpm_lidx q = 0; q < nn; ++q)
      if (pb->owned[q] >= 0) coarse[k][pb->owned[q]] += to[k][q];
}

/* The restriction of level l; sum: the fine arrays hold each rank's share, summed here first
 * (more than one rank; then only rank 0 adds the sum onto a finer level l - 1 >= 1, whose own
 * restriction sums it in turn). */
static void restrict_level(mpm_hier *h, int l, double *const *fine, double *const *coarse, int nf,
                           int sum) {
  const mpm_hier_level *lv = &h->level[l];
  mpm_timer_start(MPM_T_RESTRICT);
  if (sum) sum_ranks(h, l, fine, nf);
  fold_images(lv, fine, nf);
  if (h->nranks > 1 && l == 1)
    restrict_ranks(h, fine, coarse, nf);
  else
    restrict_into(h, l, fine, coarse, nf, !sum || h->rank == 0);
  mpm_timer_stop(MPM_T_RESTRICT);
}

void mpm_hier_restrict_level(mpm_hier *h, int l, double *const *fine, double *const *coarse,
                             int nf) {
  restrict_level(h, l, fine, coarse, nf, h->nranks > 1);
}

/* Level 0's values of nf arrays on the parents box, from the rank owning each node (the same
 * on every rank), into the box's buffer; returns the arrays there. */
static void parents_ranks(mpm_hier *h, const double *const *coarse, const double **out, int nf) {
  const mpm_hier_parents_box *pb = &h->pbox;
  const mpm_lidx nn = pb->grid->nnodes;
  for (int k = 0; k < nf; ++k) {
    double *b = pb->buf + (size_t)k * nn;
    for (mpm_lidx q = 0; q < nn; ++q) b[q] = pb->owned[q] >= 0 ? coarse[k][pb->owned[q]] : 0.0;
    out[k] = b;
  }
  MPI_Allreduce(MPI_IN_PLACE, pb->buf, (int)((size_t)nf * (size_t)nn), MPI_DOUBLE, MPI_SUM,
                h->level[0].grid->comm);
}

void mpm_hier_prolong_level(mpm_hier *h, int l, const double *const *coarse, double *const *fine,
                            int nf) {
  const mpm_hier_level *lv = &h->level[l];
  const int np = 1 << h->dim;
  const double *from[1 + 3 * MPM_MAX_DIM];
  mpm_timer_start(MPM_T_PROLONG);
  if (h->nranks > 1 && l == 1) {
    parents_ranks(h, coarse, from, nf);
    coarse = from;
  }
  for (mpm_lidx k = 0; k < lv->nnear; ++k) {
    const mpm_lidx n = lv->near[k];
    const mpm_lidx *idx = lv->near_idx + (size_t)k * np;
    const double *w = lv->near_w + (size_t)k * np;
    for (int f = 0; f < nf; ++f) {
      double v = 0.0;
      for (int q = 0; q < np; ++q) v += w[q] * coarse[f][idx[q]];
      fine[f][n] = v;
    }
  }
  copy_images(lv, fine, nf);
  mpm_timer_stop(MPM_T_PROLONG);
}

/* The deposit fields of a phase on one level: m, m v, f and, when deposited, the mass
 * gradient; returns their number. */
static int deposit_fields(mpm_grid *g, int phase, int normals, double **out) {
  mpm_grid_phase *ph = &g->phase[phase];
  int n = 0;
  out[n++] = ph->m_i;
  for (int d = 0; d < g->dim; ++d) out[n++] = ph->mv_i[d], out[n++] = ph->f_i[d];
  for (int d = 0; normals && d < g->dim; ++d) out[n++] = ph->normal_i[d];
  return n;
}

void mpm_hier_restrict(mpm_hier *h, int phase) {
  const int normals = h->level[0].grid->phase[phase].normals;
  double *fine[1 + 3 * MPM_MAX_DIM], *coarse[1 + 3 * MPM_MAX_DIM];
  const int sum = h->nranks > 1 && h->pending[phase];
  for (int l = h->nlevels - 1; l >= 1; --l) {
    const int nf = deposit_fields(h->level[l].grid, phase, normals, fine);
    deposit_fields(h->level[l - 1].grid, phase, normals, coarse);
    restrict_level(h, l, fine, coarse, nf, sum);
  }
  if (sum) h->pending[phase] = 0, h->summed[phase] = 1;
}

void mpm_hier_own_share(mpm_hier *h, int phase) {
  if (h->nranks == 1) return;
  if (h->summed[phase] && h->rank != 0) {
    const int normals = h->level[0].grid->phase[phase].normals;
    double *a[1 + 3 * MPM_MAX_DIM];
    for (int l = 1; l < h->nlevels; ++l) {
      const mpm_grid *g = h->level[l].grid;
      const int nf = deposit_fields(h->level[l].grid, phase, normals, a);
      for (int k = 0; k < nf; ++k) memset(a[k], 0, sizeof(double) * (size_t)g->nnodes);
    }
  }
  h->summed[phase] = 0, h->pending[phase] = 1;
}

void mpm_hier_prolong(mpm_hier *h, int phase) {
  const double *coarse[2 * MPM_MAX_DIM];
  double *fine[2 * MPM_MAX_DIM];
  for (int l = 1; l < h->nlevels; ++l) {
    const mpm_grid_phase *pc = &h->level[l - 1].grid->phase[phase];
    mpm_grid_phase *pf = &h->level[l].grid->phase[phase];
    for (int d = 0; d < h->dim; ++d) {
      coarse[d] = pc->v_i[d], coarse[h->dim + d] = pc->a_i[d];
      fine[d] = pf->v_i[d], fine[h->dim + d] = pf->a_i[d];
    }
    mpm_hier_prolong_level(h, l, coarse, fine, 2 * h->dim);
  }
}

/* ---- composite weights of one point ----------------------------------------------------- */

/* One weight on the way down: node gi of the level being processed. */
typedef struct entry {
  int gi[MPM_MAX_DIM];
  double w, dw[MPM_MAX_DIM];
} entry;

enum { MAX_ENTRIES = 27 }; /* 3 nodes per axis per level: see the merge in push_down */

/* The quadratic stencil of x on lattice g: 3^dim entries (weights, gradients in 1/length). */
static int stencil(const mpm_grid *g, const double *x, entry *e) {
  double w[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT], dw[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT];
  int base[MPM_MAX_DIM];
  for (int d = 0; d < g->dim; ++d) {
    base[d] = mpm_shape_1d(MPM_SHAPE_QUADRATIC, hier_xi(g, d, x[d]), 0.0, w[d], dw[d]);
    for (int k = 0; k < 3; ++k) dw[d][k] *= 1.0 / g->dx;
  }
  const int n = g->dim == 2 ? 9 : 27;
  for (int q = 0; q < n; ++q) {
    int o[MPM_MAX_DIM] = {0, 0, 0};
    e[q].gi[2] = 0;
    for (int d = 0, r = q; d < g->dim; ++d, r /= 3) o[d] = r % 3, e[q].gi[d] = base[d] + o[d];
    e[q].w = 1.0;
    for (int d = 0; d < g->dim; ++d) e[q].w *= w[d][o[d]], e[q].dw[d] = dw[d][o[d]];
    for (int d = 0; d < g->dim; ++d)
      for (int b = 0; b < g->dim; ++b)
        if (b != d) e[q].dw[d] *= w[b][o[b]];
  }
  return n;
}

/* Add s times entry e at node gi to the list (merging with an entry of the same node). */
static int merge(entry *list, int n, int dim, const int *gi, double s, const entry *e) {
  int k = 0;
  while (k < n && memcmp(list[k].gi, gi, sizeof list[k].gi) != 0) ++k;
  if (k == n) {
    if (n == MAX_ENTRIES) return -1;
    memset(&list[k], 0, sizeof list[k]);
    memcpy(list[k].gi, gi, sizeof list[k].gi), ++n;
  }
  list[k].w += s * e->w;
  for (int d = 0; d < dim; ++d) list[k].dw[d] += s * e->dw[d];
  return n;
}

/* The node of gi on level lv as the hierarchy looks it up: its image in the period where
 * the hierarchy wraps, gi itself otherwise. */
static void lookup_node(const mpm_hier *h, const mpm_hier_level *lv, int *gi) {
  if (h->wraps) hier_canon(lv, h->dim, gi);
}

/* Move entry e of a fine node onto its 2^dim parents (on coarse level cv) in next; returns
 * the new count. */
static int push_down(const mpm_hier *h, const mpm_hier_level *cv, entry *next, int n,
                     const entry *e) {
  const int dim = h->dim;
  int p[MPM_MAX_DIM][2] = {{0, 0}, {0, 0}, {0, 0}};
  for (int d = 0; d < dim; ++d) hier_parents_1d(e->gi[d], p[d]);
  for (int k = 0; k < (1 << dim) && n >= 0; ++k) {
    int q[MPM_MAX_DIM] = {0, 0, 0};
    const double s = hier_parent_k(dim, (const int(*)[2])p, k, q);
    lookup_node(h, cv, q);
    n = merge(next, n, dim, q, s, e);
  }
  return n;
}

/* Does entry e carry anything (a weight or a gradient)? */
static int nonzero(const entry *e, int dim) {
  int any = e->w != 0.0;
  for (int d = 0; d < dim; ++d) any |= e->dw[d] != 0.0;
  return any;
}

int mpm_hier_eval(const mpm_hier *h, const double *xp, mpm_hier_weight *w, int max) {
  entry cur[MAX_ENTRIES], next[MAX_ENTRIES];
  double x[MPM_MAX_DIM];
  hier_wrap_point(h, xp, x);
  const int l0 = mpm_hier_level_of(h, x);
  int ncur = stencil(h->level[l0].grid, x, cur), nout = 0;
  for (int k = 0; k < ncur; ++k) lookup_node(h, &h->level[l0], cur[k].gi);
  for (int l = l0; l >= 0 && ncur > 0; --l) {
    const mpm_grid *g = h->level[l].grid;
    int nnext = 0;
    for (int k = 0; k < ncur; ++k) {
      if (!hier_in_box(g, cur[k].gi)) return -1;
      const mpm_lidx node = mpm_grid_local_index(g, cur[k].gi);
      if (!h->level[l].active[node]) {
        /* Level 0's inactive nodes lie under level 1 and never carry a weight here. */
        if (l > 0 && (nnext = push_down(h, &h->level[l - 1], next, nnext, &cur[k])) < 0) return -1;
        continue;
      }
      if (!nonzero(&cur[k], h->dim)) continue;
      if (nout == max) return -1;
      mpm_hier_weight *o = &w[nout++];
      o->level = l, o->node = node, o->w = cur[k].w;
      for (int d = 0; d < MPM_MAX_DIM; ++d) o->dw[d] = d < h->dim ? cur[k].dw[d] : 0.0;
    }
    memcpy(cur, next, (size_t)nnext * sizeof *next);
    ncur = nnext;
  }
  return nout;
}
