/* The compiled serial vector operations (coupler/mpm_nvector.c) against SUNDIALS' own serial
 * operations, bit for bit: every special case of each operation (coefficients 1, -1, equal,
 * opposite, general; output aliasing an input; one to seven vectors in the fused
 * combinations), on vectors of odd length and on empty ones; and the one-pass error weights
 * against ARKODE's four-operation sequence. Exact equality is the point: the state of a run
 * must not depend on which implementation did the vector work. */
#include "mpm_random.h"
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <float.h>
#include <math.h>
#include <mpi.h>

#include "mpm_nvector.h"

#include <nvector/nvector_mpimanyvector.h>
#include "mpm_sundials.h"

#define N    1001
#define NVEC 7

static SUNContext g_ctx;

/* A pair of vectors with the same contents: ref uses SUNDIALS' operations, fast ours. */
typedef struct {
  N_Vector ref, fast;
} pair;

static double uniform(uint64_t *state) {
  return mpm_test_uniform(state);
}

static pair pair_new(sunindextype n, uint64_t seed) {
  pair p = {N_VNew_Serial(n, g_ctx), N_VNew_Serial(n, g_ctx)};
  assert_non_null(p.ref);
  assert_non_null(p.fast);
  assert_int_equal(N_VEnableFusedOps_Serial(p.ref, SUNTRUE), 0);
  mpm_nvector_fast_ops(p.fast);
  for (sunindextype i = 0; i < n; ++i)
    NV_Ith_S(p.ref, i) = NV_Ith_S(p.fast, i) = 4.0 * uniform(&seed) - 2.0;
  return p;
}

static void pair_free(pair *p) {
  N_VDestroy(p->ref);
  N_VDestroy(p->fast);
}

static void assert_same(const pair *p) {
  const sunindextype n = NV_LENGTH_S(p->ref);
  if (n > 0) assert_memory_equal(NV_DATA_S(p->ref), NV_DATA_S(p->fast), sizeof(double) * n);
}

static void assert_same_real(mpm_sunreal a, mpm_sunreal b) {
  assert_memory_equal(&a, &b, sizeof a);
}

/* Coefficient pairs that reach every branch of the linear sum. */
static const double g_ab[][2] = {{1, 1},      {1, -1},    {-1, 1},   {1, 0.3},
                                 {0.3, 1},    {-1, 0.3},  {0.3, -1}, {0.7, 0.7},
                                 {0.7, -0.7}, {0.3, 0.9}, {-1, -1},  {0, 0.5}};

static void test_linear_sum(void **state) {
  (void)state;
  for (size_t k = 0; k < sizeof g_ab / sizeof g_ab[0]; ++k)
    for (int alias = 0; alias < 3; ++alias) { /* z distinct, z = x, z = y */
      pair x = pair_new(N, 1), y = pair_new(N, 2), z = pair_new(N, 3);
      pair *out = alias == 1 ? &x : alias == 2 ? &y : &z;
      N_VLinearSum(g_ab[k][0], x.ref, g_ab[k][1], y.ref, out->ref);
      N_VLinearSum(g_ab[k][0], x.fast, g_ab[k][1], y.fast, out->fast);
      assert_same(out);
      pair_free(&x), pair_free(&y), pair_free(&z);
    }
}

static void test_elementwise(void **state) {
  (void)state;
  const double cs[] = {1.0, -1.0, 0.37};
  for (int k = 0; k < 3; ++k)
    for (int alias = 0; alias < 2; ++alias) {
      pair x = pair_new(N, 4), z = pair_new(N, 5);
      pair *out = alias ? &x : &z;
      N_VScale(cs[k], x.ref, out->ref);
      N_VScale(cs[k], x.fast, out->fast);
      assert_same(out);
      pair_free(&x), pair_free(&z);
    }
  pair x = pair_new(N, 6), y = pair_new(N, 7), z = pair_new(N, 8);
  N_VConst(0.25, z.ref), N_VConst(0.25, z.fast), assert_same(&z);
  N_VProd(x.ref, y.ref, z.ref), N_VProd(x.fast, y.fast, z.fast), assert_same(&z);
  N_VDiv(x.ref, y.ref, z.ref), N_VDiv(x.fast, y.fast, z.fast), assert_same(&z);
  N_VAbs(x.ref, z.ref), N_VAbs(x.fast, z.fast), assert_same(&z);
  N_VInv(x.ref, z.ref), N_VInv(x.fast, z.fast), assert_same(&z);
  N_VAddConst(x.ref, 0.3, z.ref), N_VAddConst(x.fast, 0.3, z.fast), assert_same(&z);
  pair_free(&x), pair_free(&y), pair_free(&z);
}

/* SUNDIALS' minimum reads the first element even of an empty vector; ours gives the
 * largest double there, and the other reductions give zero like SUNDIALS'. */
