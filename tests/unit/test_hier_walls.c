/* The refinement hierarchy (mpm_hier.h) at walls: levels that touch walls, on one rank.
 *   2-D [0, 2] x [0, 1], dx = 0.1, no periodic axis; walls: x_lo no-slip, y_lo and y_hi slip,
 *   x_hi none (not mirrored). Level 1: a box in the corner x_lo / y_lo, [0, 0.8] x [0, 0.6],
 *   and one on the top wall, [1.0, 1.5] x [0.6, 1.0]; level 2 in the corner, [0, 0.4] x [0, 0.3];
 *   buffer 1.
 *
 *  (1) Symmetry: every box node beyond a wall whose mirror (computed here from mpm_hier.h's
 *      formula) lies in the box has the mirror's active flag, on every level; the regions reach
 *      the walls (the first nodes inside the corner are active on levels 1 and 2, level 0's
 *      corner node is refined). Exact (flags).
 *  (2) Partition of unity at 10,000 random points, half within 0.15 of a wall: sum w = 1 to
 *      1e-14, w >= 0, every level holds points (test_hier_basis's tolerance); a point past a
 *      wall stays on a level whose box holds its stencil.
 *  (3) Fold: 20,000 random particles deposited and restricted, the finer levels folded: the
 *      finer nodes beyond a wall hold exactly zero mass, and the active nodes of all levels
 *      hold the particles' mass to 1e-14 (summed in long double; the fold only moves mass).
 *  (4) Apply: random velocities on the finer levels, then mpm_hier_walls_apply: every node
 *      beyond one wall (not a corner) holds its mirror's velocity, the wall's constrained
 *      components negated, exactly. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>
#include <mpi.h>

#include "hier_level_check.h"
#include "mpm_hier.h"
#include "mpm_random.h"

#define MAXW (27 * MPM_HIER_MAX_LEVELS)

/* Components constrained per face [axis][side]: x_lo no-slip, y slip, x_hi none. */
static const unsigned char g_wall[MPM_MAX_DIM][2] = {{3, 0}, {2, 2}, {0, 0}};

typedef struct wfix {
  mpm_grid *grid;
  mpm_hier *h;
  int phase;
} wfix;

static void wfix_make(wfix *f) {
  memset(f, 0, sizeof *f);
  const int nproc[3] = {1, 1, 1};
  const double lo[3] = {0, 0, 0}, hi[3] = {2, 1, 0};
  assert_int_equal(
      mpm_grid_new(&f->grid, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc), 0);
  assert_int_equal(mpm_grid_add_phase(f->grid, "test", &f->phase), 0);
  const mpm_hier_box b[3] = {
      {1, {0.0, 0.0}, {0.8, 0.6}}, {1, {1.0, 0.6}, {1.5, 1.0}}, {2, {0.0, 0.0}, {0.4, 0.3}}};
  char why[256] = "";
  const int rc = mpm_hier_new_walled(&f->h, f->grid, 3, b, 3, 1, g_wall, why, sizeof why);
  if (rc) fprintf(stderr, "%s\n", why);
  assert_int_equal(rc, 0);
}

static void wfix_free(wfix *f) {
  mpm_hier_destroy(&f->h);
  mpm_grid_destroy(&f->grid);
}

/* Global indices of box node n of g. */
static void node_of(const mpm_grid *g, mpm_lidx n, int *gi) {
  gi[0] = g->box_lo[0] + (int)(n % g->box_n[0]);
  gi[1] = g->box_lo[1] + (int)(n / g->box_n[0]);
  gi[2] = 0;
}

static int in_box(const mpm_grid *g, const int *gi) {
  for (int d = 0; d < 2; ++d)
    if (gi[d] < g->box_lo[d] || gi[d] >= g->box_lo[d] + g->box_n[d]) return 0;
  return 1;
}

