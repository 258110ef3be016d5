/* Finite-strain J2 plasticity with linear isotropic hardening: the multiplicative
 * formulation F = Fe Fp with logarithmic (Hencky) elastic strains and radial return in
 * principal space (Simo 1992; de Souza Neto, Peric & Owen, ch. 14).
 *
 * History per particle (always 3-D, also in 2-D plane strain, where the out-of-plane plastic
 * stretch still evolves): the symmetric Cp^{-1} = Fp^{-1} Fp^{-T} as components
 * xx yy zz xy yz xz (hist 0-5), then the equivalent plastic strain alpha (hist 6). Initially
 * Cp^{-1} = I, alpha = 0.
 *
 * Return map from F and the committed (Cp^{-1}, alpha):
 *   trial b_e = F Cp^{-1} F^T = sum lambda_i n_i n_i, eps_i = ln(lambda_i) / 2,
 *   tau_i = K tr(eps) + 2 mu dev(eps)_i, q = sqrt(3/2) |dev tau|,
 *   f = q - (sigma_y + H alpha); if f > 0: dgamma = f / (3 mu + H), dev eps scaled by
 *   1 - 3 mu dgamma / q, alpha += dgamma.
 * Plastic flow is deviatoric, so det Cp^{-1} = 1 is kept, and under uniaxial stress the
 * Kirchhoff stress follows tau = sigma_y + H eps_p exactly (the exponential map is exact
 * for fixed principal directions). stress() leaves the history alone; commit() repeats the
 * return from the accepted F and stores Cp^{-1} = F^{-1} b_e F^{-T}, b_e = exp(2 eps).
 * Parameters: E, nu (solid_elastic), sigma_y > 0 (required), hardening H >= 0. */
#include "solid_elastic.h"

#include "mpm_error.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

enum { J2_NHIST = 7, J2_ALPHA = 6 };

/* (row, column) of the stored components of Cp^{-1}. */
static const int j2_sym[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};

typedef struct j2_params {
  solid_elastic el; /* first, so that the solid_elastic helpers read it */
  double sigma_y, H;
} j2_params;

/* The returned state of one particle: principal directions (columns of Q), principal
 * elastic log strains and Kirchhoff stresses, and the updated alpha. */
typedef struct j2_state {
  double Q[3][3], eps[3], tau[3], alpha;
} j2_state;

/* Eigen-decomposition A = Q diag(lam) Q^T of a symmetric 3 x 3 matrix by cyclic Jacobi
 * rotations. Each rotation zeroes one off-diagonal entry exactly, so convergence is
 * quadratic and repeated eigenvalues need no special case (any orthonormal basis of the
 * eigenspace is returned). */
static void j2_eigen(const double A[3][3], double lam[3], double Q[3][3]) {
  double a[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[r][c] = 0.5 * (A[r][c] + A[c][r]), Q[r][c] = (r == c);
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-36 * (diag + 2.0 * off)) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        /* t = tan of the rotation angle, the smaller root (stable for any theta). */
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t = fabs(theta) > 1e150
                             ? 0.5 / theta
                             : copysign(1.0, theta) / (fabs(theta) + sqrt(theta * theta + 1.0));
        const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) {
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq, a[k][q] = s * akp + c * akq;
          const double qkp = Q[k][p], qkq = Q[k][q];
          Q[k][p] = c * qkp - s * qkq, Q[k][q] = s * qkp + c * qkq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk, a[q][k] = s * apk + c * aqk;
        }
        a[p][q] = a[q][p] = 0.0;
      }
  }
  for (int k = 0; k < 3; ++k) lam[k] = a[k][k];
}

/* B = Q diag(d) Q^T. */
static void j2_spectral(const double Q[3][3], const double d[3], double B[3][3]) {
  for (int r = 0; r < 3; ++r)
    for (int c = r; c < 3; ++c) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k) s += Q[r][k] * d[k] * Q[c][k];
      B[r][c] = B[c][r] = s;
    }
}

/* F of particle i embedded in 3 x 3 (plane strain: F33 = 1). */
static void j2_load_F(const solid_batch *b, mpm_lidx i, double F[3][3]) {
  const int dim = b->dim;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[r][c] = r < dim && c < dim ? b->F[(size_t)(r * dim + c) * b->n + i] : (double)(r == c);
}

/* Committed Cp^{-1} and alpha of particle i (the initial state if the batch has none). */
static double j2_load_hist(const solid_batch *b, mpm_lidx i, double Cpinv[3][3]) {
  for (int k = 0; k < 6; ++k) {
    const int r = j2_sym[k][0], c = j2_sym[k][1];
    Cpinv[r][c] = Cpinv[c][r] = b->hist ? b->hist[(size_t)k * b->n + i] : (double)(r == c);
  }
  return b->hist ? b->hist[(size_t)J2_ALPHA * b->n + i] : 0.0;
}

