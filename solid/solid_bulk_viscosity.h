/* A bulk (shock) viscosity for solids (solid.NAME.bulk_viscosity_linear, _quadratic), the
 * form of the explicit solid codes (LS-DYNA *CONTROL_BULK_VISCOSITY: linear 0.06, quadratic 1.5
 * by default; Abaqus/Explicit: 0.06, 1.2): on compression, tr D < 0,
 *
 *   q = rho l (c1 c |tr D| + c2 l (tr D)^2),   sigma -= q I,
 *
 * with l the cell size and c the body's elastic wave speed; q = 0 in expansion. It damps the
 * ringing behind a shock the solid's model steepens. The classic update (usl, musl) lags tr D:
 * it keeps the previous step's tr L in the state field divv (its rate over the step is
 * (new - old) / h), as the gas's lagged artificial viscosity does. The method of lines (the ERK
 * pairs, ssprk2) takes the current rate of the state itself, as the gas's current strain rate
 * does, so that the RHS is a function of y alone (solid_bulkq_rate.c). q does work only through
 * the grid forces: the kinetic energy it takes is not stored anywhere, so it shows as a drop of
 * the total energy, under either update. */
#ifndef SOLID_BULK_VISCOSITY_H
#define SOLID_BULK_VISCOSITY_H

#include "mpm_types.h"

typedef struct solid_bulkq {
  double c1, c2; /* linear and quadratic coefficients (0 and 0: off) */
  double c;      /* the body's elastic wave speed */
  double l;      /* the length: the cell size */
} solid_bulkq;

static inline int solid_bulkq_on(const solid_bulkq *q) {
  return q->c1 > 0.0 || q->c2 > 0.0;
}

/* The kinematic viscosity q / (rho l |tr D|) times l, in compression; else 0. */
static inline double solid_bulkq_nu(const solid_bulkq *q, double divv) {
  return divv < 0.0 ? q->l * (q->c1 * q->c - q->c2 * q->l * divv) : 0.0;
}

/* V q = m nu |tr D| of a particle of mass m (V rho = m), >= 0; 0 unless compressed. */
static inline double solid_bulkq_vq(const solid_bulkq *q, double m, double divv) {
  return -m * solid_bulkq_nu(q, divv) * divv;
}

/* V q = m nu |tr D| added to V sigma as -V q I, for the batch's particles idx (arrays of
 * stride n: vsig dim*dim components, m and divv one). */
void solid_bulkq_add(const solid_bulkq *q, int dim, mpm_lidx n, mpm_lidx count, const mpm_lidx *idx,
                     const double *m, const double *divv, double *vsig);

/* The signal speed it adds to the stable step dx / (c + |v| + s): s = 2 nu / dx, the explicit
 * diffusion limit written as a speed (as the gas's artificial viscosity, fluid_stress.h). */
static inline double solid_bulkq_speed(const solid_bulkq *q, double divv, double dx) {
  return 2.0 * solid_bulkq_nu(q, divv) / dx;
}

#endif
