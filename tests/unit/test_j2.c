/* J2 plasticity (solid_j2.c), checked against independent computations:
 *  - the symmetric 3 x 3 eigen solver on random, repeated-eigenvalue and badly scaled
 *    matrices (reconstruction and orthogonality to 1e-13);
 *  - the elastic range against the Hencky response built from a known polar decomposition
 *    F = R U, U = P diag(l) P^T (so ln V = (RP) diag(ln l) (RP)^T needs no eigen solver);
 *  - uniaxial stress under monotonic stretch F = diag(1+e, s, s), s solved so that the
 *    lateral stress vanishes. With eps = ln(1+e) the Kirchhoff stress tau11 = J sigma11 is
 *    the bilinear curve
 *        tau11 = E eps                                  while E eps <= sigma_y,
 *        tau11 = sigma_y + H eps_p
 *              = sigma_y + E H / (E + H) (eps - sigma_y / E)  beyond,
 *    with eps_p = alpha = eps - tau11 / E and ln s = -nu tau11 / E - alpha / 2 (elastic
 *    Poisson contraction plus plastic incompressibility). The radial return is exact for
 *    fixed principal directions, so the tolerance (1e-9 sigma_y) only covers the lateral
 *    solve and round-off;
 *  - unloading and reverse loading against the 1-D return map in log strain (elastic
 *    unloading with alpha frozen, re-yield at -(sigma_y + H alpha));
 *  - random large-deformation paths in a strided, permuted batch: returned stress never
 *    outside the yield surface and on it after plastic flow, det Cp^{-1} = 1 to 1e-12,
 *    stress() leaving the history bit for bit, particles outside the batch untouched, and
 *    2-D plane strain equal to 3-D with F33 = 1 (the out-of-plane history evolving);
 *  - objectivity of the returned stress and of the committed history. */
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

#include "mpm_config.h"
#include "mpm_error.h"
#include "solid_material.h"
#include "solid_module.h"

/* The model's own static helpers (the eigen solver) are tested directly: compile a private
 * copy of the model under another ops name; the registry still gives the library's copy. */
#define solid_j2_ops test_j2_private_ops
#include "solid_j2.c"
#undef solid_j2_ops

#define E_  2e11
#define NU_ 0.3
#define SY_ 2.5e8
#define H_  1e9
#define NH  7 /* history components */
#define PI  3.14159265358979323846

/* ------------------------------------------------------------------ helpers --- */

static uint64_t g_rng = 0x9E3779B97F4A7C15ull;

