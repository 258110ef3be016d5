/* St. Venant-Kirchhoff hyperelasticity: S = lambda tr(E) I + 2 mu E with the Green-Lagrange
 * strain E = (F^T F - I)/2, and sigma = F S F^T / J. Objective under any rotation, but it
 * softens in strong compression (it is only meant for large rotations with moderate
 * strains). In 2-D plane strain E_zz = 0, so the 2 x 2 formulas are exact. Parameters: E > 0,
 * 0 <= nu < 0.5 (solid_elastic). */
#include "solid_elastic.h"

#include <stddef.h>

/* Kirchhoff stress tau = J sigma = F S F^T of particle i, and the Green-Lagrange strain. */
static void stvk_kirchhoff(const solid_elastic *el, int dim, const double *F, mpm_lidx n,
                           mpm_lidx i, double tau[3][3], double E[3][3]) {
  double f[3][3], S[3][3], tr = 0.0;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) f[r][c] = F[(size_t)(r * dim + c) * n + i];
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) {
      double ftf = 0.0;
      for (int k = 0; k < dim; ++k) ftf += f[k][r] * f[k][c];
      E[r][c] = 0.5 * (ftf - (r == c));
    }
  for (int d = 0; d < dim; ++d) tr += E[d][d];
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) S[r][c] = 2.0 * el->mu * E[r][c] + (r == c ? el->lambda * tr : 0);
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) {
      double s = 0.0;
      for (int k = 0; k < dim; ++k)
        for (int l = 0; l < dim; ++l) s += f[r][k] * S[k][l] * f[c][l];
      tau[r][c] = s;
    }
}

/* V sigma = V0 J sigma = V0 tau: the 1/J of sigma cancels against V = V0 J. */
static void stvk_stress(const solid_material *mat, const solid_batch *b) {
  const int dim = b->dim;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    double tau[3][3], E[3][3];
    stvk_kirchhoff(mat->content, dim, b->F, b->n, i, tau, E);
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) b->out[(size_t)(r * dim + c) * b->n + i] = b->V0[i] * tau[r][c];
  }
}

/* W = lambda/2 tr(E)^2 + mu E:E per reference volume. */
static double stvk_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  const solid_elastic *el = mat->content;
  double tau[3][3], E[3][3], tr = 0.0, ee = 0.0;
  stvk_kirchhoff(el, b->dim, b->F, b->n, i, tau, E);
  for (int r = 0; r < b->dim; ++r) {
    tr += E[r][r];
    for (int c = 0; c < b->dim; ++c) ee += E[r][c] * E[r][c];
  }
  return 0.5 * el->lambda * tr * tr + el->mu * ee;
}

const solid_material_ops solid_stvk_ops = {
    .name = "stvk",
    .create = solid_elastic_create,
    .stress = stvk_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = stvk_energy_density,
    .destroy = solid_elastic_destroy,
};
