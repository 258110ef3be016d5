/* Ideal-gas equation of state, p = (gamma - 1) rho e, and the quantities derived from it.
 * Inline: every stress, stable-step and output loop calls these once per particle. Units SI:
 * rho kg/m^3, e J/kg, p Pa, R J/(kg K). */
#ifndef FLUID_EOS_H
#define FLUID_EOS_H

#include <math.h>

static inline double fluid_pressure(double gamma, double rho, double e) {
  return (gamma - 1.0) * rho * e;
}

/* Adiabatic sound speed; 0 for a state without pressure. */
static inline double fluid_sound_speed(double gamma, double rho, double p) {
  return p > 0.0 && rho > 0.0 ? sqrt(gamma * p / rho) : 0.0;
}

/* Specific internal energy of a state given by density and pressure. */
static inline double fluid_energy(double gamma, double rho, double p) {
  return p / ((gamma - 1.0) * rho);
}

static inline double fluid_temperature(double R, double rho, double p) {
  return p / (rho * R);
}

/* Specific entropy s = c_v ln(p / rho^gamma), c_v = R / (gamma - 1), up to a constant. */
static inline double fluid_entropy(double gamma, double R, double rho, double p) {
  return R / (gamma - 1.0) * (log(p) - gamma * log(rho));
}

#endif
