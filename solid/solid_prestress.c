/* Initial stress of a solid body (see solid_prestress.h).
 *
 * A total model's F0 is found by Newton's method over the independent components u of the
 * pure stretch U = I + sym(u) (3 in 2-D, 6 in 3-D), on the residual
 * r(u) = (stress(U) / det U - sigma0) / |sigma0|, with stress() at unit reference volume and
 * fresh history, a central-difference Jacobian and a backtracking line search that keeps U
 * positive definite. The residual can fall only to the roundoff of the model's stress, about
 * eps K / |sigma0| for a stiffness K: the solve stops there, and accepts a residual of
 * 1e-11 + 64 eps K / |sigma0| (a stress the model cannot reach stalls far above it). */
#include "solid_prestress.h"

#include "mpm_error.h"
#include "solid_tensor.h"

#include <sundials/sundials_dense.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { PS_MAXIT = 100, PS_HALVINGS = 40 };

/* (row, column) of the unknowns: the diagonal, then the upper off-diagonal entries. */
static const int ps_sym2[3][2] = {{0, 0}, {1, 1}, {0, 1}};
static const int ps_sym3[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};

typedef struct {
  const solid_material *mat;
  int dim, ns, nh;
  const int (*sym)[2];
  const double *sigma0;
  double scale;         /* |sigma0|, the largest entry */
  double *hist0, *hist; /* fresh history and a scratch copy (nh each), or NULL */
} ps_ctx;

/* U = I + sym(u), row-major. */
static void ps_stretch(const ps_ctx *c, const double *u, double U[9]) {
  const int dim = c->dim;
  memset(U, 0, sizeof(double) * 9);
  for (int d = 0; d < dim; ++d) U[d * dim + d] = 1.0;
  for (int k = 0; k < c->ns; ++k) {
    const int r = c->sym[k][0], col = c->sym[k][1];
    U[r * dim + col] += u[k];
    if (r != col) U[col * dim + r] += u[k];
  }
}

/* Sylvester's criterion on the leading minors. */
static int ps_positive_definite(int dim, const double U[9]) {
  if (!(U[0] > 0.0)) return 0;
  if (!(U[0] * U[dim + 1] - U[1] * U[dim] > 0.0)) return 0;
  return dim == 2 || solid_det(3, U, 1, 0) > 0.0;
}

/* A one-particle batch at F = U, unit reference volume, the scratch history reset to fresh. */
static solid_batch ps_batch(const ps_ctx *c, const double U[9], double *out) {
  static const mpm_lidx zero = 0;
  static const double V0 = 1.0;
  if (c->nh) memcpy(c->hist, c->hist0, sizeof(double) * (size_t)c->nh);
  return (solid_batch){.dim = c->dim,
                       .n = 1,
                       .count = 1,
                       .idx = &zero,
                       .F = U,
                       .V0 = &V0,
                       .hist = c->nh ? c->hist : NULL,
                       .out = out};
}

/* Scaled residual at u and its largest entry; 1 if U is not a positive definite stretch or
 * the stress is not finite there. */
static int ps_residual(const ps_ctx *c, const double *u, double *r, double *rmax) {
  double U[9], out[9];
  ps_stretch(c, u, U);
  if (!ps_positive_definite(c->dim, U)) return 1;
  const solid_batch b = ps_batch(c, U, out);
  c->mat->ops->stress(c->mat, &b);
  const double J = solid_det(c->dim, U, 1, 0);
  double m = 0.0;
  for (int k = 0; k < c->ns; ++k) {
    const int rc = c->sym[k][0] * c->dim + c->sym[k][1];
    r[k] = (out[rc] / J - c->sigma0[rc]) / c->scale;
    if (!isfinite(r[k])) return 1;
    m = fmax(m, fabs(r[k]));
  }
  *rmax = m;
  return 0;
}

/* dr/du by central differences (one-sided where a side leaves the admissible stretches); its
 * largest entry in *kmax (the stiffness over |sigma0|). 1 if neither side is admissible. */
static int ps_jacobian(const ps_ctx *c, const double *u, const double *r, double Jm[6][6],
                       double *kmax) {
  const double h = 1e-7;
  double up[6], rp[6], rm[6], dummy;
  *kmax = 0.0;
  for (int k = 0; k < c->ns; ++k) {
    memcpy(up, u, sizeof up);
    up[k] = u[k] + h;
    const int bad_p = ps_residual(c, up, rp, &dummy);
    up[k] = u[k] - h;
    const int bad_m = ps_residual(c, up, rm, &dummy);
    if (bad_p && bad_m) return 1;
    for (int q = 0; q < c->ns; ++q) {
      Jm[q][k] = bad_p   ? (r[q] - rm[q]) / h
                 : bad_m ? (rp[q] - r[q]) / h
                         : (rp[q] - rm[q]) / (2 * h);
      *kmax = fmax(*kmax, fabs(Jm[q][k]));
    }
  }
  return 0;
}

