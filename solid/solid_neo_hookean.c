/* Compressible neo-Hookean hyperelasticity:
 *   W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2,  sigma = (mu (b - I) + lambda ln J I) / J,
 * with b = F F^T, I1 = tr b, J = det F. Stiffens without bound as J -> 0, so it suits large
 * compression. In 2-D plane strain the out-of-plane stretch is 1: I1 = tr b + 1 and the
 * in-plane Cauchy stress is the formula above with 2 x 2 tensors. Parameters: E > 0,
 * 0 <= nu < 0.5 (solid_elastic; lambda and mu are the small-strain Lame constants). */
#include "solid_elastic.h"

#include <math.h>
#include <stddef.h>

/* Every loop below runs over a compile-time dimension D: the helpers are always inlined
 * and called with a literal 2 or 3, so the tensor loops unroll completely. */
#define NH_INLINE static inline __attribute__((always_inline))

/* b = F F^T of particle i; returns J = det F. */
NH_INLINE double nh_left_cauchy_green(const int D, const double *F, mpm_lidx n, mpm_lidx i,
                                      double bl[3][3]) {
  double f[3][3];
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) f[r][c] = F[(size_t)(r * D + c) * n + i];
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) {
      double s = 0.0;
      for (int k = 0; k < D; ++k) s += f[r][k] * f[c][k];
      bl[r][c] = s;
    }
  if (D == 2) return f[0][0] * f[1][1] - f[0][1] * f[1][0];
  return f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1]) -
         f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0]) +
         f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0]);
}

/* V sigma = V0 J sigma = V0 (mu (b - I) + lambda ln J I). */
NH_INLINE void nh_stress_dim(const int D, const solid_elastic *el, const solid_batch *b) {
  const double mu = el->mu, lambda = el->lambda;
  const mpm_lidx n = b->n;
  double *out = b->out;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    double bl[3][3];
    const double lnJ = log(nh_left_cauchy_green(D, b->F, n, i, bl)), V0 = b->V0[i];
    for (int r = 0; r < D; ++r)
      for (int c = 0; c < D; ++c)
        out[(size_t)(r * D + c) * n + i] =
            V0 * (mu * (bl[r][c] - (r == c)) + (r == c ? lambda * lnJ : 0.0));
  }
}

static void nh_stress(const solid_material *mat, const solid_batch *b) {
  if (b->dim == 2)
    nh_stress_dim(2, mat->content, b);
  else
    nh_stress_dim(3, mat->content, b);
}

/* W per reference volume; I1 - 3 = tr b - dim (plane strain adds the unit out-of-plane
 * stretch to both). */
NH_INLINE double nh_energy_dim(const int D, const solid_elastic *el, const solid_batch *b,
                               mpm_lidx i) {
  double bl[3][3], trb = 0.0;
  const double lnJ = log(nh_left_cauchy_green(D, b->F, b->n, i, bl));
  for (int d = 0; d < D; ++d) trb += bl[d][d];
  return 0.5 * el->mu * (trb - D) - el->mu * lnJ + 0.5 * el->lambda * lnJ * lnJ;
}

static double nh_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  return b->dim == 2 ? nh_energy_dim(2, mat->content, b, i) : nh_energy_dim(3, mat->content, b, i);
}

const solid_material_ops solid_neo_hookean_ops = {
    .name = "neo_hookean",
    .create = solid_elastic_create,
    .stress = nh_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = nh_energy_density,
    .destroy = solid_elastic_destroy,
};
