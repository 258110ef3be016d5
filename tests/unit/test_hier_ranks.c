/* The refinement hierarchy on a grid split over ranks (mpm_hier.h, ranks) against the same
 * hierarchy on one rank (MPI_COMM_SELF), on every rank: a 2-D grid periodic along x with a
 * level-1 box across the x faces and a level-2 box inside a second level-1 box.
 *  - The level of points anywhere in the domain (far from a rank's part of level 0 too) is the
 *    one rank's.
 *  - A deposit of random points (each rank depositing those it owns), restricted, with level
 *    0's halo sum: every finer level equals the one rank's on every node, level 0 on every
 *    owned node, to roundoff (1e-13 of the largest: the sums over the ranks change the order
 *    of the additions).
 *  - A nodal field set on level 0's owned nodes (the halo filling the ghosts) and prolonged:
 *    every finer level equals the one rank's to roundoff.
 * Able to fail: without the sum over the ranks (mpm_hier_basis.c, sum_ranks) level 0's deposit
 * differs by 0.29 of the largest. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>
#include <mpi.h>

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_random.h"

enum { NPTS = 4000 };

typedef struct side {
  mpm_grid *g;
  mpm_hier *h;
  int phase;
} side;

static void make(side *s, MPI_Comm comm) {
  const double lo[2] = {0, 0}, hi[2] = {2, 1};
  const int nproc[2] = {0, 1}, periodic[2] = {1, 0};
  const mpm_hier_box box[3] = {
      {1, {-0.3, 0.3}, {0.3, 0.7}}, {1, {0.8, 0.2}, {1.5, 0.8}}, {2, {1.0, 0.35}, {1.3, 0.65}}};
  char why[256] = "";
  assert_int_equal(
      mpm_grid_new_periodic(&s->g, comm, 2, lo, hi, 0.05, MPM_SHAPE_QUADRATIC, nproc, periodic), 0);
  assert_int_equal(mpm_grid_add_phase(s->g, "test", &s->phase), 0);
  const int rc = mpm_hier_new(&s->h, s->g, 3, box, 3, 1, why, sizeof why);
  if (rc) print_error("%s\n", why);
  assert_int_equal(rc, 0);
}

static void unmake(side *s) {
  mpm_hier_destroy(&s->h);
  mpm_grid_destroy(&s->g);
}

/* Deposit the points of x (n) on s, all of them or those s's rank owns; restrict and sum level
 * 0's ghosts into their owners. */
static void deposit(side *s, double (*x)[NPTS], const double *m, const double *v, int owned) {
  static double xs[2][NPTS], ms[NPTS], vs[NPTS];
  mpm_lidx n = 0;
  for (int i = 0; i < NPTS; ++i) {
    const double p[2] = {x[0][i], x[1][i]};
    if (owned && mpm_grid_owner_of(s->g, p) != s->g->rank) continue;
    xs[0][n] = p[0], xs[1][n] = p[1], ms[n] = m[i], vs[n] = v[i], ++n;
  }
  mpm_p2g_args a = {.n = n, .x = {xs[0], xs[1]}, .v = {vs, vs}, .m = ms};
  mpm_hier_phase_zero(s->h, s->phase);
  assert_int_equal(mpm_hier_p2g(s->h, s->phase, &a), 0);
  mpm_hier_restrict(s->h, s->phase);
  mpm_grid_phase *ph = &s->g->phase[s->phase];
  double *f[3] = {ph->m_i, ph->mv_i[0], ph->mv_i[1]};
  assert_int_equal(mpm_grid_halo_reverse(s->g, f, 3), 0);
}

/* The largest difference of a[l] (split) from b[l] (one rank) over level l's nodes (level 0:
 * the owned ones, matched by global index), over the largest |b|. */
static double level_diff(const side *sp, const side *one, int l, const double *a, const double *b) {
  const mpm_grid *g = sp->h->level[l].grid, *o = one->h->level[l].grid;
  double worst = 0.0, big = 1e-300;
  for (mpm_lidx k = 0; k < o->nnodes; ++k) big = fmax(big, fabs(b[k]));
  for (mpm_lidx k = 0; k < g->nnodes; ++k) {
    if (l == 0 && !mpm_grid_node_is_owned(g, k)) continue;
    int gi[3] = {0, 0, 0};
    mpm_lidx r = k;
    for (int d = 0; d < 2; ++d) gi[d] = g->box_lo[d] + (int)(r % g->box_n[d]), r /= g->box_n[d];
    worst = fmax(worst, fabs(a[k] - b[mpm_grid_local_index(o, gi)]));
  }
  return worst / big;
}

static void test_ranks(void **state) {
  (void)state;
  side sp, one;
  make(&sp, MPI_COMM_WORLD);
  make(&one, MPI_COMM_SELF);
  assert_true(sp.g->size > 1);
  static double x[2][NPTS], m[NPTS], v[NPTS];
  uint64_t rng = 12345; /* the same points on every rank */
  for (int i = 0; i < NPTS; ++i) {
    x[0][i] = 2.0 * mpm_test_uniform(&rng), x[1][i] = mpm_test_uniform(&rng);
    m[i] = 1.0 + mpm_test_uniform(&rng), v[i] = mpm_test_uniform(&rng) - 0.5;
    const double p[2] = {x[0][i], x[1][i]};
    assert_int_equal(mpm_hier_level_of(sp.h, p), mpm_hier_level_of(one.h, p));
  }
  deposit(&sp, x, m, v, 1);
  deposit(&one, x, m, v, 0);
  for (int l = 0; l < 3; ++l) {
    const mpm_grid_phase *a = &sp.h->level[l].grid->phase[sp.phase],
                         *b = &one.h->level[l].grid->phase[one.phase];
    const double dm = level_diff(&sp, &one, l, a->m_i, b->m_i),
                 dp = level_diff(&sp, &one, l, a->mv_i[0], b->mv_i[0]);
    print_message("level %d: deposit m %.1e, m v %.1e of the one rank's\n", l, dm, dp);
    assert_true(dm <= 1e-13 && dp <= 1e-13);
  }
  /* A nodal field on level 0's owned nodes (the ghosts from the halo), prolonged. */
  side *both[2] = {&sp, &one};
  for (int s = 0; s < 2; ++s) {
    mpm_grid *g = both[s]->g;
    double *v0 = g->phase[both[s]->phase].v_i[0];
    for (mpm_lidx k = 0; k < g->nnodes; ++k) {
      int gi[2];
      mpm_lidx r = k;
      for (int d = 0; d < 2; ++d) gi[d] = g->box_lo[d] + (int)(r % g->box_n[d]), r /= g->box_n[d];
      const int i = ((gi[0] % 40) + 40) % 40; /* periodic along x */
      v0[k] = sin(0.3 * i) + cos(0.7 * gi[1]);
    }
    if (s == 0) assert_int_equal(mpm_grid_halo_forward(g, &v0, 1), 0);
    mpm_hier_prolong(both[s]->h, both[s]->phase);
  }
  for (int l = 1; l < 3; ++l) {
    const double dv = level_diff(&sp, &one, l, sp.h->level[l].grid->phase[sp.phase].v_i[0],
                                 one.h->level[l].grid->phase[one.phase].v_i[0]);
    print_message("level %d: prolonged v %.1e of the one rank's\n", l, dv);
    assert_true(dv <= 1e-13);
  }
  unmake(&sp);
  unmake(&one);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_ranks)};
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