/* Uniform in [-1, 1] (xorshift64*). */
static double rnd(void) {
  g_rng ^= g_rng >> 12, g_rng ^= g_rng << 25, g_rng ^= g_rng >> 27;
  return (double)((g_rng * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

static void matmul(const double A[3][3], const double B[3][3], double C[3][3]) {
  double T[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) T[r][c] = A[r][0] * B[0][c] + A[r][1] * B[1][c] + A[r][2] * B[2][c];
  memcpy(C, T, sizeof T);
}

/* C = A B A^T */
static void congruence(const double A[3][3], const double B[3][3], double C[3][3]) {
  double AB[3][3];
  matmul(A, B, AB);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[r][c] = AB[r][0] * A[c][0] + AB[r][1] * A[c][1] + AB[r][2] * A[c][2];
}

static double det3(const double A[3][3]) {
  return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
         A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
         A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
}

static double maxabs(const double A[3][3]) {
  double m = 0.0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m = fmax(m, fabs(A[r][c]));
  return m;
}

static void identity(double A[3][3]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) A[r][c] = (r == c);
}

/* A random rotation (a unit quaternion); in-plane about z if planar. */
static void rotation(double R[3][3], int planar) {
  double q[4] = {rnd(), planar ? 0.0 : rnd(), planar ? 0.0 : rnd(), rnd()}, n = 0.0;
  for (int k = 0; k < 4; ++k) n += q[k] * q[k];
  n = sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  const double M[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  memcpy(R, M, sizeof M);
}

/* von Mises q = sqrt(3/2) |dev tau| */
static double mises(const double t[3][3]) {
  const double p = (t[0][0] + t[1][1] + t[2][2]) / 3.0;
  double s2 = 0.0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const double s = t[r][c] - (r == c ? p : 0.0);
      s2 += s * s;
    }
  return sqrt(1.5 * s2);
}

static solid_material *make(int dim, double sigma_y, double H) {
  char text[256];
  snprintf(text, sizeof text,
           "[solid.t]\nmaterial = j2\ndensity = 1000\nE = %.17g\nnu = %.17g\nsigma_y = %.17g\n"
           "hardening = %.17g\n",
           E_, NU_, sigma_y, H);
  mpm_config *cfg = NULL;
  solid_material *mat = NULL;
  assert_int_equal(mpm_config_new(&cfg, MPI_COMM_WORLD), 0);
  assert_int_equal(solid_add_schema(cfg), 0);
  assert_int_equal(mpm_config_read_string(cfg, text, "test_j2", "."), 0);
  assert_int_equal(solid_material_create(&mat, "j2", cfg, "solid.t", dim), 0);
  mpm_config_destroy(&cfg);
  assert_non_null(mat);
  return mat;
}

static void init_hist(const solid_material *mat, double *hist) {
  mpm_lidx idx = 0;
  const solid_batch b = {.dim = mat->dim, .n = 1, .count = 1, .idx = &idx, .hist = hist};
  mat->ops->init_history(mat, &b);
}

/* One particle with V0 = 1: the dim x dim block of tau (out = V sigma = V0 tau). */
static void point_stress(const solid_material *mat, const double F[3][3], double *hist,
                         double tau[3][3]) {
  const int dim = mat->dim;
  double Fa[9], out[9], V0 = 1.0;
  mpm_lidx idx = 0;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) Fa[r * dim + c] = F[r][c];
  const solid_batch b = {
      .dim = dim, .n = 1, .count = 1, .idx = &idx, .F = Fa, .V0 = &V0, .hist = hist, .out = out};
  mat->ops->stress(mat, &b);
  memset(tau, 0, 9 * sizeof(double));
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) tau[r][c] = out[r * dim + c];
}

static void point_commit(const solid_material *mat, const double F[3][3], double *hist) {
  const int dim = mat->dim;
  double Fa[9], V0 = 1.0;
  mpm_lidx idx = 0;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) Fa[r * dim + c] = F[r][c];
  const solid_batch b = {
      .dim = dim, .n = 1, .count = 1, .idx = &idx, .F = Fa, .V0 = &V0, .hist = hist};
  mat->ops->commit(mat, &b);
}

static double point_energy(const solid_material *mat, const double F[3][3], double *hist) {
  const int dim = mat->dim;
  double Fa[9], V0 = 1.0;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) Fa[r * dim + c] = F[r][c];
  const solid_batch b = {.dim = dim, .n = 1, .count = 0, .F = Fa, .V0 = &V0, .hist = hist};
  return mat->ops->energy_density(mat, &b, 0);
}

static void hist_matrix(const double *hist, mpm_lidx n, mpm_lidx i, double C[3][3]) {
  static const int rc[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};
  for (int k = 0; k < 6; ++k)
    C[rc[k][0]][rc[k][1]] = C[rc[k][1]][rc[k][0]] = hist[(size_t)k * n + i];
}

/* --------------------------------------------------------------------- tests --- */

static void check_eigen(const double A[3][3], double *rec, double *orth) {
  double lam[3], Q[3][3], B[3][3], QtQ[3][3];
  j2_eigen(A, lam, Q);
  j2_spectral(Q, lam, B);
  double d = 0.0, o = 0.0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      d = fmax(d, fabs(B[r][c] - A[r][c]));
      QtQ[r][c] = Q[0][r] * Q[0][c] + Q[1][r] * Q[1][c] + Q[2][r] * Q[2][c];
      o = fmax(o, fabs(QtQ[r][c] - (r == c)));
    }
  const double scale = maxabs(A) > 0 ? maxabs(A) : 1.0;
  *rec = fmax(*rec, d / scale);
  *orth = fmax(*orth, o);
}

