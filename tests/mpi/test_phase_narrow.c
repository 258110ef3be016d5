/* test_phase_narrow: a phase's nodal passes over its active block (mpm_grid_phase_narrow,
 * common/mpm_grid.h), in 2-D and 3-D, on any number of ranks.
 *
 * A phase holds mass in a small block of nodes (a body beside a large grid). Checked:
 *  - the first narrowing after a widening covers the nodes that hold mass and those where the
 *    last solve left a velocity or an acceleration; the next covers the nodes that hold mass
 *    now and those that did then; each two nodes wider on every side, and no more;
 *  - MPM_PHASE_FOR visits exactly the block's nodes, once each, in increasing index order;
 *  - zero and the nodal solve on the narrowed phase leave every field bit for bit as the
 *    whole-box passes do, when the mass has moved since the last narrowing or since the last
 *    solve before a widening (the velocities the solve must clear lie in the old block);
 *  - a rank holding none of the phase gets an empty block and its passes visit no node;
 *  - the walls' fold and mirror (mpm_bc.h) on a narrowed phase beside a wall leave every field
 *    as on the whole box, at the first narrowing and the next;
 *  - widening gives the whole box back. */
#include "mpm_bc.h"
#include "mpm_grid.h"
#include "mpm_module.h"

#include "mpm_testing.h"

#include <stdlib.h>
#include <string.h>

/* The global node coordinates of box node l. */
static void global_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  gi[1] = gi[2] = 0;
  for (int d = 0; d < g->dim; ++d) gi[d] = g->box_lo[d] + (int)(l % g->box_n[d]), l /= g->box_n[d];
}

/* Is global node gi in the block [lo, hi] (global, inclusive) along every axis? */
static int in_block(int dim, const int *gi, const int *lo, const int *hi) {
  for (int d = 0; d < dim; ++d)
    if (gi[d] < lo[d] || gi[d] > hi[d]) return 0;
  return 1;
}

/* Mass, momentum and force on the nodes of the global block [lo, hi], zero elsewhere; the
 * velocity and acceleration left as a solve on the block [vlo, vhi] left them. */
static void fill(mpm_grid *g, int phase, const int *lo, const int *hi, const int *vlo,
                 const int *vhi) {
  mpm_grid_phase *ph = &g->phase[phase];
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3];
    global_of(g, l, gi);
    const int in = in_block(g->dim, gi, lo, hi), was = in_block(g->dim, gi, vlo, vhi);
    ph->m_i[l] = in ? 1.0 + 0.25 * gi[0] + 0.5 * gi[1] + 0.125 * gi[2] : 0.0;
    for (int d = 0; d < g->dim; ++d) {
      ph->mv_i[d][l] = in ? 0.3 * (d + 1) * ph->m_i[l] - 0.1 * gi[d] : 0.0;
      ph->f_i[d][l] = in ? -0.7 + 0.01 * gi[0] * (d + 1) : 0.0;
      ph->v_i[d][l] = was ? 5.0 + d + 0.03 * gi[1] : 0.0;
      ph->a_i[d][l] = was ? -3.0 + 0.07 * gi[0] : 0.0;
    }
  }
}

/* Copy (to = 1) or compare (to = 0) every field of the phase with the copy in buf. */
static int fields(mpm_grid *g, int phase, double *buf, int to) {
  mpm_grid_phase *ph = &g->phase[phase];
  double *a[1 + 4 * MPM_MAX_DIM];
  int n = 0;
  a[n++] = ph->m_i;
  for (int d = 0; d < g->dim; ++d)
    a[n++] = ph->mv_i[d], a[n++] = ph->f_i[d], a[n++] = ph->v_i[d], a[n++] = ph->a_i[d];
  const size_t bytes = sizeof(double) * (size_t)g->nnodes;
  int same = 1;
  for (int k = 0; k < n; ++k)
    if (to)
      memcpy(buf + k * g->nnodes, a[k], bytes);
    else
      same &= memcmp(buf + k * g->nnodes, a[k], bytes) == 0;
  return same;
}

/* Does MPM_PHASE_FOR visit exactly the box nodes of the global block [lo, hi], in increasing
 * order? (hi < lo along an axis: no node.) */