static void test_reductions(void **state) {
  (void)state;
  pair x = pair_new(N, 9), w = pair_new(N, 10);
  assert_same_real(N_VWSqrSumLocal(x.ref, w.ref), N_VWSqrSumLocal(x.fast, w.fast));
  assert_same_real(N_VMinLocal(x.ref), N_VMinLocal(x.fast));
  assert_same_real(N_VMaxNormLocal(x.ref), N_VMaxNormLocal(x.fast));
  pair_free(&x), pair_free(&w);
  pair e = pair_new(0, 11), f = pair_new(0, 12);
  assert_same_real(N_VWSqrSumLocal(e.ref, f.ref), N_VWSqrSumLocal(e.fast, f.fast));
  assert_same_real(N_VMaxNormLocal(e.ref), N_VMaxNormLocal(e.fast));
  assert_true(N_VMinLocal(e.fast) == DBL_MAX);
  pair_free(&e), pair_free(&f);
}

/* z = sum c_k X_k for 1..NVEC vectors: into a separate z, into X_0 with c_0 = 1 and with
 * c_0 != 1. */
static void test_linear_combination(void **state) {
  (void)state;
  double c[NVEC] = {0.3, 1.0, -0.7, 0.25, -1.0, 2.5, 0.125};
  for (int nvec = 1; nvec <= NVEC; ++nvec)
    for (int mode = 0; mode < 3; ++mode) {
      pair X[NVEC], z = pair_new(N, 99);
      N_Vector xr[NVEC], xf[NVEC];
      for (int k = 0; k < nvec; ++k) {
        X[k] = pair_new(N, 20 + (uint64_t)k);
        xr[k] = X[k].ref, xf[k] = X[k].fast;
      }
      c[0] = mode == 1 ? 1.0 : 0.3;
      pair *out = mode == 0 ? &z : &X[0];
      assert_int_equal(N_VLinearCombination(nvec, c, xr, out->ref), 0);
      assert_int_equal(N_VLinearCombination(nvec, c, xf, out->fast), 0);
      assert_same(out);
      for (int k = 0; k < nvec; ++k) pair_free(&X[k]);
      pair_free(&z);
    }
}

/* Z_k = a_k x + Y_k, in place and not. */
static void test_scale_add_multi(void **state) {
  (void)state;
  double a[3] = {0.3, 1.0, -1.0};
  for (int nvec = 1; nvec <= 3; ++nvec)
    for (int inplace = 0; inplace < 2; ++inplace) {
      pair x = pair_new(N, 30), Y[3], Z[3];
      N_Vector yr[3], yf[3], zr[3], zf[3];
      for (int k = 0; k < nvec; ++k) {
        Y[k] = pair_new(N, 31 + (uint64_t)k), Z[k] = pair_new(N, 41 + (uint64_t)k);
        yr[k] = Y[k].ref, yf[k] = Y[k].fast;
        zr[k] = inplace ? yr[k] : Z[k].ref, zf[k] = inplace ? yf[k] : Z[k].fast;
      }
      assert_int_equal(N_VScaleAddMulti(nvec, a, x.ref, yr, zr), 0);
      assert_int_equal(N_VScaleAddMulti(nvec, a, x.fast, yf, zf), 0);
      for (int k = 0; k < nvec; ++k) {
        assert_same(inplace ? &Y[k] : &Z[k]);
        pair_free(&Y[k]), pair_free(&Z[k]);
      }
      pair_free(&x);
    }
}

/* 1 / (rtol |y| + atol) in one pass against ARKODE's arkEwtSetSS sequence of SUNDIALS
 * operations (abs, scale, add constant, inverse), on a two-block MPIManyVector. */
static void test_weights(void **state) {
  (void)state;
  const double rtol = 1e-6, atol = 1e-9;
  pair y[2] = {pair_new(N, 50), pair_new(7, 51)}, w[2] = {pair_new(N, 52), pair_new(7, 53)};
  N_Vector ys[2] = {y[0].ref, y[1].ref}, ws[2] = {w[0].fast, w[1].fast};
  N_Vector ym = N_VMake_MPIManyVector(MPI_COMM_SELF, 2, ys, g_ctx);
  N_Vector wm = N_VMake_MPIManyVector(MPI_COMM_SELF, 2, ws, g_ctx);
  mpm_nvector_weights(ym, wm, rtol, atol);
  for (int k = 0; k < 2; ++k) {
    N_Vector t = N_VClone(y[k].ref);
    N_VAbs(y[k].ref, t);
    N_VScale(rtol, t, t);
    N_VAddConst(t, atol, t);
    N_VInv(t, w[k].ref);
    assert_same(&w[k]);
    N_VDestroy(t);
  }
  N_VDestroy(ym), N_VDestroy(wm);
  for (int k = 0; k < 2; ++k) pair_free(&y[k]), pair_free(&w[k]);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm comm = MPI_COMM_SELF;
  if (mpm_sun_context_create(&comm, &g_ctx) != 0) return 1;
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_linear_sum),      cmocka_unit_test(test_elementwise),
      cmocka_unit_test(test_reductions),      cmocka_unit_test(test_linear_combination),
      cmocka_unit_test(test_scale_add_multi), cmocka_unit_test(test_weights),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  SUNContext_Free(&g_ctx);
  MPI_Finalize();
  return rc;
}