static void test_eigen(void **state) {
  (void)state;
  double rec = 0.0, orth = 0.0;
  for (int t = 0; t < 20000; ++t) {
    double A[3][3], R[3][3], l[3];
    const int kind = t % 5;
    if (kind == 0) { /* random entries */
      for (int r = 0; r < 3; ++r)
        for (int c = r; c < 3; ++c) A[r][c] = A[c][r] = rnd();
    } else {
      /* known spectrum: distinct, double, triple, or spread over 16 decades */
      for (int k = 0; k < 3; ++k) l[k] = rnd();
      if (kind == 2) l[1] = l[0];
      if (kind == 3) l[1] = l[2] = l[0];
      if (kind == 4)
        for (int k = 0; k < 3; ++k) l[k] = pow(10.0, 8.0 * rnd());
      if (kind == 2 && t % 2) l[2] = l[0] * (1 + 1e-14); /* nearly triple */
      rotation(R, 0);
      double D[3][3] = {{l[0], 0, 0}, {0, l[1], 0}, {0, 0, l[2]}};
      congruence(R, D, A);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < r; ++c) A[r][c] = A[c][r];
    }
    check_eigen(A, &rec, &orth);
  }
  const double Z[3][3] = {{0}}, D[3][3] = {{3, 0, 0}, {0, -1, 0}, {0, 0, 2}};
  check_eigen(Z, &rec, &orth);
  check_eigen(D, &rec, &orth);
  print_message("eigen: 20002 matrices, max |A - Q L Q^T| / |A| = %.2e, max |Q^T Q - I| = %.2e\n",
                rec, orth);
  assert_true(rec <= 1e-13);
  assert_true(orth <= 1e-13);
}

/* tau of the Hencky model for F = R P diag(l) P^T (dim 2: in-plane R, P; l[2] = 1). */
static void hencky(const double R[3][3], const double P[3][3], const double l[3], double tau[3][3],
                   double *W) {
  const double mu = E_ / (2 * (1 + NU_)), K = E_ / (3 * (1 - 2 * NU_));
  double e[3], RP[3][3], D[3][3] = {{0}};
  for (int k = 0; k < 3; ++k) e[k] = log(l[k]);
  const double tr = e[0] + e[1] + e[2];
  *W = 0.5 * K * tr * tr;
  for (int k = 0; k < 3; ++k) {
    D[k][k] = K * tr + 2 * mu * (e[k] - tr / 3);
    *W += mu * (e[k] - tr / 3) * (e[k] - tr / 3);
  }
  matmul(R, P, RP);
  congruence(RP, D, tau);
}

static void elastic_range(int dim, double sigma_y, double amp, double *err, double *werr) {
  solid_material *mat = make(dim, sigma_y, H_);
  for (int t = 0; t < 500; ++t) {
    double R[3][3], P[3][3], U[3][3], F[3][3], l[3], D[3][3] = {{0}};
    double tau[3][3], ref[3][3], hist[NH], hist0[NH], W;
    rotation(R, dim == 2);
    rotation(P, dim == 2);
    for (int k = 0; k < 3; ++k) l[k] = k < dim ? 1.0 + amp * rnd() : 1.0, D[k][k] = l[k];
    congruence(P, D, U);
    matmul(R, U, F);
    hencky(R, P, l, ref, &W);
    init_hist(mat, hist);
    memcpy(hist0, hist, sizeof hist);
    point_stress(mat, F, hist, tau);
    double d = 0.0;
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) d = fmax(d, fabs(tau[r][c] - ref[r][c]));
    /* relative to the yield scales: ln of the eigenvalues of b_e = 1 + O(strain) has an
     * absolute round-off of ~1e-16, a floor of ~E 1e-16 on the stress */
    const double scale = fmax(maxabs(ref), SY_), wscale = fmax(W, SY_ * SY_ / E_);
    *err = fmax(*err, d / scale);
    *werr = fmax(*werr, fabs(point_energy(mat, F, hist) - W) / wscale);
    /* elastic: commit leaves Cp^{-1} = I and alpha = 0 */
    point_commit(mat, F, hist);
    for (int k = 0; k < NH; ++k) assert_true(fabs(hist[k] - hist0[k]) <= 1e-12);
  }
  solid_material_destroy(&mat);
}

static void test_elastic_hencky(void **state) {
  (void)state;
  double err[2] = {0}, werr[2] = {0};
  for (int dim = 2; dim <= 3; ++dim) {
    /* small strains below the yield strain (1.25e-3), and finite elastic strains with a
     * yield stress out of reach */
    elastic_range(dim, SY_, 3e-4, &err[0], &werr[0]);
    elastic_range(dim, 1e30, 0.35, &err[1], &werr[1]);
  }
  print_message("elastic vs Hencky: small strain stress %.2e energy %.2e; finite strain stress "
                "%.2e energy %.2e (relative to max(value, yield scale))\n",
                err[0], werr[0], err[1], werr[1]);
  assert_true(err[0] <= 1e-11 && werr[0] <= 1e-11); /* ~1e-14 in strain */
  assert_true(err[1] <= 1e-12 && werr[1] <= 1e-12);
}

