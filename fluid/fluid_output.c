/* The gas output fields, derived from the state just before a snapshot or checkpoint is
 * written (the module's output op), so that steps between outputs do not pay for them:
 * density, pressure, Mach number |v| / c, temperature p / (rho R) and specific entropy
 * c_v ln(p / rho^gamma). */
#include "fluid_eos.h"
#include "fluid_internal.h"

void fluid_output_fields(mpm_module *m) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const fluid_layout *lay = &fc->lay;
  const double gamma = fc->gas.gamma;
  const double *mass = mpm_particles_comp(p, lay->f_m, 0),
               *V0 = mpm_particles_comp(p, lay->f_V0, 0);
  const double *J = mpm_particles_comp(p, FLUID_J, 0), *e = mpm_particles_comp(p, FLUID_E, 0);
  double *rho = mpm_particles_comp(p, lay->f_rho, 0), *pr = mpm_particles_comp(p, lay->f_p, 0);
  double *mach = mpm_particles_comp(p, lay->f_mach, 0), *T = mpm_particles_comp(p, lay->f_T, 0);
  double *s = mpm_particles_comp(p, lay->f_s, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    rho[i] = mass[i] / (V0[i] * J[i]);
    pr[i] = fluid_pressure(gamma, rho[i], e[i]);
    T[i] = fluid_temperature(fc->R, rho[i], pr[i]);
    s[i] = fluid_entropy(gamma, fc->R, rho[i], pr[i]);
    mach[i] = 0.0;
  }
  for (int d = 0; d < p->dim; ++d) {
    const double *v = mpm_particles_comp(p, FLUID_V, d);
    for (mpm_lidx i = 0; i < p->n; ++i) mach[i] += v[i] * v[i];
  }
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const double c = fluid_sound_speed(gamma, rho[i], pr[i]);
    mach[i] = c > 0.0 ? sqrt(mach[i]) / c : 0.0;
  }
}