/* Solve A x = b (n x n) with SUNDIALS's dense LU (partial pivoting); 1 if a pivot falls below
 * 1e-13 of A's largest entry (singular to roundoff). b is overwritten. */
static int ps_linear_solve(int n, double A[6][6], double *b, double *x) {
  double amax = 0.0, colmajor[6][6], *cols[6];
  sunindextype piv[6];
  for (int j = 0; j < n; ++j) {
    cols[j] = colmajor[j];
    for (int i = 0; i < n; ++i) colmajor[j][i] = A[i][j], amax = fmax(amax, fabs(A[i][j]));
  }
  if (SUNDlsMat_denseGETRF(cols, n, n, piv) != 0) return 1;
  for (int k = 0; k < n; ++k)
    if (!(fabs(cols[k][k]) > 1e-13 * amax)) return 1;
  SUNDlsMat_denseGETRS(cols, n, piv, b);
  memcpy(x, b, sizeof(double) * (size_t)n);
  return 0;
}

/* Newton from U = I; u ends at the smallest residual found, *rmax is it and *tol the residual
 * accepted as converged. */
static void ps_newton(const ps_ctx *c, double *u, double *rmax, double *tol) {
  double r[6], Jm[6][6], du[6], ut[6] = {0}, rt[6], rtmax, kmax;
  memset(u, 0, sizeof(double) * 6);
  *tol = 0.0; /* nothing is accepted before the first Jacobian sets it */
  if (ps_residual(c, u, r, rmax)) return;
  for (int it = 0; it < PS_MAXIT; ++it) {
    if (ps_jacobian(c, u, r, Jm, &kmax)) return;
    if (it == 0) *tol = 1e-11 + 64.0 * DBL_EPSILON * kmax;
    if (*rmax <= 1e-3 * *tol) return; /* at roundoff */
    double rhs[6];
    for (int k = 0; k < c->ns; ++k) rhs[k] = -r[k];
    if (ps_linear_solve(c->ns, Jm, rhs, du)) return;
    double alpha = 1.0;
    int moved = 0;
    for (int k = 0; k < PS_HALVINGS && !moved; ++k, alpha *= 0.5) {
      for (int q = 0; q < c->ns; ++q) ut[q] = u[q] + alpha * du[q];
      moved = !ps_residual(c, ut, rt, &rtmax) && rtmax < (1.0 - 1e-4 * alpha) * *rmax;
    }
    if (!moved) return; /* stalled: at roundoff, or no stretch reduces the residual */
    memcpy(u, ut, sizeof(double) * 6);
    memcpy(r, rt, sizeof r);
    *rmax = rtmax;
  }
}

/* Does commit() at U change the fresh history (the model yields there)? */
static int ps_yields(const ps_ctx *c, const double U[9]) {
  if (!c->nh || !c->mat->ops->commit) return 0;
  const solid_batch b = ps_batch(c, U, NULL);
  c->mat->ops->commit(c->mat, &b);
  for (int k = 0; k < c->nh; ++k)
    if (!(fabs(c->hist[k] - c->hist0[k]) <= 1e-10)) return 1;
  return 0;
}

/* Fresh history of model mat (init_history at F = I); NULL without history. */
static double *ps_fresh_history(const solid_material *mat, int dim, int *nh) {
  *nh = mat->ops->nhistory ? mat->ops->nhistory(dim) : 0;
  if (!*nh) return NULL;
  double *h = calloc(2 * (size_t)*nh, sizeof *h);
  if (!h) return NULL;
  if (mat->ops->init_history) {
    double I[9] = {0};
    for (int d = 0; d < dim; ++d) I[d * dim + d] = 1.0;
    static const mpm_lidx zero = 0;
    const solid_batch b = {.dim = dim, .n = 1, .count = 1, .idx = &zero, .F = I, .hist = h};
    mat->ops->init_history(mat, &b);
  }
  return h;
}