/* The lateral stretch s giving tau22 = tau33 = 0 under F = diag(1+e, s, s) (secant). */
static double lateral(const solid_material *mat, double e, double s, double *hist,
                      double tau[3][3]) {
  double F[3][3] = {{1 + e, 0, 0}, {0, s, 0}, {0, 0, s}};
  point_stress(mat, F, hist, tau);
  double s0 = s, g0 = tau[1][1], s1 = s * (1 - 1e-5);
  for (int it = 0; it < 100; ++it) {
    F[1][1] = F[2][2] = s1;
    point_stress(mat, F, hist, tau);
    const double g1 = tau[1][1];
    if (fabs(g1) <= 1e-11 * SY_ || g1 == g0) return s1;
    const double s2 = s1 - g1 * (s1 - s0) / (g1 - g0);
    s0 = s1, g0 = g1, s1 = s2;
  }
  fail_msg("lateral stretch did not converge at e = %g", e);
  return s1;
}

static void uniaxial(double H, double *terr, double *serr, double *aerr, double *lerr,
                     double *cerr) {
  solid_material *mat = make(3, SY_, H);
  const double Et = E_ * H / (E_ + H);
  double hist[NH], s = 1.0, tau[3][3], C[3][3];
  init_hist(mat, hist);
  for (int k = 1; k <= 200; ++k) {
    const double e = 2.5e-4 * k, eps = log1p(e); /* to 5% in 200 increments */
    s = lateral(mat, e, s, hist, tau);
    const double ref = E_ * eps <= SY_ ? E_ * eps : SY_ + Et * (eps - SY_ / E_);
    const double ep = eps - ref / E_, J = (1 + e) * s * s;
    *terr = fmax(*terr, fabs(tau[0][0] - ref) / SY_);
    /* Cauchy sigma11 = tau11 / J with J = exp((1 - 2 nu) tau11 / E) */
    *cerr = fmax(*cerr, fabs(tau[0][0] / J - ref / exp((1 - 2 * NU_) * ref / E_)) / SY_);
    *serr = fmax(*serr, fabs(tau[2][2]) / SY_); /* tau33 = tau22 by symmetry */
    const double F[3][3] = {{1 + e, 0, 0}, {0, s, 0}, {0, 0, s}};
    point_commit(mat, F, hist);
    *aerr = fmax(*aerr, fabs(hist[6] - ep));
    *lerr = fmax(*lerr, fabs(log(s) - (-NU_ * ref / E_ - 0.5 * ep)));
    hist_matrix(hist, 1, 0, C);
    assert_true(fabs(det3(C) - 1.0) <= 1e-12);
  }
  solid_material_destroy(&mat);
}

static void test_uniaxial(void **state) {
  (void)state;
  double terr = 0, serr = 0, aerr = 0, lerr = 0, cerr = 0;
  uniaxial(H_, &terr, &serr, &aerr, &lerr, &cerr);
  uniaxial(0.0, &terr, &serr, &aerr, &lerr, &cerr);
  uniaxial(2e10, &terr, &serr, &aerr, &lerr, &cerr);
  print_message("uniaxial (H = 1e9, 0, 2e10; 200 increments to 5%%): |tau11 - bilinear| / sy = "
                "%.2e, Cauchy %.2e, lateral tau / sy %.2e, |alpha - eps_p| = %.2e, |ln s - ref| "
                "= %.2e\n",
                terr, cerr, serr, aerr, lerr);
  assert_true(terr <= 1e-9 && cerr <= 1e-9 && serr <= 1e-10);
  assert_true(aerr <= 1e-12 && lerr <= 1e-12);
}

/* Load to 3%, unload through zero to -3% and reload to 3%, against the 1-D return map in
 * log strain: tau_tr = E (eps - eps_p), f = |tau_tr| - (sy + H alpha),
 * dgamma = f / (E + H). */
