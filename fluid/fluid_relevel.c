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
 * waits for the rest of its particles; in a flow that never fills it they stay fine.
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
 * The size and position level of every particle are found once and again only after the set
 * changed (a level of position costs a walk down the hierarchy). */
#include "fluid_internal.h"
#include "fluid_split.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_timer.h"

#include <math.h>
#include <stdlib.h>

/* The level of size of particle i (0 .. MPM_HIER_MAX_LEVELS - 1), V0_0 level 0's volume. */
int fluid_size_level(const mpm_module *m, double V0_0, mpm_lidx i) {
  /* round(log2(r) / dim), clamped, without a logarithm (every particle, every step): level l
   * from r >= 2^(dim (l - 1/2)) on. */
  _Static_assert(MPM_HIER_MAX_LEVELS == 5, "one threshold per finer level");
  static const double from[3][MPM_HIER_MAX_LEVELS - 1] = {
      {1.4142135623730951, 2.8284271247461903, 5.656854249492381, 11.313708498984761},
      {2.0, 8.0, 32.0, 128.0},
      {2.8284271247461903, 22.627416997969522, 181.01933598375618, 1448.1546878700494}};
  const fluid_content *fc = m->content;
  const double r = V0_0 / mpm_particles_comp(m->particles, fc->lay.f_V0, 0)[i];
  const double *t = from[m->grid->dim - 1];
  int l = 0;
  while (l + 1 < MPM_HIER_MAX_LEVELS && r >= t[l]) ++l;
  return l;
}

/* The size and position levels of every particle: lev[2 i] and lev[2 i + 1] (room for the set,
 * grown as it grows). */
static int classify(const mpm_module *m, unsigned char **lev) {
  const fluid_content *fc = m->content;
  const mpm_lidx n = m->particles->n;
  unsigned char *grown = realloc(*lev, 2 * (size_t)MPM_MAX(n, 1));
  if (!grown) MPM_FAIL_OOM(2 * (size_t)MPM_MAX(n, 1));
  *lev = grown;
  const double V0_0 = pow(m->grid->dx / fc->ppc, m->grid->dim);
  const unsigned char *at = fluid_position_levels(m, m->particles->data);
  for (mpm_lidx i = 0; i < n; ++i) {
    grown[2 * i] = (unsigned char)fluid_size_level(m, V0_0, i);
    grown[2 * i + 1] = (unsigned char)fluid_position_level(m, at, m->particles->data, i);
  }
  return 0;
}

/* Merge the full groups of the particles of size level L that lie on a coarser level (lev from
 * classify); *merged grows by the groups merged. */
static int merge_level(mpm_module *m, int L, const unsigned char *lev, mpm_lidx *idx,
                       mpm_lidx *merged) {
  const fluid_content *fc = m->content;
  const mpm_lidx n = m->particles->n;
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; ++i)
    if (lev[2 * i] == L && lev[2 * i + 1] < L) idx[k++] = i;
  if (k == 0) return 0;
  mpm_lidx *start, *member, ng;
  const double H = ldexp(m->grid->dx, 1 - L) / fc->ppc; /* level L - 1's particle spacing */
  MPM_CALL(fluid_merge_groups(m, idx, k, H, 1, &start, &member, &ng));
  fluid_split_report rep = {0};
  const int rc = ng ? fluid_merge(m, start, member, ng, &rep) : 0;
  free(start), free(member);
  *merged += rep.groups;
  return rc;
}

/* Did no rank split (k: this rank's parents)? One rank answers alone; several agree. */
static int none_left(const mpm_grid *g, mpm_lidx k) {
  if (g->size == 1) return k == 0;
  int any = k > 0; /* (MPI's errors abort: the default handler) */
  MPI_Allreduce(MPI_IN_PLACE, &any, 1, MPI_INT, MPI_LOR, g->comm);
  return !any;
}

static int relevel(mpm_module *m, int *changed) {
  mpm_lidx *idx;
  MPM_ALLOC(idx, m->particles->n > 0 ? m->particles->n : 1);
  unsigned char *lev = NULL;
  mpm_lidx merged = 0;
  int rc = classify(m, &lev);
  for (int L = MPM_HIER_MAX_LEVELS - 1; !rc && L >= 1; --L) {
    const mpm_lidx before = merged;
    rc = merge_level(m, L, lev, idx, &merged);
    if (!rc && merged > before) rc = classify(m, &lev); /* the set changed */
  }
  /* Split until every particle has its level's size: a regrid may put a particle two levels
   * below its new level (idx grows with the set). */
  mpm_lidx split = 0;
  for (int pass = 0; !rc && pass < MPM_HIER_MAX_LEVELS; ++pass) {
    mpm_lidx k = 0;
    if (pass > 0 && (rc = classify(m, &lev)) != 0) break; /* after the last pass's splits */
    for (mpm_lidx i = 0; i < m->particles->n; ++i)
      if (lev[2 * i] < lev[2 * i + 1]) idx[k++] = i;
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
    }
  }
  free(idx), free(lev);
  MPM_CALL(rc);
  *changed |= merged > 0 || split > 0;
  return 0;
}

int fluid_relevel(mpm_module *m, int *changed) {
  const fluid_content *fc = m->content;
  if (!fc->refined) return 0;
  mpm_timer_start(MPM_T_RELEVEL);
  const int rc = relevel(m, changed);
  mpm_timer_stop(MPM_T_RELEVEL);
  return rc;
}
