/* The gauge pressure (physics.gauge_pressure = p_g): a uniform pressure taken out of the stress
 * in every phase's nodal forces, the gas's -V (p - p_g) I (fluid_stress.c) and a solid's
 * V (sigma + p_g I) (solid/solid_module.c), but not out of their energy: the gas's internal
 * energy takes the whole pressure's work (fluid_module.c, energy_rate).
 *
 * Why. A uniform stress has no divergence: its only force is on the boundary of the domain,
 * where walls hold it. The particles' quadrature of it is not exact, though: beside the solid
 * under coupling.scheme = sharp, where the gas's own field ends at the solid's face, the
 * quadrature of the ambient pressure over the gas's last particle columns grows a transverse
 * mode out of roundoff (the resonator, cases/fsi_resonator.ini, bs32 at 400 cells per metre:
 * max |v_y| 2.6e-8 of c after 18 s; with the gauge at the ambient 3e-15, its frequencies
 * unchanged). With the gauge the quadrature sees the perturbation only.
 *
 * What it costs. Each phase's own energy then changes by -p_g dV/dt besides the interface's
 * work (coupling.csv books the exchanges only); the sum over the phases is -p_g times the rate
 * of the particles' total volume, zero in a closed box up to that volume's discretisation.
 *
 * Scope. The gauge's exact boundary force is left to the domain's walls and periodic faces: open
 * faces (which impose the exterior's whole pressure), static obstacles (their ghost pressure
 * reads the stress), the least-squares wall and refinement levels are refused, and so are the
 * grid and hybrid pressures (fluid_gridp.c: their nodal pressure is the whole one; auto keeps
 * the particles'). A solid's surface must face the gas or a wall: a free surface elsewhere would
 * carry the gauge as a load. */
#include "fluid_internal.h"

#include "mpm_error.h"

#include <stdio.h>
#include <string.h>

static int refuse(const mpm_config *cfg, const char *what) {
  return mpm_config_fail(cfg, "physics.gauge_pressure",
                         "a gauge is carried by walls and periodic faces only, and this scene "
                         "has %s: remove the key",
                         what);
}

int fluid_gauge_check(const mpm_module *m, const mpm_config *cfg) {
  const fluid_content *fc = m->content;
  if (fc->gas.gauge == 0.0) return 0;
  static const char *const side[2] = {"lo", "hi"};
  char what[64];
  for (int d = 0; d < m->grid->dim; ++d)
    for (int k = 0; k < 2; ++k)
      if (m->open[d][k]) {
        snprintf(what, sizeof what, "an open face (boundary.%c_%s)", "xyz"[d], side[k]);
        return refuse(cfg, what);
      }
  if (fc->obs.count > 0) return refuse(cfg, "static obstacles ([obstacle.*])");
  const char *wall;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.wall_treatment", &wall));
  if (strcmp(wall, "least_squares") == 0)
    return refuse(cfg, "fluid.wall_treatment = least_squares");
  int levels = 1;
  if (mpm_config_has(cfg, "refine.levels"))
    MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &levels));
  if (levels > 1) return refuse(cfg, "refinement levels (refine.levels)");
  return 0;
}