static int ps_solve_stretch(solid_prestress *ps, const solid_material *mat, int dim,
                            const double *sigma0, double scale, char *why, size_t nwhy) {
  ps_ctx c = {.mat = mat,
              .dim = dim,
              .ns = dim == 2 ? 3 : 6,
              .sym = dim == 2 ? ps_sym2 : ps_sym3,
              .sigma0 = sigma0,
              .scale = scale};
  c.hist0 = ps_fresh_history(mat, dim, &c.nh);
  if (c.nh && !c.hist0) return snprintf(why, nwhy, "out of memory"), MPM_ERR_MEMORY;
  c.hist = c.hist0 ? c.hist0 + c.nh : NULL;
  double u[6], rmax = HUGE_VAL, tol;
  ps_newton(&c, u, &rmax, &tol);
  ps_stretch(&c, u, ps->F0);
  const int yields = ps_yields(&c, ps->F0);
  free(c.hist0);
  if (yields) {
    snprintf(why, nwhy,
             "it lies beyond the model's initial yield surface (the body would yield "
             "at once); lower its deviatoric part%s",
             dim == 2 ? " (in 2-D the plane-strain out-of-plane stress adds one, even to a "
                        "pure pressure, of about (mu / K) p)"
                      : "");
    return MPM_ERR_INPUT;
  }
  if (!(rmax <= tol)) {
    snprintf(why, nwhy,
             "no elastic stretch gives it (the closest misses by %.2g of its size: the model's "
             "stress saturates there); lower the stress or choose a stiffer model",
             rmax);
    return MPM_ERR_INPUT;
  }
  ps->J0 = solid_det(dim, ps->F0, 1, 0);
  return 0;
}

int solid_prestress_solve(solid_prestress *ps, const solid_material *mat, int dim,
                          const double *sigma0, char *why, size_t nwhy) {
  memset(ps, 0, sizeof *ps);
  for (int d = 0; d < dim; ++d) ps->F0[d * dim + d] = 1.0;
  ps->J0 = 1.0;
  double scale = 0.0;
  for (int k = 0; k < dim * dim; ++k) scale = fmax(scale, fabs(sigma0[k]));
  if (scale == 0.0) return 0; /* stress-free: every model, rigid too, starts at F = I */
  if (mat->ops->rigid) return snprintf(why, nwhy, "a rigid body carries no stress"), MPM_ERR_INPUT;
  if (mat->ops->rate) { /* the stress is state: it starts where it is given */
    memcpy(ps->sigma0, sigma0, sizeof(double) * (size_t)(dim * dim));
    return 0;
  }
  return ps_solve_stretch(ps, mat, dim, sigma0, scale, why, nwhy);
}

/* The initial_stress tensor: dim x dim finite values, symmetric. */
static int ps_read_tensor(const mpm_config *cfg, const char *key, int dim, double *s) {
  static const char *const order[] = {"", "", "xx xy yx yy", "xx xy xz yx yy yz zx zy zz"};
  static const char axis[] = "xyz";
  int nv;
  MPM_CALL(mpm_config_get_reals(cfg, key, s, 9, &nv));
  if (nv != dim * dim)
    return mpm_config_fail(cfg, key,
                           "needs %d values in a %d-D case (the Cauchy stress row by row: %s), "
                           "got %d",
                           dim * dim, dim, order[dim], nv);
  for (int k = 0; k < nv; ++k)
    if (!isfinite(s[k])) return mpm_config_fail(cfg, key, "value %d is not a finite number", k + 1);
  for (int r = 0; r < dim; ++r)
    for (int c = r + 1; c < dim; ++c) {
      const double a = s[r * dim + c], b = s[c * dim + r];
      if (fabs(a - b) > 1e-12 * fmax(fabs(a), fabs(b)))
        return mpm_config_fail(cfg, key,
                               "the stress must be symmetric, but sigma_%c%c = %g and sigma_%c%c "
                               "= %g; give equal values",
                               axis[r], axis[c], a, axis[c], axis[r], b);
      s[r * dim + c] = s[c * dim + r] = 0.5 * (a + b);
    }
  return 0;
}

int solid_prestress_read(solid_prestress *ps, const mpm_config *cfg, const char *section,
                         const solid_material *mat, int dim) {
  char ks[160], kp[160], why[256];
  double s[9] = {0};
  snprintf(ks, sizeof ks, "%s.initial_stress", section);
  snprintf(kp, sizeof kp, "%s.initial_pressure", section);
  const int has_s = mpm_config_has(cfg, ks), has_p = mpm_config_has(cfg, kp);
  const char *key = has_s ? ks : kp;
  if (!has_s && !has_p) return solid_prestress_solve(ps, mat, dim, s, why, sizeof why);
  if (has_s && has_p)
    return mpm_config_fail(cfg, kp, "give either initial_stress or initial_pressure, not both");
  if (mat->ops->rigid)
    return mpm_config_fail(cfg, key, "a rigid body carries no stress; remove %s",
                           has_s ? "initial_stress" : "initial_pressure");
  if (has_s) {
    MPM_CALL(ps_read_tensor(cfg, ks, dim, s));
  } else {
    double p;
    MPM_CALL(mpm_config_get_real(cfg, kp, &p));
    if (!isfinite(p)) return mpm_config_fail(cfg, kp, "the pressure must be a finite number");
    for (int d = 0; d < dim; ++d) s[d * dim + d] = -p;
  }
  if (solid_prestress_solve(ps, mat, dim, s, why, sizeof why))
    return mpm_config_fail(cfg, key, "material %s cannot start at this stress: %s", mat->ops->name,
                           why);
  return 0;
}