static int visits_block(const mpm_grid *g, const mpm_grid_phase *ph, const int *lo, const int *hi) {
  mpm_lidx count = 0, expect = 0, last = -1;
  int ok = 1;
  MPM_PHASE_FOR(g, ph, l) {
    int gi[3];
    global_of(g, l, gi);
    ok &= l > last && in_block(g->dim, gi, lo, hi);
    last = l, count++;
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3];
    global_of(g, l, gi);
    expect += in_block(g->dim, gi, lo, hi);
  }
  return ok && count == expect;
}

/* The blocks [a_lo, a_hi] and [b_lo, b_hi] (global, inclusive) as this rank holds them, padded
 * by 2 and clipped to its box, into [lo, hi]; returns whether the rank holds any of them. */
static int padded_union(const mpm_grid *g, const int *a_lo, const int *a_hi, const int *b_lo,
                        const int *b_hi, int *lo, int *hi) {
  int clo[3] = {1000, 1000, 1000}, chi[3] = {-1000, -1000, -1000}, any = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3];
    global_of(g, l, gi);
    if (!in_block(g->dim, gi, a_lo, a_hi) && !in_block(g->dim, gi, b_lo, b_hi)) continue;
    any = 1;
    for (int d = 0; d < g->dim; ++d)
      clo[d] = gi[d] < clo[d] ? gi[d] : clo[d], chi[d] = gi[d] > chi[d] ? gi[d] : chi[d];
  }
  for (int d = 0; d < 3; ++d) {
    const int blo = d < g->dim ? g->box_lo[d] : 0;
    const int bhi = d < g->dim ? g->box_lo[d] + g->box_n[d] - 1 : 0;
    lo[d] = d < g->dim ? (clo[d] - 2 > blo ? clo[d] - 2 : blo) : 0;
    hi[d] = d < g->dim ? (chi[d] + 2 < bhi ? chi[d] + 2 : bhi) : 0;
  }
  return any;
}

/* The block visited is [lo, hi] where the rank holds any of the phase, none elsewhere. */
static int visits_expected(const mpm_grid *g, const mpm_grid_phase *ph, int any, const int *lo,
                           const int *hi) {
  const int none[3] = {0, 0, 0}, nonehi[3] = {-1, -1, -1};
  return any ? visits_block(g, ph, lo, hi) : visits_block(g, ph, nonehi, none);
}

static void run(int dim) {
  const double lo[3] = {0, 0, 0}, hi[3] = {2.0, 1.0, 0.75};
  const double dx = 0.125; /* 16 x 8 (x 6) cells */
  mpm_grid *g = NULL;
  int phase = -1;
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, dim, lo, hi, dx, MPM_SHAPE_QUADRATIC, NULL) == 0,
        "grid (dim %d)", dim);
  CHECK(mpm_grid_add_phase(g, "body", &phase) == 0, "phase");
  mpm_grid_phase *ph = &g->phase[phase];
  double *ref = malloc(sizeof(double) * (1 + 4 * MPM_MAX_DIM) * (size_t)g->nnodes);
  /* the body at nodes 3..5 (x), 2..4 (y), 1..2 (z); then moved one node up x */
  const int b0lo[3] = {3, 2, 1}, b0hi[3] = {5, 4, 2}, b1lo[3] = {4, 2, 1}, b1hi[3] = {6, 4, 2};
  const int none[3] = {0, 0, 0}, nonehi[3] = {-1, -1, -1};

  int all_lo[3] = {-1000, -1000, -1000}, all_hi[3] = {1000, 1000, 1000};
  int elo[3], ehi[3];
  fill(g, phase, b0lo, b0hi, none, nonehi);
  mpm_grid_phase_narrow(g, phase);
  int any = padded_union(g, b0lo, b0hi, b0lo, b0hi, elo, ehi);
  CHECK(visits_expected(g, ph, any, elo, ehi),
        "dim %d, rank %d: the first narrowing, no velocity left: the mass padded by 2", dim,
        g_rank);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "solve");

  /* The first narrowing after a widening, the last solve's velocities far from the mass: the
   * block must cover both, padded by 2, clipped to the box. */
  const int b2lo[3] = {11, 5, 3}, b2hi[3] = {12, 6, 4};
  fill(g, phase, b1lo, b1hi, b2lo, b2hi);
  mpm_grid_phase_widen(g, phase);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "whole-box solve");
  fields(g, phase, ref, 1); /* the reference: the whole box */
  any = padded_union(g, b1lo, b1hi, b2lo, b2hi, elo, ehi);
  fill(g, phase, b1lo, b1hi, b2lo, b2hi);
  mpm_grid_phase_narrow(g, phase);
  CHECK(visits_expected(g, ph, any, elo, ehi),
        "dim %d, rank %d: the first narrowing: the mass and the last solve's velocities, padded "
        "by 2",
        dim, g_rank);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "narrowed solve");
  CHECK(fields(g, phase, ref, 0),
        "dim %d, rank %d: the first narrowed solve leaves every field as the whole-box solve does",
        dim, g_rank);

  /* The body moves; the block must cover both positions, padded by 2, clipped to the box. */
  fill(g, phase, b1lo, b1hi, b0lo, b0hi);
  mpm_grid_phase_widen(g, phase);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "whole-box solve");
  fields(g, phase, ref, 1);
  any = padded_union(g, b0lo, b0hi, b1lo, b1hi, elo, ehi);
  /* the same state narrowed as a second substep finds it */
  mpm_grid_phase_widen(g, phase);
  fill(g, phase, b0lo, b0hi, none, nonehi);
  mpm_grid_phase_narrow(g, phase);
  fill(g, phase, b1lo, b1hi, b0lo, b0hi);
  mpm_grid_phase_narrow(g, phase);
  CHECK(visits_expected(g, ph, any, elo, ehi),
        "dim %d, rank %d: the block is both positions padded by 2", dim, g_rank);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "narrowed solve");
  CHECK(fields(g, phase, ref, 0),
        "dim %d, rank %d: the narrowed solve leaves every field as the "
        "whole-box solve does",
        dim, g_rank);
  /* zero: every field of the deposit, on the block, leaves the whole phase empty */
  mpm_grid_phase_zero(g, phase);
  int empty = 1;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    empty &= ph->m_i[l] == 0.0;
    for (int d = 0; d < dim; ++d) empty &= ph->mv_i[d][l] == 0.0 && ph->f_i[d][l] == 0.0;
  }
  CHECK(empty, "dim %d, rank %d: zero on the block empties the deposit", dim, g_rank);
  mpm_grid_phase_widen(g, phase);
  CHECK(visits_block(g, ph, all_lo, all_hi), "dim %d: widening gives the whole box", dim);
  free(ref);
  mpm_grid_destroy(&g);
}

