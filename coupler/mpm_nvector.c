/* Compiled serial vector operations (see mpm_nvector.h). The special cases follow
 * nvector_serial.c of SUNDIALS 6.4 one for one; test_nvector checks every one of them
 * against the library's own operations, bit for bit. */
#include "mpm_nvector.h"

#include "mpm_sundials.h"

#include <float.h>
#include <nvector/nvector_mpimanyvector.h>
#include <math.h>
#include <string.h>

typedef sunindextype idx_t;

#define LEN(v)  NV_LENGTH_S(v)
#define DATA(v) NV_DATA_S(v)

static void v_const(mpm_sunreal c, N_Vector z) {
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(z); ++i) zd[i] = c;
}

static void v_scale(mpm_sunreal c, N_Vector x, N_Vector z) {
  const double *xd = DATA(x);
  double *zd = DATA(z);
  const idx_t n = LEN(x);
  if (z == x) {
    for (idx_t i = 0; i < n; ++i) zd[i] *= c;
  } else if (c == 1.0) {
    if (n > 0) memcpy(zd, xd, sizeof(double) * (size_t)n);
  } else if (c == -1.0) {
    for (idx_t i = 0; i < n; ++i) zd[i] = -xd[i];
  } else {
    for (idx_t i = 0; i < n; ++i) zd[i] = c * xd[i];
  }
}

/* y += a x, the in-place form of a linear sum. */
static void axpy(double a, const double *xd, double *yd, idx_t n) {
  if (a == 1.0)
    for (idx_t i = 0; i < n; ++i) yd[i] += xd[i];
  else if (a == -1.0)
    for (idx_t i = 0; i < n; ++i) yd[i] -= xd[i];
  else
    for (idx_t i = 0; i < n; ++i) yd[i] += a * xd[i];
}

/* z = a x + b y, with SUNDIALS' choice of formula for each case. */
static void v_linear_sum(mpm_sunreal a, N_Vector x, mpm_sunreal b, N_Vector y, N_Vector z) {
  const idx_t n = LEN(x);
  const double *xd = DATA(x), *yd = DATA(y);
  double *zd = DATA(z);
  if (b == 1.0 && z == y) {
    axpy(a, xd, zd, n);
    return;
  }
  if (a == 1.0 && z == x) {
    axpy(b, yd, zd, n);
    return;
  }
  if (a == 1.0 && b == 1.0) {
    for (idx_t i = 0; i < n; ++i) zd[i] = xd[i] + yd[i];
    return;
  }
  int test;
  if ((test = (a == 1.0 && b == -1.0)) || (a == -1.0 && b == 1.0)) {
    const double *v1 = test ? yd : xd, *v2 = test ? xd : yd; /* z = v2 - v1 */
    for (idx_t i = 0; i < n; ++i) zd[i] = v2[i] - v1[i];
    return;
  }
  if ((test = (a == 1.0)) || b == 1.0) {
    const double c = test ? b : a, *v1 = test ? yd : xd, *v2 = test ? xd : yd; /* c v1 + v2 */
    for (idx_t i = 0; i < n; ++i) zd[i] = c * v1[i] + v2[i];
    return;
  }
  if ((test = (a == -1.0)) || b == -1.0) {
    const double c = test ? b : a, *v1 = test ? yd : xd, *v2 = test ? xd : yd; /* c v1 - v2 */
    for (idx_t i = 0; i < n; ++i) zd[i] = c * v1[i] - v2[i];
    return;
  }
  if (a == b) {
    for (idx_t i = 0; i < n; ++i) zd[i] = a * (xd[i] + yd[i]);
    return;
  }
  if (a == -b) {
    for (idx_t i = 0; i < n; ++i) zd[i] = a * (xd[i] - yd[i]);
    return;
  }
  for (idx_t i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
}

static void v_prod(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = DATA(x), *yd = DATA(y);
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(x); ++i) zd[i] = xd[i] * yd[i];
}

static void v_div(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = DATA(x), *yd = DATA(y);
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(x); ++i) zd[i] = xd[i] / yd[i];
}

static void v_abs(N_Vector x, N_Vector z) {
  const double *xd = DATA(x);
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(x); ++i) zd[i] = fabs(xd[i]);
}

static void v_inv(N_Vector x, N_Vector z) {
  const double *xd = DATA(x);
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(x); ++i) zd[i] = 1.0 / xd[i];
}

static void v_add_const(N_Vector x, mpm_sunreal b, N_Vector z) {
  const double *xd = DATA(x);
  double *zd = DATA(z);
  for (idx_t i = 0; i < LEN(x); ++i) zd[i] = xd[i] + b;
}

/* A sequential sum, in index order like SUNDIALS' (so the rounding is the same). */
static mpm_sunreal v_wsqrsum_local(N_Vector x, N_Vector w) {
  const double *xd = DATA(x), *wd = DATA(w);
  double sum = 0.0;
  for (idx_t i = 0; i < LEN(x); ++i) {
    const double p = xd[i] * wd[i];
    sum += p * p;
  }
  return sum;
}

