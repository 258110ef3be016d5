/* Gas particles that follow the refinement (issue 51, item 3): after every accepted step, a
 * particle whose size is that of a coarser level than the level of its position splits into
 * 2^dim children (fluid_split), and the particles of a finer size than their position's level
 * merge back, 2^dim at a time (fluid_merge), so that every level holds particles of its own
 * spacing. Mass, momentum, total energy and the centre of mass stay exact (fluid_split.h).
 *
 * Size. A gas particle's level of size follows from its reference volume: seeding gives level l
 * particles V0 = (h_l / ppc)^dim, a split divides V0 by 2^dim and a merge sums it, so the level
 * is round(log2(V0_level0 / V0) / dim). No field is stored, and a restart needs nothing.
 *
 * Merging. The candidates of one level of size L are grouped by the slots of the coarser
 * particle lattice (spacing h_{L-1} / ppc, fluid_merge_groups): a slot of c candidates gives
 * floor(c / 2^dim) groups of exactly 2^dim, so every merged particle has the coarser level's
 * size. A slot lies wholly inside or outside
 * each refined region (the regions are unions of coarser spans, whose faces are slot faces for
 * an even ppc), so the merged particle sits on the level of its members. A part-filled slot
 * waits for the rest of its particles. For L >= 2, those a slot leaves over are
 * then grouped by level L - 1's cell (merge_groups): in gas that expanded after it left the
 * finer level (the fan behind a rarefaction) a slot never fills again, and its fine particles
 * stayed fine for the rest of the run (16 % of the particles at the end of Sod on 4 levels;
 * docs/refinement.md). Every level's groups merge in one edit, which copies the set: between
 * regrids only once they remove 1 / MERGE_BATCH of the particles (merge_due), and a merged
 * particle that should merge again does so at a later step.
 *
 * Lag at a face. Split and merge keep the centre of mass, so a parent or group straddling a
 * region's face always leaves particles of the wrong size on the wrong side: children of a
 * parent that has just entered wait outside within s / 4 of the face, and a fine particle that
 * has just left waits in its slot (within H = h_{L-1} / ppc of the face) for its partners. A
 * snapshot may show them (docs/refinement.md; tests/verification/test_refine_gas.py bounds
 * them to H of the face in a uniform stream).
 *
 * Splitting. The children sit at +-s/4 of the parent (s its size): a parent that has just
 * crossed into a finer region may leave some children outside it, which then wait (their slot
 * is not full) and enter with the flow. Splits repeat until no particle is coarser than its
 * level (a regrid may put one two levels below).
 *
 * Without a hierarchy (a regrid found nothing to refine) every position is level 0 and the fine
 * particles merge back.
 *
 * Merges first, then splits (fluid_split.h): a merge removes particles and renumbers the set.
 * The size and position level of every particle are found once per call; after an edit the
 * levels follow the set (a merge's compaction, a split's appended children) and only the
 * particles the edit moved or added are looked up again. */
#include "fluid_internal.h"
#include "fluid_split.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_timer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Level l of size from r = V0_0 / V0 >= 2^(dim (l - 1/2)): round(log2(r) / dim), clamped,
 * without a logarithm (every particle, every step). */
static int size_level_of(int dim, double r) {
  _Static_assert(MPM_HIER_MAX_LEVELS == 5, "one threshold per finer level");
  static const double from[3][MPM_HIER_MAX_LEVELS - 1] = {
      {1.4142135623730951, 2.8284271247461903, 5.656854249492381, 11.313708498984761},
      {2.0, 8.0, 32.0, 128.0},
      {2.8284271247461903, 22.627416997969522, 181.01933598375618, 1448.1546878700494}};
  const double *t = from[dim - 1];
  /* (the thresholds rise: the count of those reached is the level, without a branch; NaN
   * reaches none) */
  return (r >= t[0]) + (r >= t[1]) + (r >= t[2]) + (r >= t[3]);
}

/* The level of size of particle i (0 .. MPM_HIER_MAX_LEVELS - 1), V0_0 level 0's volume. */
int fluid_size_level(const mpm_module *m, double V0_0, mpm_lidx i) {
  const fluid_content *fc = m->content;
  return size_level_of(m->grid->dim, V0_0 / mpm_particles_comp(m->particles, fc->lay.f_V0, 0)[i]);
}

/* The particles' levels: lev[2 i] of size, lev[2 i + 1] of position, with room for the set. */
typedef struct levels {
  unsigned char *lev;
  size_t cap; /* particles lev has room for */
} levels;

static int levels_room(levels *L, mpm_lidx n) {
  if ((size_t)n <= L->cap) return 0;
  unsigned char *grown = realloc(L->lev, 2 * (size_t)n);
  if (!grown) MPM_FAIL_OOM(2 * (size_t)n);
  L->lev = grown, L->cap = (size_t)n;
  return 0;
}

