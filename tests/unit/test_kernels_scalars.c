/* G2P of nodal scalars (mpm_g2p_args.nscalar), for every shape in 2-D and 3-D on a one-rank
 * grid: an affine nodal field s_i = s0 + b . x_i interpolates to s0 + b . x_p at every particle
 * (the weights sum to one and reproduce linear functions), for two fields at once; they use
 * the same weights as the velocity (a velocity component equal to the first field gives the
 * same values), and asking for them leaves the other outputs bitwise unchanged.
 *
 * Tolerance: 1e-12 relative to |s0| + |b| |x|max. Both identities are exact in real
 * arithmetic; rounding in sums of up to 64 terms leaves about 1e-15, and a wrong weight or
 * node would be off by O(1e-2) relative. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>
#include <math.h>
#include <mpi.h>

#include "mpm_grid.h"
#include "mpm_kernels.h"

#define TOL 1e-12
#define NP  2000

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.2, 2.0, 2.6}, g_dx = 0.1;
static const double g_s0[2] = {0.7, -2.0}, g_b[2][3] = {{0.3, -1.1, 0.6}, {-0.9, 0.4, 1.3}};

static double uniform(uint64_t *state) { /* splitmix64 */
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

static double affine(int j, int dim, const double *x) {
  double s = g_s0[j];
  for (int d = 0; d < dim; ++d) s += g_b[j][d] * x[d];
  return s;
}

static void check_shape(int dim, mpm_shape_kind shape) {
  /* dim is 2 or 3: said so that GCC (-O2 with the sanitizers) does not warn that the
   * per-axis loops below might index past the three axes. */
  if (dim != 2 && dim != 3) abort();
  mpm_grid *g = NULL;
  const int nproc[3] = {1, 1, 1};
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_WORLD, dim, g_lo, g_hi, g_dx, shape, nproc), 0);
  double *s_i[2], *s_out[2], *x[3] = {NULL}, *v_out[3], *a_out[3];
  for (int j = 0; j < 2; ++j) {
    s_i[j] = malloc(sizeof(double) * (size_t)g->nnodes);
    s_out[j] = malloc(sizeof(double) * NP);
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    double xn[3] = {0, 0, 0};
    mpm_lidx r = l;
    for (int d = 0; d < dim; ++d) {
      xn[d] = g->lo[d] + (g->box_lo[d] + (int)(r % g->box_n[d])) * g->dx;
      r /= g->box_n[d];
    }
    for (int j = 0; j < 2; ++j) s_i[j][l] = affine(j, dim, xn);
  }
  uint64_t seed = 17u + (uint64_t)(10 * dim + shape);
  for (int d = 0; d < dim; ++d) {
    x[d] = malloc(sizeof(double) * NP);
    v_out[d] = malloc(sizeof(double) * NP), a_out[d] = malloc(sizeof(double) * NP);
    for (int p = 0; p < NP; ++p)
      x[d][p] = g_lo[d] + 0.1 + (g_hi[d] - g_lo[d] - 0.2) * uniform(&seed);
  }
  double *v_ref[3], *a_ref[3];
  mpm_g2p_args a = {.n = NP, .lp = 0.25};
  for (int d = 0; d < dim; ++d) {
    v_ref[d] = malloc(sizeof(double) * NP), a_ref[d] = malloc(sizeof(double) * NP);
    a.x[d] = x[d], a.v_i[d] = s_i[0], a.a_i[d] = s_i[1];
    a.v_out[d] = v_ref[d], a.a_out[d] = a_ref[d];
  }
  mpm_kernels_get(dim)->g2p(g, &a); /* without scalars */
  a.nscalar = 2;
  for (int j = 0; j < 2; ++j) a.s_i[j] = s_i[j], a.s_out[j] = s_out[j];
  for (int d = 0; d < dim; ++d) a.v_out[d] = v_out[d], a.a_out[d] = a_out[d];
  mpm_kernels_get(dim)->g2p(g, &a);
  int unchanged = 1;
  for (int d = 0; d < dim; ++d)
    for (int p = 0; p < NP; ++p)
      unchanged &= v_out[d][p] == v_ref[d][p] && a_out[d][p] == a_ref[d][p];
  double err = 0.0, same = 0.0;
  for (int j = 0; j < 2; ++j) {
    double scale = fabs(g_s0[j]);
    for (int d = 0; d < dim; ++d) scale += fabs(g_b[j][d]) * 2.6;
    for (int p = 0; p < NP; ++p) {
      double xp[3] = {0, 0, 0};
      for (int d = 0; d < dim; ++d) xp[d] = x[d][p];
      err = fmax(err, fabs(s_out[j][p] - affine(j, dim, xp)) / scale);
      same = fmax(same, fabs(s_out[j][p] - (j == 0 ? v_out[0][p] : a_out[0][p])) / scale);
    }
  }
  printf("  %d-D %-9s scalars s0 + b . x: max error %.2e, vs the velocity %.2e, other outputs "
         "%s\n",
         dim, mpm_shape_name(shape), err, same, unchanged ? "unchanged" : "CHANGED");
  assert_true(err <= TOL);
  assert_true(same <= TOL);
  assert_true(unchanged);
  for (int j = 0; j < 2; ++j) free(s_i[j]), free(s_out[j]);
  for (int d = 0; d < dim; ++d)
    free(x[d]), free(v_out[d]), free(a_out[d]), free(v_ref[d]), free(a_ref[d]);
  mpm_grid_destroy(&g);
}

static void test_affine_scalars(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) check_shape(dim, (mpm_shape_kind)s);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_affine_scalars)};
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