static void test_unloading(void **state) {
  (void)state;
  solid_material *mat = make(3, SY_, H_);
  double hist[NH], s = 1.0, tau[3][3], ep = 0.0, al = 0.0, terr = 0.0, aerr = 0.0;
  int nel = 0;
  init_hist(mat, hist);
  const double path[3][2] = {{0.0, 0.03}, {0.03, -0.03}, {-0.03, 0.03}};
  for (int leg = 0; leg < 3; ++leg)
    for (int k = 1; k <= 300; ++k) {
      const double e = path[leg][0] + (path[leg][1] - path[leg][0]) * k / 300.0;
      const double eps = log1p(e);
      const double ttr = E_ * (eps - ep), f = fabs(ttr) - (SY_ + H_ * al);
      double ref = ttr;
      if (f > 0) {
        const double dg = f / (E_ + H_), sg = ttr > 0 ? 1.0 : -1.0;
        ep += sg * dg, al += dg, ref = ttr - sg * E_ * dg;
      }
      const double alpha_before = hist[6];
      s = lateral(mat, e, s, hist, tau);
      const double F[3][3] = {{1 + e, 0, 0}, {0, s, 0}, {0, 0, s}};
      point_commit(mat, F, hist);
      terr = fmax(terr, fabs(tau[0][0] - ref) / SY_);
      aerr = fmax(aerr, fabs(hist[6] - al));
      if (f <= 0) { /* elastic step: alpha frozen exactly */
        assert_true(hist[6] == alpha_before);
        ++nel;
      }
      assert_true(fabs(tau[0][0]) <= (SY_ + H_ * hist[6]) * (1 + 1e-12));
    }
  print_message("load/unload/reverse (900 increments, %d elastic): |tau11 - 1-D ref| / sy = "
                "%.2e, |alpha - ref| = %.2e, final alpha = %.4f\n",
                nel, terr, aerr, al);
  assert_true(nel >= 20); /* the elastic range 2 (sy + H alpha) / E spans ~14 increments */
  assert_true(terr <= 1e-9 && aerr <= 1e-12);
  solid_material_destroy(&mat);
}

enum { NP = 8, NSTEP = 250 };

typedef struct path_arrays {
  int dim;
  double F[9 * NP], V0[NP], hist[NH * NP], out[9 * NP];
} path_arrays;

/* Random large-deformation paths of NP particles, batched over a permuted subset; the 2-D
 * run is repeated in 3-D with F33 = 1 and must agree. */