/* Classify particle i again (after it moved, merged or was added). */
static void classify_one(const mpm_module *m, levels *L, mpm_lidx i) {
  const fluid_content *fc = m->content;
  const double V0_0 = pow(m->grid->dx / fc->ppc, m->grid->dim);
  L->lev[2 * i] = (unsigned char)fluid_size_level(m, V0_0, i);
  L->lev[2 * i + 1] = (unsigned char)fluid_position_level(m, NULL, m->particles->data, i);
}

/* The size and position levels of every particle; *parents: those to split (a coarser size
 * than their position's level). */
static int classify(const mpm_module *m, levels *L, mpm_lidx *parents) {
  const fluid_content *fc = m->content;
  const mpm_lidx n = m->particles->n;
  MPM_CALL(levels_room(L, MPM_MAX(n, 1)));
  const int dim = m->grid->dim;
  const double V0_0 = pow(m->grid->dx / fc->ppc, dim);
  const double *V0 = mpm_particles_comp(m->particles, fc->lay.f_V0, 0);
  const unsigned char *at = fluid_position_levels(m, m->particles->data);
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    const int size = size_level_of(dim, V0_0 / V0[i]);
    const int level = fluid_position_level(m, at, m->particles->data, i);
    L->lev[2 * i] = (unsigned char)size, L->lev[2 * i + 1] = (unsigned char)level;
    k += size < level;
  }
  *parents = k;
  return 0;
}

/* Is a cell's group of size L, centred at x, settled: the cells around it (h wide) off level
 * L's region? Particles that have just left the region wait in their slots for their partners,
 * who follow within a few steps (a stream across the region's face), and merge back where their
 * parent was; a group of them taken early would put its particle elsewhere. */
static int settled(const mpm_module *m, int L, double h, const double *x) {
  if (!m->hier) return 1;
  const int dim = m->grid->dim;
  for (int q = 0; q < (dim == 3 ? 27 : dim == 2 ? 9 : 3); ++q) {
    double y[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0, r = q; d < dim; ++d, r /= 3) y[d] = x[d] + (r % 3 - 1) * h;
    mpm_grid_wrap(m->grid, y);
    if (mpm_hier_level_of(m->hier, y) >= L) return 0;
  }
  return 1;
}

/* The groups of the k candidates idx[] of size level L: first by parent slot (the coarser
 * level's particle lattice); then, for L >= 2, those left over (a slot the flow never fills
 * again: the gas expanded since it left the finer level) by the coarser level's cell, h_{L-1}
 * wide from the domain's corner: one of level L - 1's knot spans, which holds ppc^dim slots,
 * lies wholly inside or outside every region and on one rank. Both give full groups of 2^dim;
 * the rest wait, and so do a cell's groups that have not settled. Level 0's spans are centred
 * on its nodes and straddle its cells, and so the ranks' boxes: level-1 particles left over on
 * level 0 stay (a merge there by cell would move mass between level 0's spans, which the
 * starvation criterion counts). */
static int merge_groups(const mpm_module *m, int L, const mpm_lidx *idx, mpm_lidx k,
                        mpm_lidx **start, mpm_lidx **member, mpm_lidx *ng) {
  const fluid_content *fc = m->content;
  const double h = ldexp(m->grid->dx, 1 - L); /* level L - 1's spacing */
  MPM_CALL(fluid_merge_groups(m, idx, k, h / fc->ppc, 0.0, 1, start, member, ng));
  const mpm_lidx grouped = (*start)[*ng];
  if (L < 2 || k - grouped < 1 << m->grid->dim) return 0;
  /* The rest, in idx's order: idx rises (merge_levels' scan), so a member's place in it is
   * found by bisection. */
  unsigned char *in;
  mpm_lidx *rest = malloc(sizeof *rest * (size_t)(k - grouped));
  if (!rest || !(in = calloc((size_t)k, 1))) {
    free(rest), free(*start), free(*member);
    MPM_FAIL_OOM((size_t)k);
  }
  for (mpm_lidx a = 0; a < grouped; ++a) {
    mpm_lidx lo = 0, hi = k; /* the first place whose index is not below the member's */
    while (lo < hi) {
      const mpm_lidx mid = lo + (hi - lo) / 2;
      if (idx[mid] < (*member)[a])
        lo = mid + 1;
      else
        hi = mid;
    }
    in[lo] = 1;
  }
  mpm_lidx kr = 0;
  for (mpm_lidx a = 0; a < k; ++a)
    if (!in[a]) rest[kr++] = idx[a];
  free(in);
  mpm_lidx *s2, *m2, ng2;
  int rc = fluid_merge_groups(m, rest, kr, h / fc->ppc, h, 1, &s2, &m2, &ng2);
  free(rest);
  mpm_lidx *st = rc || !ng2 ? NULL : realloc(*start, sizeof *st * (size_t)(*ng + ng2 + 1));
  if (!rc && ng2 && !st) rc = MPM_ERR_MEMORY;
  if (st) { /* (member has room for all k) */
    *start = st;
    mpm_lidx at = grouped;
    for (mpm_lidx g = 0; g < ng2; ++g) {
      double x[MPM_MAX_DIM];
      const int c = (int)(s2[g + 1] - s2[g]);
      fluid_merge_centre(m, m2 + s2[g], c, x);
      if (!settled(m, L, h, x)) continue;
      for (int a = 0; a < c; ++a) (*member)[at++] = m2[s2[g] + a];
      (*start)[++*ng] = at;
    }
  }
  if (!rc) free(s2), free(m2);
  if (rc) free(*start), free(*member), *start = *member = NULL;
  if (rc == MPM_ERR_MEMORY) MPM_FAIL_OOM(sizeof **start * (size_t)k);
  MPM_CALL(rc);
  return 0;
}