/* A body on the wall y = 0 (its mass on the pad nodes beyond it too): fold, solve and mirror
 * on the narrowed phase against the same on the whole box. */
static void walls(int dim) {
  const double lo[3] = {0, 0, 0}, hi[3] = {2.0, 1.0, 0.75};
  mpm_grid *g = NULL;
  int phase = -1;
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, dim, lo, hi, 0.125, MPM_SHAPE_QUADRATIC, NULL) == 0,
        "grid (dim %d)", dim);
  CHECK(mpm_grid_add_phase(g, "body", &phase) == 0, "phase");
  mpm_walls w;
  for (int d = 0; d < MPM_MAX_DIM; ++d) w.face[d][0] = w.face[d][1] = MPM_WALL_SLIP;
  mpm_node_constraints c = {0};
  CHECK(mpm_constraints_add_walls(&c, &w, g) == 0, "walls");
  double *ref = malloc(sizeof(double) * (1 + 4 * MPM_MAX_DIM) * (size_t)g->nnodes);
  const int blo[3] = {3, -1, 1}, bhi[3] = {5, 2, 2}, none[3] = {0, 0, 0}, nonehi[3] = {-1, -1, -1};
  fill(g, phase, blo, bhi, none, nonehi);
  mpm_constraints_fold(&c, g, phase);
  CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "whole-box solve");
  mpm_constraints_apply(&c, g, phase);
  fields(g, phase, ref, 1);
  for (int round = 0; round < 2; ++round) { /* the first narrowing, then the next */
    fill(g, phase, blo, bhi, none, nonehi);
    mpm_grid_phase_narrow(g, phase);
    mpm_constraints_fold(&c, g, phase);
    CHECK(mpm_grid_phase_update(g, phase, 1e-3) == 0, "narrowed solve");
    mpm_constraints_apply(&c, g, phase);
    CHECK(fields(g, phase, ref, 0),
          "dim %d, rank %d, round %d: the walls on the narrowed phase leave every field as on "
          "the whole box",
          dim, g_rank, round);
  }
  mpm_grid_phase_widen(g, phase);
  mpm_constraints_free(&c);
  free(ref);
  mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  run(2);
  run(3);
  walls(2);
  walls(3);
  int rc = mpm_test_finish("test_phase_narrow");
  MPI_Finalize();
  return rc ? 1 : 0;
}