/* The side (0, 1) of the wall of axis d that index i of level l lies beyond, or -1. */
static int beyond(const wfix *f, int l, int d, int i) {
  const int lo2 = (1 << l) - 1, hi2 = 2 * (f->grid->ncells[d] << l) + lo2;
  if (g_wall[d][0] && 2 * i < lo2) return 0;
  if (g_wall[d][1] && 2 * i > hi2) return 1;
  return -1;
}

static int mirror(const wfix *f, int l, int d, int i, int side) {
  const int lo2 = (1 << l) - 1, hi2 = 2 * (f->grid->ncells[d] << l) + lo2;
  return side == 0 ? lo2 - i : hi2 - i;
}

static void test_symmetry(void **state) {
  (void)state;
  wfix f;
  wfix_make(&f);
  int pairs = 0;
  for (int l = 0; l < 3; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    for (mpm_lidx n = 0; n < g->nnodes; ++n) {
      int gi[3];
      node_of(g, n, gi);
      for (int d = 0; d < 2; ++d) {
        const int side = beyond(&f, l, d, gi[d]);
        if (side < 0) continue;
        int gm[3] = {gi[0], gi[1], 0};
        gm[d] = mirror(&f, l, d, gi[d], side);
        if (!in_box(g, gm)) continue;
        assert_int_equal(f.h->level[l].active[n],
                         f.h->level[l].active[mpm_grid_local_index(g, gm)]);
        ++pairs;
      }
    }
  }
  assert_true(pairs > 100);
  /* level 1 at x_lo above level 2 (y = 0.475), level 2 in the corner, level 0 on the corner */
  const int c1[3] = {1, 10, 0}, c2[3] = {2, 2, 0}, c0[3] = {0, 0, 0};
  assert_true(f.h->level[1].active[mpm_grid_local_index(f.h->level[1].grid, c1)]);
  assert_true(f.h->level[2].active[mpm_grid_local_index(f.h->level[2].grid, c2)]);
  assert_false(f.h->level[0].active[mpm_grid_local_index(f.grid, c0)]);
  wfix_free(&f);
}

/* Random point k: even k over the domain, odd k within 0.15 of a wall (x_lo, y_lo or y_hi). */
static void point(uint64_t *rng, int k, double *x) {
  x[0] = 2.0 * mpm_test_uniform(rng), x[1] = mpm_test_uniform(rng), x[2] = 0.0;
  if (k % 2 == 0) return;
  const double u = 0.15 * mpm_test_uniform(rng);
  const int which = k / 2 % 3;
  if (which == 0) x[0] = u;
  if (which == 1) x[1] = u;
  if (which == 2) x[1] = 1.0 - u;
}

static void test_pou(void **state) {
  (void)state;
  wfix f;
  wfix_make(&f);
  uint64_t rng = 77;
  int per_level[MPM_HIER_MAX_LEVELS] = {0};
  double ew = 0.0;
  mpm_hier_weight w[MAXW];
  for (int k = 0; k < 10000; ++k) {
    double x[3];
    point(&rng, k, x);
    per_level[mpm_hier_level_of(f.h, x)]++;
    hier_check_level(f.h, x);
    const int n = mpm_hier_eval(f.h, x, w, MAXW);
    assert_true(n > 0);
    double sw = 0.0;
    for (int q = 0; q < n; ++q) {
      assert_true(w[q].w >= 0.0);
      sw += w[q].w;
    }
    ew = fmax(ew, fabs(sw - 1.0));
  }
  /* A point 1.6 level-0 cells past y_lo (an integrator's stage may step past a wall): its
   * mirrored masks would send it to level 2, whose box stops two nodes past the wall; it stays
   * on level 1, whose box holds its stencil (the transfers then stay inside the boxes). */
  const double past[3] = {0.1, -0.08, 0.0};
  assert_int_equal(mpm_hier_level_of(f.h, past), 1);
  printf("walls: partition of unity to %.1e; points per level %d %d %d\n", ew, per_level[0],
         per_level[1], per_level[2]);
  assert_true(ew <= 1e-14);
  for (int l = 0; l < 3; ++l) assert_true(per_level[l] > 100);
  wfix_free(&f);
}

