/* Hypoelasticity with the Jaumann rate (the solid of the seed paper, Hu et al. 2010):
 *   d sigma/dt = lambda tr(D) I + 2 mu D + W sigma - sigma W,  D = sym(L), W = skew(L).
 * A rate-form model: the Cauchy stress is the "sigma" state field (zero at the start, or the
 * initial stress), so it is objective (the Jaumann rate co-rotates with the material) but path
 * dependent: it derives from no stored-energy function, and a closed strain cycle can leave a
 * residual stress. In 2-D plane strain sigma, D and W are the in-plane 2 x 2 blocks (sigma_zz
 * is not needed by the in-plane equations). Parameters: E > 0, 0 <= nu < 0.5 (solid_elastic). */
#include "solid_tensor.h"
#include "solid_elastic.h"

#include <stddef.h>

/* V sigma with the current volume V = V0 det F. */
static void hypo_stress(const solid_material *mat, const solid_batch *b) {
  (void)mat;
  const int dim = b->dim;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    const double V = b->V0[i] * solid_det(dim, b->F, b->n, i);
    for (int rc = 0; rc < dim * dim; ++rc) {
      const size_t at = (size_t)rc * b->n + i;
      b->out[at] = V * b->sigma[at];
    }
  }
}

static void hypo_rate(const solid_material *mat, const solid_batch *b) {
  const solid_elastic *el = mat->content;
  const int dim = b->dim;
  const mpm_lidx n = b->n;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    double D[3][3], W[3][3], s[3][3], trD = 0.0;
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) {
        const double Lrc = b->L[(size_t)(r * dim + c) * n + i];
        const double Lcr = b->L[(size_t)(c * dim + r) * n + i];
        D[r][c] = 0.5 * (Lrc + Lcr);
        W[r][c] = 0.5 * (Lrc - Lcr);
        s[r][c] = b->sigma[(size_t)(r * dim + c) * n + i];
      }
    for (int d = 0; d < dim; ++d) trD += D[d][d];
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) {
        double spin = 0.0;
        for (int q = 0; q < dim; ++q) spin += W[r][q] * s[q][c] - s[r][q] * W[q][c];
        b->out[(size_t)(r * dim + c) * n + i] =
            2.0 * el->mu * D[r][c] + (r == c ? el->lambda * trD : 0.0) + spin;
      }
  }
}

/* No stored energy exists for this model; this is the complementary-energy estimate
 * sigma : C^{-1} : sigma / 2 per current volume (exact for small strains), times J for
 * reference volume. C^{-1}: sigma -> (sigma - a tr(sigma) I) / (2 mu), a = lambda / (dim
 * lambda + 2 mu); in 2-D this inverts the plane-strain stiffness, so eps_zz = 0 and
 * sigma_zz does no work. */
static double hypo_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  const solid_elastic *el = mat->content;
  const int dim = b->dim;
  double ss = 0.0, tr = 0.0;
  for (int r = 0; r < dim; ++r) {
    tr += b->sigma[(size_t)(r * dim + r) * b->n + i];
    for (int c = 0; c < dim; ++c) {
      const double s = b->sigma[(size_t)(r * dim + c) * b->n + i];
      ss += s * s;
    }
  }
  const double a = el->lambda / (dim * el->lambda + 2.0 * el->mu);
  return solid_det(dim, b->F, b->n, i) * (ss - a * tr * tr) / (4.0 * el->mu);
}

const solid_material_ops solid_hypoelastic_ops = {
    .name = "hypoelastic",
    .create = solid_elastic_create,
    .stress = hypo_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = hypo_energy_density,
    .destroy = solid_elastic_destroy,
    .rate = hypo_rate,
};