/* Starts from the first element like SUNDIALS (a NaN there is returned); an empty vector,
 * which SUNDIALS would read past, gives the largest double. */
static mpm_sunreal v_min_local(N_Vector x) {
  const double *xd = DATA(x);
  if (LEN(x) < 1) return DBL_MAX;
  double m = xd[0];
  for (idx_t i = 1; i < LEN(x); ++i)
    if (xd[i] < m) m = xd[i];
  return m;
}

static mpm_sunreal v_max_norm_local(N_Vector x) {
  const double *xd = DATA(x);
  double m = 0.0;
  for (idx_t i = 0; i < LEN(x); ++i)
    if (fabs(xd[i]) > m) m = fabs(xd[i]);
  return m;
}

/* z = sum_k c_k X_k in one pass; each element adds its terms in the order k = 0, 1, ...,
 * like SUNDIALS' vector-at-a-time loops. Terms are taken in blocks of four vectors. */
static int v_linear_combination(int nvec, mpm_sunreal *c, N_Vector *X, N_Vector z) {
  if (nvec < 1) return -1;
  if (nvec == 1) {
    v_scale(c[0], X[0], z);
    return 0;
  }
  if (nvec == 2) {
    v_linear_sum(c[0], X[0], c[1], X[1], z);
    return 0;
  }
  const idx_t n = LEN(z);
  double *zd = DATA(z);
  int k = 1;
  if (X[0] == z) {
    if (c[0] != 1.0)
      for (idx_t i = 0; i < n; ++i) zd[i] *= c[0];
  } else {
    /* First block writes z: c0 x0 + c1 x1 (+ c2 x2), then later blocks accumulate. */
    const double *x0 = DATA(X[0]), *x1 = DATA(X[1]);
    if (nvec >= 3) {
      const double *x2 = DATA(X[2]);
      for (idx_t i = 0; i < n; ++i) zd[i] = c[0] * x0[i] + c[1] * x1[i] + c[2] * x2[i];
      k = 3;
    }
  }
  for (; k + 3 < nvec; k += 4) {
    const double *a = DATA(X[k]), *b = DATA(X[k + 1]), *e = DATA(X[k + 2]), *f = DATA(X[k + 3]);
    for (idx_t i = 0; i < n; ++i)
      zd[i] = zd[i] + c[k] * a[i] + c[k + 1] * b[i] + c[k + 2] * e[i] + c[k + 3] * f[i];
  }
  for (; k < nvec; ++k) {
    const double *a = DATA(X[k]);
    for (idx_t i = 0; i < n; ++i) zd[i] += c[k] * a[i];
  }
  return 0;
}

/* Z_k = a_k x + Y_k (in place when Y = Z). */
static int v_scale_add_multi(int nvec, mpm_sunreal *a, N_Vector x, N_Vector *Y, N_Vector *Z) {
  if (nvec < 1) return -1;
  if (nvec == 1) {
    v_linear_sum(a[0], x, 1.0, Y[0], Z[0]);
    return 0;
  }
  const idx_t n = LEN(x);
  const double *xd = DATA(x);
  for (int k = 0; k < nvec; ++k) {
    const double *yd = DATA(Y[k]);
    double *zd = DATA(Z[k]);
    if (Y == Z)
      for (idx_t i = 0; i < n; ++i) zd[i] += a[k] * xd[i];
    else
      for (idx_t i = 0; i < n; ++i) zd[i] = a[k] * xd[i] + yd[i];
  }
  return 0;
}

void mpm_nvector_fast_ops(N_Vector v) {
  struct _generic_N_Vector_Ops *ops = v->ops;
  ops->nvconst = v_const;
  ops->nvscale = v_scale;
  ops->nvlinearsum = v_linear_sum;
  ops->nvprod = v_prod;
  ops->nvdiv = v_div;
  ops->nvabs = v_abs;
  ops->nvinv = v_inv;
  ops->nvaddconst = v_add_const;
  ops->nvwsqrsumlocal = v_wsqrsum_local;
  ops->nvminlocal = v_min_local;
  ops->nvmaxnormlocal = v_max_norm_local;
  ops->nvlinearcombination = v_linear_combination;
  ops->nvscaleaddmulti = v_scale_add_multi;
}

void mpm_nvector_weights(N_Vector y, N_Vector w, double rtol, double atol) {
  for (sunindextype k = 0; k < N_VGetNumSubvectors_MPIManyVector(y); ++k) {
    N_Vector ys = N_VGetSubvector_MPIManyVector(y, k), ws = N_VGetSubvector_MPIManyVector(w, k);
    const double *yd = DATA(ys);
    double *wd = DATA(ws);
    for (idx_t i = 0; i < LEN(ys); ++i) wd[i] = 1.0 / (fabs(yd[i]) * rtol + atol);
  }
}
