/* Small-strain linear elasticity: sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I.
 * Valid while rotations and strains stay small: it is not objective under finite rotation
 * (use stvk or neo_hookean for that). Parameters: E > 0, 0 <= nu < 0.5. */
#include "solid_elastic.h"

#include "mpm_error.h"

#include <stdlib.h>

/* Strain of particle i (component-major tensor with stride n). */
static void le_strain(int dim, const double *F, mpm_lidx n, mpm_lidx i, double eps[3][3]) {
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c)
      eps[r][c] =
          0.5 * (F[(size_t)(r * dim + c) * n + i] + F[(size_t)(c * dim + r) * n + i]) - (r == c);
}

static void le_stress(const solid_material *mat, const solid_batch *b) {
  const solid_elastic *el = mat->content;
  const int dim = b->dim;
  for (mpm_lidx k = 0; k < b->count; ++k) {
    const mpm_lidx i = b->idx[k];
    double eps[3][3], tr = 0.0;
    le_strain(dim, b->F, b->n, i, eps);
    for (int d = 0; d < dim; ++d) tr += eps[d][d];
    /* Small strain: the current volume is V0 to first order, consistent with the model. */
    const double V = b->V0[i];
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c)
        b->out[(size_t)(r * dim + c) * b->n + i] =
            V * (2.0 * el->mu * eps[r][c] + (r == c ? el->lambda * tr : 0.0));
  }
}

static double le_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  const solid_elastic *el = mat->content;
  double eps[3][3], tr = 0.0, ee = 0.0;
  le_strain(b->dim, b->F, b->n, i, eps);
  for (int r = 0; r < b->dim; ++r) {
    tr += eps[r][r];
    for (int c = 0; c < b->dim; ++c) ee += eps[r][c] * eps[r][c];
  }
  return 0.5 * el->lambda * tr * tr + el->mu * ee;
}

const solid_material_ops solid_linear_elastic_ops = {
    .name = "linear_elastic",
    .create = solid_elastic_create,
    .stress = le_stress,
    .wave_speed = solid_elastic_wave_speed,
    .energy_density = le_energy_density,
    .destroy = solid_elastic_destroy,
    .small_strain = 1,
};
