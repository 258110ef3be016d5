/* The kernels' scalar paths (mpm_kernels.h), for every shape in 2-D and 3-D on a one-rank grid,
 * against the full kernels on random particles and random nodal fields:
 *  (i) the lean deposit (v[0] NULL) of masses m and a stress, isotropic (viso) or full (vsig),
 *      gives the nodal mass and force of the full deposit with zero velocity (and vsig = viso I),
 *      and leaves the momentum alone; with m or the stress alone, that part alone;
 *  (ii) the scalar gather (v_out[0] NULL) gives the full gather's scalars, and div_out its
 *      trace of L, L_00 + L_11 (+ L_22), for one to three scalars with and without div_out;
 *  (iii) the two-scalar deposit (m and s, v[0] NULL) gives the nodal mass and mv_i[0] of the
 *      full deposit with v = (s, 0, ...), and touches no other array.
 *
 * Tolerance: none, the values must be equal. The scalar paths are documented to do the full
 * kernels' operations in the full kernels' order (the grid pressure's results must not move
 * when it switches to them), so any difference at all is a fault. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <mpi.h>

#include "mpm_grid.h"
#include "mpm_kernels.h"

#define NP 1500

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.2, 2.0, 2.6}, g_dx = 0.1;

static double uniform(uint64_t *state) { /* splitmix64 */
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

static double *random_array(size_t n, double lo, double hi, uint64_t *seed) {
  double *a = malloc(sizeof(double) * n);
  for (size_t k = 0; k < n; ++k) a[k] = lo + (hi - lo) * uniform(seed);
  return a;
}

static mpm_grid *grid_make(int dim, mpm_shape_kind shape) {
  mpm_grid *g = NULL;
  const int nproc[3] = {1, 1, 1};
  int phase;
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_SELF, dim, g_lo, g_hi, g_dx, shape, nproc), 0);
  assert_int_equal(mpm_grid_add_phase(g, "scalar", &phase), 0);
  assert_int_equal(mpm_grid_add_phase(g, "full", &phase), 0);
  return g;
}

/* Positions 0.1 inside the domain: every stencil lies in the box. */
static void positions(int dim, uint64_t *seed, double **x) {
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d)
    x[d] = random_array(NP, g_lo[d] + 0.1, g_hi[d] - 0.1, seed);
}

/* Nodes where the arrays a (the lean deposit's) and b (the full one's) differ. */
static long differ(const double *a, const double *b, mpm_lidx nn) {
  long count = 0;
  for (mpm_lidx l = 0; l < nn; ++l) count += a[l] != b[l];
  return count;
}

/* (i) with the mass (with_m) on or off and the stress (with_s) off (0), isotropic (1) or full
 * (2, an asymmetric random tensor). */