static void test_random_paths(void **state) {
  (void)state;
  static const mpm_lidx idx[6] = {5, 0, 3, 7, 2, 6}; /* 1 and 4 stay outside the batch */
  solid_material *m3 = make(3, SY_, H_), *m2 = make(2, SY_, H_);
  double Fp[NP][3][3], drift[NP][3][3];
  double yerr = 0.0, over = 0.0, derr = 0.0, e23 = 0.0, hmax = 0.0, c33 = 0.0, amax = 0.0;
  int nplastic = 0;
  for (int dim = 3; dim >= 2; --dim) {
    path_arrays a3 = {.dim = 3}, a2 = {.dim = 2};
    for (int i = 0; i < NP; ++i) {
      identity(Fp[i]);
      a3.V0[i] = a2.V0[i] = 0.5 + 0.125 * i;
      /* a trace-free drift so that strains grow to O(0.5) */
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) drift[i][r][c] = r < dim && c < dim ? 2e-3 * rnd() : 0.0;
      const double tr = (drift[i][0][0] + drift[i][1][1] + drift[i][2][2]) / dim;
      for (int r = 0; r < dim; ++r) drift[i][r][r] -= tr;
    }
    const solid_batch b3 = {.dim = 3,
                            .n = NP,
                            .count = 6,
                            .idx = idx,
                            .F = a3.F,
                            .V0 = a3.V0,
                            .hist = a3.hist,
                            .out = a3.out};
    const solid_batch b2 = {.dim = 2,
                            .n = NP,
                            .count = 6,
                            .idx = idx,
                            .F = a2.F,
                            .V0 = a2.V0,
                            .hist = a2.hist,
                            .out = a2.out};
    for (int k = 0; k < NH * NP; ++k) a3.hist[k] = a2.hist[k] = -7.0; /* sentinels */
    m3->ops->init_history(m3, &b3);
    m2->ops->init_history(m2, &b2);
    for (int step = 0; step < NSTEP; ++step) {
      for (int i = 0; i < NP; ++i) {
        double G[3][3];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            G[r][c] = (r == c) + (r < dim && c < dim ? 4e-3 * rnd() + drift[i][r][c] : 0.0);
        matmul(G, Fp[i], Fp[i]);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            a3.F[(r * 3 + c) * NP + i] = Fp[i][r][c];
            if (r < 2 && c < 2) a2.F[(r * 2 + c) * NP + i] = Fp[i][r][c];
          }
      }
      for (int k = 0; k < 9 * NP; ++k) a3.out[k] = a2.out[k] = NAN;
      double h3[NH * NP], h2[NH * NP];
      memcpy(h3, a3.hist, sizeof h3);
      memcpy(h2, a2.hist, sizeof h2);
      m3->ops->stress(m3, &b3);
      m3->ops->stress(m3, &b3); /* as an RK stage would: repeated, same result */
      assert_memory_equal(h3, a3.hist, sizeof h3);
      if (dim == 2) {
        m2->ops->stress(m2, &b2);
        assert_memory_equal(h2, a2.hist, sizeof h2);
      }
      for (int j = 0; j < 6; ++j) {
        const mpm_lidx i = idx[j];
        double tau[3][3];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) tau[r][c] = a3.out[(r * 3 + c) * NP + i] / a3.V0[i];
        const double q = mises(tau);
        const double alpha0 = a3.hist[6 * NP + i];
        if (dim == 2) {
          for (int r = 0; r < 2; ++r)
            for (int c = 0; c < 2; ++c)
              e23 = fmax(e23, fabs(a2.out[(r * 2 + c) * NP + i] / a2.V0[i] - tau[r][c]) / SY_);
        }
        /* commit this particle alone to read its new alpha */
        const solid_batch one = {
            .dim = 3, .n = NP, .count = 1, .idx = &idx[j], .F = a3.F, .V0 = a3.V0, .hist = a3.hist};
        m3->ops->commit(m3, &one);
        const double alpha = a3.hist[6 * NP + i], k_y = SY_ + H_ * alpha;
        over = fmax(over, (q - k_y) / SY_);
        if (alpha > alpha0) ++nplastic, yerr = fmax(yerr, fabs(q - k_y) / SY_);
        amax = fmax(amax, alpha);
        double C[3][3];
        hist_matrix(a3.hist, NP, i, C);
        derr = fmax(derr, fabs(det3(C) - 1.0));
      }
      if (dim == 2) {
        m2->ops->commit(m2, &b2);
        for (int j = 0; j < 6; ++j)
          for (int k = 0; k < NH; ++k) {
            const size_t at = (size_t)k * NP + idx[j];
            hmax = fmax(hmax, fabs(a2.hist[at] - a3.hist[at]));
          }
        for (int j = 0; j < 6; ++j) c33 = fmax(c33, fabs(a2.hist[2 * NP + idx[j]] - 1.0));
      }
      for (int k = 0; k < NH; ++k) {
        assert_true(a3.hist[k * NP + 1] == -7.0 && a3.hist[k * NP + 4] == -7.0);
        assert_true(a2.hist[k * NP + 1] == -7.0 && a2.hist[k * NP + 4] == -7.0);
      }
      for (int k = 0; k < 9; ++k)
        assert_true(isnan(a3.out[k * NP + 1]) && isnan(a3.out[k * NP + 4]));
    }
  }
  print_message("random paths (%d particle steps, %d plastic, max alpha %.3f): q above the "
                "surface %.2e sy, |q - k| after flow %.2e sy, |det Cp^-1 - 1| %.2e; 2-D vs 3-D: "
                "stress %.2e sy, history %.2e; max |Cp^-1_33 - 1| in 2-D %.3f\n",
                2 * NSTEP * 6, nplastic, amax, over, yerr, derr, e23, hmax, c33);
  assert_true(nplastic > NSTEP);
  assert_true(over <= 1e-12 && yerr <= 1e-10);
  assert_true(derr <= 1e-12);
  assert_true(e23 <= 1e-12 && hmax <= 1e-12);
  assert_true(c33 > 1e-3); /* plane strain: the out-of-plane plastic stretch evolves */
  solid_material_destroy(&m3);
  solid_material_destroy(&m2);
}

