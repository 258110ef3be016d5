/* Gas stress over a batch of particles (see fluid_stress.h). */
#include "fluid_stress.h"

#include "fluid_eos.h"

/* -V (p + q - p_g) on the diagonal (q only with av; p_g the gauge, fluid_gauge.c); the viscous
 * part, if any, is added by viscous_stress. */
static void pressure_stress(const fluid_gas *g, const fluid_batch *b, int av) {
  const int dim = b->dim;
  const mpm_lidx n = b->n;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c)
      if (r != c)
        for (mpm_lidx i = 0; i < n; ++i) b->vsig[(size_t)(r * dim + c) * n + i] = 0.0;
  double *s00 = b->vsig;
  for (mpm_lidx i = 0; i < n; ++i) {
    const double V = b->V0[i] * b->J[i], rho = b->m[i] / V;
    const double p = fluid_pressure(g->gamma, rho, b->e[i]);
    const fluid_gas gi = fluid_gas_at(g, b->l, i);
    const double q = av ? fluid_av_pressure(&gi, rho, fluid_sound_speed(g->gamma, rho, p),
                                            b->divv[i], b->psi ? b->psi[i] : 0.0)
                        : 0.0;
    s00[i] = -V * (p + q - g->gauge);
  }
  for (int d = 1; d < dim; ++d) {
    double *sdd = b->vsig + (size_t)(d * dim + d) * n;
    for (mpm_lidx i = 0; i < n; ++i) sdd[i] = s00[i];
  }
}

/* Component (r, c) of V 2 mu (D - tr D / 3 I), V = V0 J, diag = (r == c). */
static inline double viscous_part(const fluid_gas *g, double V0, double J, double D, double divv,
                                  int diag) {
  return 2.0 * g->mu * V0 * J * (diag ? D - divv / 3.0 : D);
}

/* V 2 mu (D - tr D / 3 I). */
static void viscous_stress(const fluid_gas *g, const fluid_batch *b) {
  const int dim = b->dim;
  const mpm_lidx n = b->n;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) {
      const double *D = b->D + (size_t)(r * dim + c) * n;
      double *s = b->vsig + (size_t)(r * dim + c) * n;
      for (mpm_lidx i = 0; i < n; ++i)
        s[i] += viscous_part(g, b->V0[i], b->J[i], D[i], b->divv[i], r == c);
    }
}

void fluid_stress(const fluid_gas *g, const fluid_batch *b) {
  pressure_stress(g, b, 1);
  if (g->mu > 0.0 && b->D) viscous_stress(g, b);
}

void fluid_stress_pressure(const fluid_gas *g, const fluid_batch *b) {
  pressure_stress(g, b, 0);
}

int fluid_stress_viscous(const fluid_gas *g, const fluid_batch *b, mpm_lidx i, double *out) {
  const int dim = b->dim;
  const mpm_lidx n = b->n;
  const int viscous = g->mu > 0.0 && b->D;
  const int av = b->divv[i] < 0.0 && (g->av_lin > 0.0 || g->av_quad > 0.0) &&
                 !(b->psi && b->psi[i] >= 1.0); /* the limiter switched it off */
  if (!av && !viscous) return 0;
  if (!out) return 1;
  const double V = b->V0[i] * b->J[i], rho = b->m[i] / V;
  const double c = fluid_sound_speed(g->gamma, rho, fluid_pressure(g->gamma, rho, b->e[i]));
  const fluid_gas gi = fluid_gas_at(g, b->l, i);
  const double q = av ? fluid_av_pressure(&gi, rho, c, b->divv[i], b->psi ? b->psi[i] : 0.0) : 0.0;
  for (int r = 0; r < dim; ++r)
    for (int k = 0; k < dim; ++k) {
      const double D = viscous ? b->D[(size_t)(r * dim + k) * n + i] : 0.0;
      out[r * dim + k] =
          (r == k ? -V * q : 0.0) +
          (viscous ? viscous_part(g, b->V0[i], b->J[i], D, b->divv[i], r == k) : 0.0);
    }
  return 1;
}