static void check_deposit(int dim, mpm_shape_kind shape, int with_m, int with_s) {
  if (dim < 1 || dim > 3) fail_msg("dim %d", dim); /* bounds the loops over x[3] for gcc */
  mpm_grid *g = grid_make(dim, shape);
  uint64_t seed = 5u + (uint64_t)(100 * dim + 10 * shape + 2 * with_m + with_s);
  double *x[3] = {NULL};
  positions(dim, &seed, x);
  double *m = random_array(NP, 0.5, 2.0, &seed), *q = random_array(NP, -3.0, 3.0, &seed);
  double *zero = calloc(NP, sizeof(double)),
         *vsig = calloc((size_t)(dim * dim) * NP, sizeof(double));
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d)
    memcpy(vsig + (size_t)(d * dim + d) * NP, q, sizeof(double) * NP);
  for (size_t k = 0; with_s == 2 && k < (size_t)(dim * dim) * NP; ++k)
    vsig[k] = -2.0 + 4.0 * uniform(&seed);
  mpm_p2g_args s = {.n = NP,
                    .m = with_m ? m : NULL,
                    .viso = with_s == 1 ? q : NULL,
                    .vsig = with_s == 2 ? vsig : NULL,
                    .lp = 0.25};
  mpm_p2g_args f = {.n = NP, .m = with_m ? m : zero, .vsig = with_s ? vsig : NULL, .lp = 0.25};
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) s.x[d] = f.x[d] = x[d], f.v[d] = zero;
  mpm_grid_phase_zero(g, 0);
  mpm_grid_phase_zero(g, 1);
  const mpm_lidx nn = g->nnodes;
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) /* a momentum the lean deposit must not touch */
    for (mpm_lidx l = 0; l < nn; ++l) g->phase[0].mv_i[d][l] = 7.0;
  mpm_kernels_get(dim)->p2g(g, 0, &s);
  mpm_kernels_get(dim)->p2g(g, 1, &f);
  const mpm_grid_phase *a = &g->phase[0], *b = &g->phase[1];
  long dm = differ(a->m_i, b->m_i, nn), df = 0, dmv = 0;
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) {
    df += differ(a->f_i[d], b->f_i[d], nn);
    for (mpm_lidx l = 0; l < nn; ++l) dmv += a->mv_i[d][l] != 7.0;
  }
  long touched = 0; /* the deposit reached nodes (the comparison is not of zeros alone) */
  for (mpm_lidx l = 0; l < nn; ++l) touched += b->m_i[l] != 0.0 || b->f_i[0][l] != 0.0;
  static const char *const stress[3] = {"off", "isotropic", "full"};
  printf("  %d-D %-9s lean deposit (m %s, stress %s): %ld nodes reached; differing m_i %ld, "
         "f_i %ld, momentum touched %ld\n",
         dim, mpm_shape_name(shape), with_m ? "on" : "off", stress[with_s], touched, dm, df, dmv);
  assert_true(touched > 100);
  assert_int_equal(dm + df + dmv, 0);
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) free(x[d]);
  free(m), free(q), free(zero), free(vsig);
  mpm_grid_destroy(&g);
}

/* (iii) the two-scalar deposit (m and s): m_i and mv_i[0] of the full deposit with v = (s, 0,
 * ...), and nothing into mv_i[1..] or f_i. */
static void check_two_scalars(int dim, mpm_shape_kind shape) {
  if (dim < 1 || dim > 3) fail_msg("dim %d", dim); /* bounds the loops over x[3] for gcc */
  mpm_grid *g = grid_make(dim, shape);
  uint64_t seed = 17u + (uint64_t)(100 * dim + 10 * shape);
  double *x[3] = {NULL};
  positions(dim, &seed, x);
  double *m = random_array(NP, 0.5, 2.0, &seed), *q = random_array(NP, -3.0, 3.0, &seed);
  double *zero = calloc(NP, sizeof(double));
  mpm_p2g_args s = {.n = NP, .m = m, .s = q, .lp = 0.25};
  mpm_p2g_args f = {.n = NP, .m = m, .lp = 0.25};
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) s.x[d] = f.x[d] = x[d], f.v[d] = d ? zero : q;
  mpm_grid_phase_zero(g, 0);
  mpm_grid_phase_zero(g, 1);
  const mpm_lidx nn = g->nnodes;
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) /* arrays the deposit must not touch */
    for (mpm_lidx l = 0; l < nn; ++l) {
      g->phase[0].f_i[d][l] = 7.0;
      if (d) g->phase[0].mv_i[d][l] = 7.0;
    }
  mpm_kernels_get(dim)->p2g(g, 0, &s);
  mpm_kernels_get(dim)->p2g(g, 1, &f);
  const mpm_grid_phase *a = &g->phase[0], *b = &g->phase[1];
  long dm = differ(a->m_i, b->m_i, nn), ds = differ(a->mv_i[0], b->mv_i[0], nn), other = 0;
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d)
    for (mpm_lidx l = 0; l < nn; ++l) other += a->f_i[d][l] != 7.0 || (d && a->mv_i[d][l] != 7.0);
  long touched = 0;
  for (mpm_lidx l = 0; l < nn; ++l) touched += b->mv_i[0][l] != 0.0;
  printf("  %d-D %-9s two-scalar deposit: %ld nodes reached; differing m_i %ld, mv_i[0] %ld, "
         "other arrays touched %ld\n",
         dim, mpm_shape_name(shape), touched, dm, ds, other);
  assert_true(touched > 100);
  assert_int_equal(dm + ds + other, 0);
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) free(x[d]);
  free(m), free(q), free(zero);
  mpm_grid_destroy(&g);
}

