/* Isotropic elastic constants shared by the elastic models: reading E and nu from a body's
 * section, the Lame constants, and the P-wave speed. */
#ifndef SOLID_ELASTIC_H
#define SOLID_ELASTIC_H

#include "solid_material.h"

typedef struct solid_elastic {
  double E, nu, lambda, mu, K; /* K: bulk modulus, lambda + 2 mu / 3 (3-D) */
} solid_elastic;

/* Read E (required) and nu of `section` into a new solid_elastic as mat->content. */
int solid_elastic_create(solid_material *mat, const mpm_config *cfg, const char *section, int dim);
void solid_elastic_destroy(solid_material *mat);
/* sqrt((lambda + 2 mu) / rho): the P-wave speed of the small-strain tangent. */
double solid_elastic_wave_speed(const solid_material *mat, double rho);

#endif