/* stress(Q F) = Q stress(F) Q^T and commit(Q F) = commit(F), from a plastic history and a
 * plastic trial step. */
static void test_objectivity(void **state) {
  (void)state;
  double serr = 0.0, herr = 0.0;
  for (int dim = 2; dim <= 3; ++dim) {
    solid_material *mat = make(dim, SY_, H_);
    for (int t = 0; t < 50; ++t) {
      double F[3][3], hist[NH];
      identity(F);
      init_hist(mat, hist);
      for (int step = 0; step < 20; ++step) {
        double G[3][3];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) G[r][c] = (r == c) + (r < dim && c < dim ? 0.01 * rnd() : 0);
        matmul(G, F, F);
        point_commit(mat, F, hist);
      }
      double G[3][3], Fn[3][3], QF[3][3], R[3][3], tau[3][3], tauQ[3][3], rot[3][3];
      double h1[NH], h2[NH];
      for (int tries = 0; tries < 100; ++tries) { /* a plastic trial step */
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) G[r][c] = (r == c) + (r < dim && c < dim ? 0.01 * rnd() : 0);
        matmul(G, F, Fn);
        memcpy(h1, hist, sizeof h1);
        point_commit(mat, Fn, h1);
        if (h1[6] > hist[6]) break;
      }
      assert_true(h1[6] > hist[6]);
      rotation(R, dim == 2);
      matmul(R, Fn, QF);
      point_stress(mat, Fn, hist, tau);
      point_stress(mat, QF, hist, tauQ);
      congruence(R, tau, rot);
      for (int r = 0; r < dim; ++r)
        for (int c = 0; c < dim; ++c) serr = fmax(serr, fabs(tauQ[r][c] - rot[r][c]) / SY_);
      memcpy(h2, hist, sizeof h2);
      point_commit(mat, QF, h2);
      for (int k = 0; k < NH; ++k) herr = fmax(herr, fabs(h2[k] - h1[k]));
    }
    solid_material_destroy(&mat);
  }
  print_message("objectivity (plastic steps): stress %.2e sy, history %.2e\n", serr, herr);
  assert_true(serr <= 1e-12 && herr <= 1e-12);
}

/* Interface: history count and initial values, wave speed, zero stress at F = I, and a
 * missing sigma_y is an input error. */
static void test_interface(void **state) {
  (void)state;
  solid_material *mat = make(3, SY_, H_);
  assert_int_equal(mat->ops->nhistory(2), NH);
  assert_int_equal(mat->ops->nhistory(3), NH);
  assert_int_equal(mat->ops->small_strain, 0);
  const double lam = E_ * NU_ / ((1 + NU_) * (1 - 2 * NU_)), mu = E_ / (2 * (1 + NU_));
  assert_true(fabs(mat->ops->wave_speed(mat, 7800) - sqrt((lam + 2 * mu) / 7800)) <= 1e-12 * 5e3);
  double hist[NH], F[3][3], tau[3][3];
  init_hist(mat, hist);
  const double h0[NH] = {1, 1, 1, 0, 0, 0, 0};
  assert_memory_equal(hist, h0, sizeof h0);
  identity(F);
  point_stress(mat, F, hist, tau);
  assert_true(maxabs(tau) == 0.0);
  assert_true(point_energy(mat, F, hist) == 0.0);
  solid_material_destroy(&mat);

  mpm_config *cfg = NULL;
  assert_int_equal(mpm_config_new(&cfg, MPI_COMM_WORLD), 0);
  assert_int_equal(solid_add_schema(cfg), 0);
  assert_int_equal(mpm_config_read_string(cfg, "[solid.t]\nmaterial = j2\nE = 2e11\n", "t", "."),
                   0);
  assert_int_equal(solid_material_create(&mat, "j2", cfg, "solid.t", 3), MPM_ERR_INPUT);
  assert_null(mat);
  mpm_config_destroy(&cfg);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_eigen),        cmocka_unit_test(test_elastic_hencky),
      cmocka_unit_test(test_uniaxial),     cmocka_unit_test(test_unloading),
      cmocka_unit_test(test_random_paths), cmocka_unit_test(test_objectivity),
      cmocka_unit_test(test_interface),
  };
  const int failed = cmocka_run_group_tests_name("j2", tests, NULL, NULL);
  MPI_Finalize();
  return failed;
}