/* Is a merge of r particles (removed on this rank) worth its edit, which copies the whole set?
 * After a regrid always; between regrids when the ranks together remove at least
 * 1 / MERGE_BATCH of their particles: an edit costs each particle about a 25th of its step's
 * work (Sod on 4 levels, callgrind), so such a merge pays for itself within about ten steps,
 * where merging every few groups at once copied the set at almost every step. A fine particle
 * waiting for the batch costs what it did before it left its level. Collective. */
#define MERGE_BATCH 256
static int merge_due(const mpm_module *m, int regrid, mpm_lidx r) {
  if (regrid) return 1;
  double sum[2] = {(double)r, (double)m->particles->n};
  if (m->grid->size > 1) /* (MPI's errors abort: the default handler) */
    MPI_Allreduce(MPI_IN_PLACE, sum, 2, MPI_DOUBLE, MPI_SUM, m->grid->comm);
  return sum[0] > 0.0 && MERGE_BATCH * sum[0] >= sum[1];
}

/* Merge the full groups (merge_groups) of the particles of every level of size L that lie on
 * a coarser level, in one edit, the levels following the set; *merged: the groups merged. A
 * merged particle that lies on a coarser level still merges at the next call. */
static int merge_levels(mpm_module *m, int regrid, levels *lv, mpm_lidx *idx, mpm_lidx *merged) {
  mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const unsigned char *lev = lv->lev;
  mpm_lidx *start = NULL, *member = NULL, ng = 0, nm = 0, removed = 0;
  int rc = 0;
  /* The candidates of every size level L at once, in index order within each: idx[at[L] ..
   * at[L + 1]). */
  mpm_lidx at[MPM_HIER_MAX_LEVELS + 1] = {0};
  for (mpm_lidx i = 0; i < n; ++i)
    if (lev[2 * i] > lev[2 * i + 1]) at[lev[2 * i] + 1]++;
  for (int L = 0; L < MPM_HIER_MAX_LEVELS; ++L) at[L + 1] += at[L];
  mpm_lidx fill[MPM_HIER_MAX_LEVELS];
  memcpy(fill, at, sizeof fill);
  for (mpm_lidx i = 0; at[MPM_HIER_MAX_LEVELS] > 0 && i < n; ++i)
    if (lev[2 * i] > lev[2 * i + 1]) idx[fill[lev[2 * i]]++] = i;
  for (int L = MPM_HIER_MAX_LEVELS - 1; !rc && L >= 1; --L) {
    const mpm_lidx k = at[L + 1] - at[L];
    if (k == 0) continue;
    mpm_lidx *s1, *m1, n1;
    if ((rc = merge_groups(m, L, idx + at[L], k, &s1, &m1, &n1)) != 0) break;
    mpm_lidx *st = n1 ? realloc(start, sizeof *st * (size_t)(ng + n1 + 1)) : start;
    mpm_lidx *mb = n1 ? realloc(member, sizeof *mb * (size_t)(nm + s1[n1])) : member;
    if (st) start = st;
    if (mb) member = mb;
    if (n1 && (!st || !mb)) rc = MPM_ERR_MEMORY;
    if (!rc && n1) {
      if (ng == 0) start[0] = 0;
      for (mpm_lidx a = 0; a < s1[n1]; ++a) member[nm + a] = m1[a];
      for (mpm_lidx g = 1; g <= n1; ++g) start[ng + g] = nm + s1[g];
      removed += s1[n1] - n1, ng += n1, nm += s1[n1];
    }
    free(s1), free(m1);
  }
  if (!merge_due(m, regrid, rc ? 0 : removed)) ng = 0; /* (every rank calls it) */
  /* Each group's kept member (its lowest id, fluid_merge) and the dropped ones, by index. */
  unsigned char *state = !rc && ng ? malloc((size_t)n) : NULL; /* 1 untouched, 2 kept, 0 dropped */
  if (!rc && ng && !state) rc = MPM_ERR_MEMORY;
  if (state) {
    memset(state, 1, (size_t)n);
    for (mpm_lidx g = 0; g < ng; ++g) {
      mpm_lidx keep = member[start[g]];
      for (mpm_lidx a = start[g]; a < start[g + 1]; ++a) {
        state[member[a]] = 0;
        if (p->id[member[a]] < p->id[keep]) keep = member[a];
      }
      state[keep] = 2;
    }
  }
  fluid_split_report rep = {0};
  if (!rc && ng) rc = fluid_merge(m, start, member, ng, &rep);
  free(start), free(member);
  if (!rc && rep.removed > 0) { /* the set was compacted as state says (fluid_merge) */
    mpm_lidx j = 0;
    for (mpm_lidx i = 0; i < n; ++i) {
      if (!state[i]) continue;
      lv->lev[2 * j] = lv->lev[2 * i], lv->lev[2 * j + 1] = lv->lev[2 * i + 1];
      if (state[i] == 2) classify_one(m, lv, j);
      ++j;
    }
    if (j != p->n) rc = MPM_ERR_INTERNAL;
  }
  free(state);
  if (rc == MPM_ERR_MEMORY) MPM_FAIL_OOM((size_t)n);
  if (rc == MPM_ERR_INTERNAL)
    MPM_FAIL(rc, "relevel: the merge left %d particles, not the count its groups give", (int)p->n);
  MPM_CALL(rc);
  *merged += rep.groups;
  return 0;
}

