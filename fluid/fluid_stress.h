/* The gas stress: pressure from the ideal-gas law, optional Newtonian viscosity and a
 * compression-only artificial viscosity q of one of two forms (fluid.av_form):
 *
 *   sigma = -(p + q) I + 2 mu (D - tr(D) / 3 I),
 *   vnr:     q = rho du (c_lin c + c_quad du)   (von Neumann-Richtmyer quadratic + Landshoff
 *            linear term),
 *   riemann: q = rho du (1 - psi) [c_quad a du + sqrt(c_quad^2 a^2 du^2 + c_lin^2 c^2)],
 *            a = (gamma + 1) / 4 (Kuropatenko's two-shock form, as in Caramana, Shashkov and
 *            Whalen 1998, with a Christensen limiter psi in [0, 1]: fluid_limiter.c),
 *
 * for tr D < 0, else q = 0, with du = l |tr D| the velocity jump over l, the cell size (on a
 * refinement the spacing of the particle's own level: fluid_batch.l, fluid_refine.c). The
 * riemann form is the pressure jump of a shock of speed jump du in a gas of sound speed c; psi
 * is 1 (q off) where the compression is as strong one cell either side (smooth compression)
 * and 0 at a shock. tr(D)/3 is the deviator of the physical 3-D rate: a 2-D run is plane flow
 * (D_zz = 0). Which strain rate D is depends on the time method (fluid_module.c). */
#ifndef FLUID_STRESS_H
#define FLUID_STRESS_H

#include "mpm_types.h"

#include <math.h>

/* The riemann form's default coefficients c_lin and c_quad (fluid.av_form). */
#define FLUID_RIEMANN_LIN  1.0
#define FLUID_RIEMANN_QUAD 4.0

typedef struct fluid_gas {
  double gamma;           /* ratio of specific heats */
  double mu;              /* dynamic viscosity, Pa s */
  double av_lin, av_quad; /* artificial viscosity coefficients */
  int av_riemann;         /* fluid.av_form = riemann (else vnr) */
  int damped_step;        /* fluid.viscous_step = damped (else additive) */
  double l;               /* artificial viscosity length: the cell size */
  double gauge;           /* physics.gauge_pressure, Pa: out of the forces' pressure (below) */
} fluid_gas;

/* Particles in component-major arrays of stride n (tensors: component r*dim + c). */
typedef struct fluid_batch {
  int dim;
  mpm_lidx n;
  const double *m, *V0, *J, *e; /* mass, reference volume, V / V0, specific internal energy */
  const double *divv;           /* tr D */
  const double *D;              /* strain rate (dim*dim), or NULL when mu = 0 */
  const double *psi;            /* riemann form: the limiter (fluid_limiter.c), else NULL */
  const double *l;              /* per particle artificial viscosity length, else NULL: g->l */
  double *vsig;                 /* out: V sigma (dim*dim) */
} fluid_batch;

/* The gas as particle i of a batch with per-particle lengths l sees it (l NULL: g). */
static inline fluid_gas fluid_gas_at(const fluid_gas *g, const double *l, mpm_lidx i) {
  fluid_gas a = *g;
  if (l) a.l = l[i];
  return a;
}

/* The artificial kinematic viscosity per unit length, q / (rho du), of the velocity jump
 * du = l |tr D| >= 0 at sound speed c and limiter psi (riemann form only; see above). */
static inline double fluid_av_speed(const fluid_gas *g, double c, double du, double psi) {
  if (!g->av_riemann) return g->av_lin * c + g->av_quad * du;
  const double a = g->av_quad * 0.25 * (g->gamma + 1.0) * du, b = g->av_lin * c;
  return (1.0 - psi) * (a + sqrt(a * a + b * b));
}

/* The artificial viscous pressure (>= 0) of a particle. */
static inline double fluid_av_pressure(const fluid_gas *g, double rho, double c, double divv,
                                       double psi) {
  if (!(divv < 0.0)) return 0.0;
  const double du = -g->l * divv; /* velocity jump across one cell */
  return rho * du * fluid_av_speed(g, c, du, psi);
}

/* Signal speed for the stable step dx / (c + |v| + s): s = 2 nu / dx, nu the kinematic
 * viscosity of the artificial (l fluid_av_speed in compression) and the physical
 * ((4/3) mu / rho) viscous terms, the explicit diffusion limit written as a speed. */
static inline double fluid_viscous_speed(const fluid_gas *g, double rho, double c, double divv,
                                         double psi, double dx) {
  double nu = g->mu > 0.0 ? 4.0 / 3.0 * g->mu / rho : 0.0; /* (rho is only read if mu > 0) */
  if (divv < 0.0) /* (vnr in its own order of operations: its step sizes bit for bit) */
    nu += g->l * (g->av_riemann ? fluid_av_speed(g, c, -g->l * divv, psi)
                                : g->av_lin * c - g->av_quad * g->l * divv);
  return 2.0 * nu / dx;
}

/* A particle's signal speed for the stable step dx / (|v| + s) without its |v|: s = c + 2 nu / dx
 * (fluid.viscous_step = additive, the acoustic and the diffusion limits added), or the damped
 * critical step of the explicit central-difference update, dt = (2 / w)(sqrt(1 + xi^2) - xi)
 * (Belytschko, Liu and Moran, Nonlinear finite elements, 6.3), with w = 2 c / dx the grid's
 * highest frequency and xi = nu / (c dx) its damping ratio, written as a speed:
 * s = nu / dx + sqrt(c^2 + (nu / dx)^2) (damped). The damped speed is never below c nor above
 * the additive one; at vnr's linear term alone (nu / dx = c / 2) it is 1.62 c against 2 c. */
static inline double fluid_signal_speed(const fluid_gas *g, double rho, double c, double divv,
                                        double psi, double dx) {
  const double s = fluid_viscous_speed(g, rho, c, divv, psi, dx);
  if (!g->damped_step) return c + s;
  const double a = 0.5 * s; /* nu / dx */
  return a + sqrt(c * c + a * a);
}

/* V sigma of every particle of the batch. */
void fluid_stress(const fluid_gas *g, const fluid_batch *b);
/* Its pressure part alone, -V p I. */
void fluid_stress_pressure(const fluid_gas *g, const fluid_batch *b);
/* The rest, the artificial and physical viscous part, of particle i into out (dim*dim; NULL:
 * only say whether there is one): 1 if it is not zero. */
int fluid_stress_viscous(const fluid_gas *g, const fluid_batch *b, mpm_lidx i, double *out);

#endif