/* (ii) with nscalar scalars, with and without div_out. */
static void check_gather(int dim, mpm_shape_kind shape, int nscalar, int with_div) {
  if (dim < 1 || dim > 3) fail_msg("dim %d", dim); /* bounds the loops over x[3] for gcc */
  mpm_grid *g = grid_make(dim, shape);
  uint64_t seed = 11u + (uint64_t)(100 * dim + 10 * shape + 2 * nscalar + with_div);
  const size_t nn = (size_t)g->nnodes;
  const mpm_grid_phase *ph = &g->phase[0];
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d)
    for (size_t l = 0; l < nn; ++l)
      ph->v_i[d][l] = -1.0 + 2.0 * uniform(&seed), ph->a_i[d][l] = uniform(&seed);
  double *x[3] = {NULL}, *s_i[3], *ref[3], *out[3], *v[3], *acc[3];
  positions(dim, &seed, x);
  for (int j = 0; j < 3; ++j) {
    s_i[j] = random_array(nn, -2.0, 2.0, &seed);
    ref[j] = malloc(sizeof(double) * NP), out[j] = malloc(sizeof(double) * NP);
  }
  double *L = malloc(sizeof(double) * (size_t)(dim * dim) * NP), *div = malloc(sizeof(double) * NP);
  mpm_g2p_args f = {.n = NP, .lp = 0.25, .L_out = L, .nscalar = nscalar};
  mpm_g2p_args s = {.n = NP, .lp = 0.25, .nscalar = nscalar, .div_out = with_div ? div : NULL};
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) {
    v[d] = malloc(sizeof(double) * NP), acc[d] = malloc(sizeof(double) * NP);
    f.x[d] = s.x[d] = x[d];
    f.v_i[d] = s.v_i[d] = ph->v_i[d], f.a_i[d] = s.a_i[d] = ph->a_i[d];
    f.v_out[d] = v[d], f.a_out[d] = acc[d];
  }
  for (int j = 0; j < nscalar; ++j)
    f.s_i[j] = s.s_i[j] = s_i[j], f.s_out[j] = ref[j], s.s_out[j] = out[j];
  mpm_kernels_get(dim)->g2p(g, &f);
  mpm_kernels_get(dim)->g2p(g, &s);
  long ds = 0, dd = 0;
  for (int j = 0; j < nscalar; ++j)
    for (int p = 0; p < NP; ++p) ds += out[j][p] != ref[j][p];
  for (int p = 0; with_div && p < NP; ++p) {
    double tr = L[p];
    for (int d = 1; d < dim; ++d) tr += L[(size_t)(d * dim + d) * NP + p];
    dd += div[p] != tr;
  }
  printf("  %d-D %-9s scalar gather (%d scalars, div %s): differing scalars %ld, div %ld\n", dim,
         mpm_shape_name(shape), nscalar, with_div ? "on" : "off", ds, dd);
  assert_int_equal(ds + dd, 0);
  for (int j = 0; j < 3; ++j) free(s_i[j]), free(ref[j]), free(out[j]);
  for (int d = 0; d < dim && d < MPM_MAX_DIM; ++d) free(x[d]), free(v[d]), free(acc[d]);
  free(L), free(div);
  mpm_grid_destroy(&g);
}

static void test_lean_deposit(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s)
      for (int with_m = 0; with_m <= 1; ++with_m)
        for (int with_s = 0; with_s <= 2; ++with_s)
          if (with_m || with_s) check_deposit(dim, (mpm_shape_kind)s, with_m, with_s);
}

static void test_two_scalar_deposit(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) check_two_scalars(dim, (mpm_shape_kind)s);
}

static void test_scalar_gather(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s)
      for (int ns = 0; ns <= 3; ++ns)
        for (int div = 0; div <= 1; ++div)
          if (ns > 0 || div) check_gather(dim, (mpm_shape_kind)s, ns, div);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_lean_deposit),
                                     cmocka_unit_test(test_two_scalar_deposit),
                                     cmocka_unit_test(test_scalar_gather)};
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
