/* Small-strain linear elasticity: sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I.
 * Valid while rotations and strains stay small; it is not objective under large rotation
 * (use a finite-strain model for that). Parameters: E > 0, 0 <= nu < 0.5. */
#include "solid_material.h"

#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct {
  double E, nu, lambda, mu;
} linear_elastic;

static int le_create(solid_material *mat, const mpm_config *cfg, const char *section) {
  char key[160];
  linear_elastic *le;
  MPM_ALLOC(le, 1);
  mat->content = le;
  snprintf(key, sizeof key, "%s.E", section);
  MPM_CALL(mpm_config_get_real(cfg, key, &le->E));
  snprintf(key, sizeof key, "%s.nu", section);
  MPM_CALL(mpm_config_get_real(cfg, key, &le->nu));
  le->lambda = le->E * le->nu / ((1 + le->nu) * (1 - 2 * le->nu));
  le->mu = le->E / (2 * (1 + le->nu));
  return 0;
}

/* Strain from F (component-major tensor at particle i). */
static void le_strain(int dim, const double *F, mpm_lidx n, mpm_lidx i, double eps[3][3]) {
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c)
      eps[r][c] =
          0.5 * (F[(size_t)(r * dim + c) * n + i] + F[(size_t)(c * dim + r) * n + i]) - (r == c);
}

static void le_stress(const solid_material *mat, const solid_stress_batch *b) {
  const linear_elastic *le = mat->content;
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
        b->vsig[(size_t)(r * dim + c) * b->n + i] =
            V * (2.0 * le->mu * eps[r][c] + (r == c ? le->lambda * tr : 0.0));
  }
}

static double le_wave_speed(const solid_material *mat, double rho) {
  const linear_elastic *le = mat->content;
  return sqrt((le->lambda + 2.0 * le->mu) / rho);
}

static double le_energy_density(const solid_material *mat, int dim, const double *F) {
  const linear_elastic *le = mat->content;
  double eps[3][3], tr = 0.0, ee = 0.0;
  le_strain(dim, F, 1, 0, eps);
  for (int r = 0; r < dim; ++r) {
    tr += eps[r][r];
    for (int c = 0; c < dim; ++c) ee += eps[r][c] * eps[r][c];
  }
  return 0.5 * le->lambda * tr * tr + le->mu * ee;
}

static void le_destroy(solid_material *mat) {
  free(mat->content);
}

const solid_material_ops solid_linear_elastic_ops = {
    "linear_elastic", le_create, le_stress, le_wave_speed, le_energy_density, le_destroy,
};
