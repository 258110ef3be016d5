/* Isotropic elastic constants (see solid_elastic.h). */
#include "solid_elastic.h"

#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int solid_elastic_create(solid_material *mat, const mpm_config *cfg, const char *section, int dim) {
  (void)dim;
  char key[160];
  solid_elastic *el;
  MPM_ALLOC(el, 1);
  mat->content = el;
  snprintf(key, sizeof key, "%s.E", section);
  if (!mpm_config_has(cfg, key))
    return mpm_config_fail(cfg, section, "the elastic model needs Young's modulus: add E = ...");
  MPM_CALL(mpm_config_get_real(cfg, key, &el->E));
  snprintf(key, sizeof key, "%s.nu", section);
  MPM_CALL(mpm_config_get_real(cfg, key, &el->nu));
  el->lambda = el->E * el->nu / ((1 + el->nu) * (1 - 2 * el->nu));
  el->mu = el->E / (2 * (1 + el->nu));
  el->K = el->lambda + 2.0 * el->mu / 3.0;
  return 0;
}

void solid_elastic_destroy(solid_material *mat) {
  free(mat->content);
}

double solid_elastic_wave_speed(const solid_material *mat, double rho) {
  const solid_elastic *el = mat->content;
  return sqrt((el->lambda + 2.0 * el->mu) / rho);
}
