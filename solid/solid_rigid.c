/* Rigid body with a prescribed velocity, for obstacles and fixtures: no stress, F stays I,
 * the particles move with the body's constant `velocity`, and the body holds the grid nodes
 * inside its region (translated with it) at that velocity. The motion and the node rule
 * live in the solid module (solid_module.c), which reads the `rigid` flag; this file gives
 * the model's side: zero stress and energy, and a wave speed of 0 so that only the body's
 * velocity enters the stable step. Parameters: density only (it gives the particle mass).
 * E and sigma_y given to a rigid body are input errors. nu and hardening have defaults, so a
 * user may set them to their defaults' values: they are ignored, as every model ignores the
 * keys it does not use. */
#include "solid_material.h"

#include <stdio.h>
#include <string.h>

static int rigid_create(solid_material *mat, const mpm_config *cfg, const char *section, int dim) {
  (void)dim;
  static const char *const unused[] = {"E", "sigma_y"};
  mat->content = NULL;
  for (size_t k = 0; k < sizeof unused / sizeof unused[0]; ++k) {
    char key[160];
    snprintf(key, sizeof key, "%s.%s", section, unused[k]);
    if (mpm_config_has(cfg, key))
      return mpm_config_fail(cfg, key,
                             "a rigid body has no material constants (it carries no stress "
                             "and moves with its prescribed velocity); remove %s",
                             unused[k]);
  }
  return 0;
}

static void rigid_stress(const solid_material *mat, const solid_batch *b) {
  (void)mat;
  const int dd = b->dim * b->dim;
  for (int rc = 0; rc < dd; ++rc) {
    double *out = b->out + (size_t)rc * b->n;
    for (mpm_lidx k = 0; k < b->count; ++k) out[b->idx[k]] = 0.0;
  }
}

static double rigid_wave_speed(const solid_material *mat, double rho) {
  (void)mat, (void)rho;
  return 0.0;
}

static double rigid_energy_density(const solid_material *mat, const solid_batch *b, mpm_lidx i) {
  (void)mat, (void)b, (void)i;
  return 0.0;
}

static void rigid_destroy(solid_material *mat) {
  (void)mat;
}

const solid_material_ops solid_rigid_ops = {
    .name = "rigid",
    .create = rigid_create,
    .stress = rigid_stress,
    .wave_speed = rigid_wave_speed,
    .energy_density = rigid_energy_density,
    .destroy = rigid_destroy,
    .rigid = 1,
};
