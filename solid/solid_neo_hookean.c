/* Compressible neo-Hookean hyperelasticity:
 *   W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2,  sigma = (mu (b - I) + lambda ln J I) / J,
 * with b = F F^T, I1 = tr b, J = det F. Stiffens without bound as J -> 0, so it suits large
 * compression. In 2-D plane strain the out-of-plane stretch is 1: I1 = tr b + 1 and the
 * in-plane Cauchy stress is the formula above with 2 x 2 tensors. Parameters: E > 0,
 * 0 <= nu < 0.5 (solid_elastic; lambda and mu are the small-strain Lame constants). */
#include "solid_elastic.h"

#include <math.h>
#include <stddef.h>

/* b = F F^T of particle i; returns J = det F. */
static double nh_left_cauchy_green(int dim, const double *F, mpm_lidx n, mpm_lidx i,
                                   double bl[3][3]) {
  double f[3][3];
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) f[r][c] = F[(size_t)(r * dim + c) * n + i];
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) {
      double s = 0.0;
      for (int k = 0; k < dim; ++k) s += f[r][k] * f[c][k];
      bl[r][c] = s;
    }
  if (dim == 2) return f[0][0] * f[1][1] - f[0][1] * f[1][0];
  return f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1]) -
         f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0]) +
         f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0]);
}

/* V sigma = V0 J sigma = V0 (mu (b - I) + lambda ln J I). */
static void nh_stress(const solid_material *mat, const solid_batch *b) {
  const solid_elastic *el = mat->content;
  const int dim = b->dim;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    double bl[3][3];
    const double lnJ = log(nh_left_cauchy_green(dim, b->F, b->n, i, bl));
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c)
        b->out[(size_t)(r * dim + c) * b->n + i] =
            b->V0[i] * (el->mu * (bl[r][c] - (r == c)) + (r == c ? el->lambda * lnJ : 0.0));
  }
}

/* W per reference volume; I1 - 3 = tr b - dim (plane strain adds the unit out-of-plane
 * stretch to both). */
static double nh_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  const solid_elastic *el = mat->content;
  double bl[3][3], trb = 0.0;
  const double lnJ = log(nh_left_cauchy_green(b->dim, b->F, b->n, i, bl));
  for (int d = 0; d < b->dim; ++d) trb += bl[d][d];
  return 0.5 * el->mu * (trb - b->dim) - el->mu * lnJ + 0.5 * el->lambda * lnJ * lnJ;
}

const solid_material_ops solid_neo_hookean_ops = {
    .name = "neo_hookean",
    .create = solid_elastic_create,
    .stress = nh_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = nh_energy_density,
    .destroy = solid_elastic_destroy,
};
