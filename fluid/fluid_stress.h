/* The gas stress: pressure from the ideal-gas law, optional Newtonian viscosity and a
 * compression-only artificial viscosity (von Neumann-Richtmyer quadratic + Landshoff
 * linear term):
 *
 *   sigma = -(p + q) I + 2 mu (D - tr(D) / 3 I),
 *   q = rho l |tr D| (c_lin c + c_quad l |tr D|)   for tr D < 0, else 0,
 *
 * with l the cell size. tr(D)/3 is the deviator of the physical 3-D rate: a 2-D run is plane
 * flow (D_zz = 0). Which strain rate D is depends on the time method (fluid_module.c). */
#ifndef FLUID_STRESS_H
#define FLUID_STRESS_H

#include "mpm_types.h"

typedef struct fluid_gas {
  double gamma;           /* ratio of specific heats */
  double mu;              /* dynamic viscosity, Pa s */
  double av_lin, av_quad; /* artificial viscosity coefficients */
  double l;               /* artificial viscosity length: the cell size */
} fluid_gas;

/* Particles in component-major arrays of stride n (tensors: component r*dim + c). */
typedef struct fluid_batch {
  int dim;
  mpm_lidx n;
  const double *m, *V0, *J, *e; /* mass, reference volume, V / V0, specific internal energy */
  const double *divv;           /* tr D */
  const double *D;              /* strain rate (dim*dim), or NULL when mu = 0 */
  double *vsig;                 /* out: V sigma (dim*dim) */
} fluid_batch;

/* The artificial viscous pressure (>= 0) of a particle. */
static inline double fluid_av_pressure(const fluid_gas *g, double rho, double c, double divv) {
  if (!(divv < 0.0)) return 0.0;
  const double dv = -g->l * divv; /* velocity jump across one cell */
  return rho * dv * (g->av_lin * c + g->av_quad * dv);
}

/* Signal speed for the stable step dx / (c + |v| + s): s = 2 nu / dx, nu the kinematic
 * viscosity of the artificial (l (c_lin c + c_quad l |tr D|) in compression) and the
 * physical ((4/3) mu / rho) viscous terms, the explicit diffusion limit written as a speed. */
static inline double fluid_viscous_speed(const fluid_gas *g, double rho, double c, double divv,
                                         double dx) {
  double nu = g->mu > 0.0 ? 4.0 / 3.0 * g->mu / rho : 0.0; /* (rho is only read if mu > 0) */
  if (divv < 0.0) nu += g->l * (g->av_lin * c - g->av_quad * g->l * divv);
  return 2.0 * nu / dx;
}

/* V sigma of every particle of the batch. */
void fluid_stress(const fluid_gas *g, const fluid_batch *b);
/* Its pressure part alone, -V p I. */
void fluid_stress_pressure(const fluid_gas *g, const fluid_batch *b);
/* The rest, the artificial and physical viscous part, of particle i into out (dim*dim; NULL:
 * only say whether there is one): 1 if it is not zero. */
int fluid_stress_viscous(const fluid_gas *g, const fluid_batch *b, mpm_lidx i, double *out);

#endif