/* Did no rank split (k: this rank's parents)? One rank answers alone; several agree. */
static int none_left(const mpm_grid *g, mpm_lidx k) {
  if (g->size == 1) return k == 0;
  int any = k > 0; /* (MPI's errors abort: the default handler) */
  MPI_Allreduce(MPI_IN_PLACE, &any, 1, MPI_INT, MPI_LOR, g->comm);
  return !any;
}

static int relevel(mpm_module *m, int regrid, int *changed) {
  mpm_lidx *idx = malloc(sizeof *idx * (size_t)MPM_MAX(m->particles->n, 1)); /* (no zeroing) */
  if (!idx) MPM_FAIL_OOM(sizeof *idx * (size_t)MPM_MAX(m->particles->n, 1));
  levels lv = {0};
  mpm_lidx merged = 0;
  /* Split candidates counted in the same scan (a merge adds none: its particle lies outside
   * its members' finer level). */
  mpm_lidx parents = 0;
  int rc = classify(m, &lv, &parents);
  if (!rc) rc = merge_levels(m, regrid, &lv, idx, &merged);
  /* Split until every particle has its level's size: a regrid may put a particle two levels
   * below its new level (idx grows with the set). After a pass only its parents (moved, in
   * place) and their children (appended) are classified again. */
  mpm_lidx split = 0;
  for (int pass = 0; !rc && pass < MPM_HIER_MAX_LEVELS; ++pass) {
    mpm_lidx k = 0;
    const mpm_lidx n0 = m->particles->n;
    for (mpm_lidx i = 0; (pass > 0 || parents > 0) && i < n0; ++i) /* (a merge adds none) */
      if (lv.lev[2 * i] < lv.lev[2 * i + 1]) idx[k++] = i;
    fluid_split_report rep = {0};
    rc = fluid_split(m, idx, k, &rep); /* collective: every rank calls, k = 0 too */
    split += rep.parents;
    if (!rc && none_left(m->grid, k)) break; /* (on every rank alike) */
    if (!rc && pass + 1 < MPM_HIER_MAX_LEVELS) {
      mpm_lidx *grown = realloc(idx, sizeof *idx * (size_t)MPM_MAX(m->particles->n, 1));
      if (!grown)
        rc = MPM_ERR_MEMORY;
      else
        idx = grown;
      if (!rc) rc = levels_room(&lv, MPM_MAX(m->particles->n, 1));
      for (mpm_lidx a = 0; !rc && a < k; ++a) classify_one(m, &lv, idx[a]);
      for (mpm_lidx i = n0; !rc && i < m->particles->n; ++i) classify_one(m, &lv, i);
    }
  }
  free(idx), free(lv.lev);
  MPM_CALL(rc);
  *changed |= merged > 0 || split > 0;
  return 0;
}

int fluid_relevel(mpm_module *m, int regrid, int *changed) {
  const fluid_content *fc = m->content;
  if (!fc->refined) return 0;
  mpm_timer_start(MPM_T_RELEVEL);
  const int rc = relevel(m, regrid, changed);
  mpm_timer_stop(MPM_T_RELEVEL);
  return rc;
}