static void test_fold(void **state) {
  (void)state;
  wfix f;
  wfix_make(&f);
  enum { N = 20000 };
  double *x[2], *v[2], *m = calloc(N, sizeof *m);
  for (int d = 0; d < 2; ++d) x[d] = calloc(N, sizeof *x[d]), v[d] = calloc(N, sizeof *v[d]);
  uint64_t rng = 5;
  long double M = 0;
  for (int i = 0; i < N; ++i) {
    double p[3];
    point(&rng, i, p);
    for (int d = 0; d < 2; ++d) x[d][i] = p[d], v[d][i] = 2 * mpm_test_uniform(&rng) - 1;
    m[i] = 0.5 + mpm_test_uniform(&rng);
    M += m[i];
  }
  mpm_hier_phase_zero(f.h, f.phase);
  mpm_p2g_args a = {.n = N, .m = m};
  for (int d = 0; d < 2; ++d) a.x[d] = x[d], a.v[d] = v[d];
  assert_int_equal(mpm_hier_p2g(f.h, f.phase, &a), 0);
  mpm_hier_restrict(f.h, f.phase);
  mpm_hier_walls_fold(f.h, f.phase);
  long double sum = 0;
  for (int l = 0; l < 3; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    const double *mi = g->phase[f.phase].m_i;
    for (mpm_lidx n = 0; n < g->nnodes; ++n) {
      if (f.h->level[l].active[n]) sum += mi[n];
      int gi[3];
      node_of(g, n, gi);
      if (l > 0 && (beyond(&f, l, 0, gi[0]) >= 0 || beyond(&f, l, 1, gi[1]) >= 0))
        assert_true(mi[n] == 0.0);
    }
  }
  const double err = (double)fabsl(sum - M) / (double)M;
  printf("walls: mass after restriction and fold %.1e\n", err);
  assert_true(err <= 1e-14);
  for (int d = 0; d < 2; ++d) free(x[d]), free(v[d]);
  free(m);
  wfix_free(&f);
}

static void test_apply(void **state) {
  (void)state;
  wfix f;
  wfix_make(&f);
  uint64_t rng = 9;
  for (int l = 1; l < 3; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    for (int e = 0; e < 2; ++e)
      for (mpm_lidx n = 0; n < g->nnodes; ++n)
        g->phase[f.phase].v_i[e][n] = g->phase[f.phase].a_i[e][n] = mpm_test_uniform(&rng);
  }
  mpm_hier_walls_apply(f.h, f.phase);
  int checked = 0;
  for (int l = 1; l < 3; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f.phase];
    for (mpm_lidx n = 0; n < g->nnodes; ++n) {
      int gi[3];
      node_of(g, n, gi);
      const int sx = beyond(&f, l, 0, gi[0]), sy = beyond(&f, l, 1, gi[1]);
      if ((sx >= 0) == (sy >= 0)) continue; /* inside, or a corner */
      const int d = sx >= 0 ? 0 : 1, side = sx >= 0 ? sx : sy;
      int gm[3] = {gi[0], gi[1], 0};
      gm[d] = mirror(&f, l, d, gi[d], side);
      if (!in_box(g, gm)) continue;
      const mpm_lidx s = mpm_grid_local_index(g, gm);
      for (int e = 0; e < 2; ++e) {
        const double sign = (g_wall[d][side] >> e) & 1 ? -1.0 : 1.0;
        assert_true(ph->v_i[e][n] == sign * ph->v_i[e][s]);
        assert_true(ph->a_i[e][n] == sign * ph->a_i[e][s]);
      }
      ++checked;
    }
  }
  assert_true(checked > 50);
  wfix_free(&f);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_symmetry),
      cmocka_unit_test(test_pou),
      cmocka_unit_test(test_fold),
      cmocka_unit_test(test_apply),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