/* Radial return from the trial state of particle i. */
static void j2_return(const j2_params *p, const solid_batch *b, mpm_lidx i, j2_state *s) {
  double F[3][3], Cpinv[3][3], FC[3][3], be[3][3], lam[3];
  j2_load_F(b, i, F);
  const double alpha = j2_load_hist(b, i, Cpinv);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      FC[r][c] = F[r][0] * Cpinv[0][c] + F[r][1] * Cpinv[1][c] + F[r][2] * Cpinv[2][c];
  for (int r = 0; r < 3; ++r)
    for (int c = r; c < 3; ++c)
      be[r][c] = be[c][r] = FC[r][0] * F[c][0] + FC[r][1] * F[c][1] + FC[r][2] * F[c][2];
  j2_eigen(be, lam, s->Q);
  /* b_e is positive definite while det F > 0; the floor only keeps an inverted F (which
   * the module's state check rejects) from producing NaN here. */
  for (int k = 0; k < 3; ++k) s->eps[k] = 0.5 * log(fmax(lam[k], DBL_MIN));
  const double mu = p->el.mu, tr = s->eps[0] + s->eps[1] + s->eps[2];
  double dev[3], dev2 = 0.0;
  for (int k = 0; k < 3; ++k) dev[k] = s->eps[k] - tr / 3.0, dev2 += dev[k] * dev[k];
  const double q = 2.0 * mu * sqrt(1.5 * dev2);
  const double f = q - (p->sigma_y + p->H * alpha);
  double scale = 1.0;
  s->alpha = alpha;
  if (f > 0.0) {
    const double dgamma = f / (3.0 * mu + p->H);
    scale = 1.0 - 3.0 * mu * dgamma / q;
    s->alpha = alpha + dgamma;
  }
  for (int k = 0; k < 3; ++k) {
    s->eps[k] = tr / 3.0 + scale * dev[k];
    s->tau[k] = p->el.K * tr + 2.0 * mu * scale * dev[k];
  }
}

static void j2_stress(const solid_material *mat, const solid_batch *b) {
  const j2_params *p = mat->content;
  const int dim = b->dim;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    j2_state s;
    double tau[3][3];
    j2_return(p, b, i, &s);
    j2_spectral(s.Q, s.tau, tau);
    /* V sigma = (V0 J)(tau / J) = V0 tau. */
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) b->out[(size_t)(r * dim + c) * b->n + i] = b->V0[i] * tau[r][c];
  }
}

/* Inverse of a 3 x 3 matrix by the adjugate (F is well conditioned in practice). */
static void j2_inverse(const double A[3][3], double Ai[3][3]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      Ai[r][c] = A[r1][c1] * A[r2][c2] - A[r1][c2] * A[r2][c1];
    }
  const double det = A[0][0] * Ai[0][0] + A[0][1] * Ai[1][0] + A[0][2] * Ai[2][0];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Ai[r][c] /= det;
}

static void j2_commit(const solid_material *mat, const solid_batch *b) {
  const j2_params *p = mat->content;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    j2_state s;
    double F[3][3], Fi[3][3], be[3][3], e2[3], FiB[3][3];
    j2_return(p, b, i, &s);
    for (int d = 0; d < 3; ++d) e2[d] = exp(2.0 * s.eps[d]);
    j2_spectral(s.Q, e2, be);
    j2_load_F(b, i, F);
    j2_inverse(F, Fi);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        FiB[r][c] = Fi[r][0] * be[0][c] + Fi[r][1] * be[1][c] + Fi[r][2] * be[2][c];
    for (int m = 0; m < 6; ++m) {
      const int r = j2_sym[m][0], c = j2_sym[m][1];
      b->hist[(size_t)m * b->n + i] =
          FiB[r][0] * Fi[c][0] + FiB[r][1] * Fi[c][1] + FiB[r][2] * Fi[c][2];
    }
    b->hist[(size_t)J2_ALPHA * b->n + i] = s.alpha;
  }
}

static void j2_init_history(const solid_material *mat, const solid_batch *b) {
  (void)mat;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    for (int m = 0; m < J2_NHIST; ++m) b->hist[(size_t)m * b->n + i] = m < 3 ? 1.0 : 0.0;
  }
}

/* Hencky energy of the returned elastic strain. */
static double j2_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  const j2_params *p = mat->content;
  j2_state s;
  j2_return(p, b, i, &s);
  const double tr = s.eps[0] + s.eps[1] + s.eps[2];
  double dev2 = 0.0;
  for (int k = 0; k < 3; ++k) dev2 += (s.eps[k] - tr / 3.0) * (s.eps[k] - tr / 3.0);
  return 0.5 * p->el.K * tr * tr + p->el.mu * dev2;
}

static int j2_nhistory(int dim) {
  (void)dim;
  return J2_NHIST;
}

static int j2_create(solid_material *mat, const mpm_config *cfg, const char *section, int dim) {
  char key[160];
  MPM_CALL(solid_elastic_create(mat, cfg, section, dim));
  j2_params *p;
  MPM_ALLOC(p, 1);
  p->el = *(const solid_elastic *)mat->content;
  free(mat->content);
  mat->content = p;
  snprintf(key, sizeof key, "%s.sigma_y", section);
  if (!mpm_config_has(cfg, key))
    return mpm_config_fail(cfg, section,
                           "the j2 plasticity model needs the initial yield stress: add "
                           "sigma_y = ... (Pa)");
  MPM_CALL(mpm_config_get_real(cfg, key, &p->sigma_y));
  if (!(p->sigma_y > 0.0)) return mpm_config_fail(cfg, key, "the yield stress must be > 0");
  snprintf(key, sizeof key, "%s.hardening", section);
  MPM_CALL(mpm_config_get_real(cfg, key, &p->H));
  if (!(p->H >= 0.0))
    return mpm_config_fail(cfg, key, "the hardening modulus must be >= 0 (0: perfect plasticity)");
  return 0;
}

static void j2_destroy(solid_material *mat) {
  free(mat->content);
  mat->content = NULL;
}

const solid_material_ops solid_j2_ops = {
    .name = "j2",
    .create = j2_create,
    .stress = j2_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = j2_energy_density,
    .destroy = j2_destroy,
    .nhistory = j2_nhistory,
    .init_history = j2_init_history,
    .commit = j2_commit,
    .small_strain = 0,
};
