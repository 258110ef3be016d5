/* The blow-up guard (see mpm_guard.h). */
#include "mpm_guard.h"

#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>

const mpm_key_spec mpm_guard_keys[] = {
    {"time.collapse_ratio", MPM_KEY_REAL, "1e-3", 0, 1, 0, 0, NULL,
     "blow-up guard: stop when the step stays below this fraction of the starting state's CFL "
     "step for time.collapse_steps steps in a row (0: never)",
     0, "-"},
    {"time.collapse_steps", MPM_KEY_INT, "100", 1, HUGE_VAL, 0, 0, NULL,
     "blow-up guard: how many steps in a row the step must stay collapsed", 0, "-"},
    {"time.energy_growth", MPM_KEY_REAL, "1000", 0, HUGE_VAL, 0, 0, NULL,
     "blow-up guard: stop when the total energy exceeds this multiple of the largest total "
     "energy of the first half of the steps taken (0: never; a non-finite energy always stops "
     "the run)",
     0, "-"},
    /* 1e-5: MPM_GUARD_KINETIC_FLOOR */
    {"time.kinetic_growth", MPM_KEY_REAL, "100", 0, HUGE_VAL, 0, 0, NULL,
     "blow-up guard: stop when the kinetic energy exceeds this multiple of the largest kinetic "
     "energy of the first half of the steps taken, or of 1e-5 of the largest total energy if "
     "that is larger (a velocity mode that grows while the total energy stays flat; 0: never)",
     0, "-"},
};
const int mpm_guard_nkeys = (int)(sizeof mpm_guard_keys / sizeof mpm_guard_keys[0]);

int mpm_guard_init(mpm_guard *g, const mpm_config *cfg, double h0, double e0, double k0) {
  mpm_guard_free(g);
  MPM_CALL(mpm_config_get_real(cfg, "time.collapse_ratio", &g->ratio));
  MPM_CALL(mpm_config_get_int(cfg, "time.collapse_steps", &g->window));
  MPM_CALL(mpm_config_get_real(cfg, "time.energy_growth", &g->growth));
  MPM_CALL(mpm_config_get_real(cfg, "time.kinetic_growth", &g->kgrowth));
  g->h0 = h0;
  g->cap = 1024;
  MPM_ALLOC(g->emax, g->cap);
  MPM_ALLOC(g->kmax, g->cap);
  g->emax[0] = fabs(e0), g->kmax[0] = k0, g->n = 1;
  return 0;
}

void mpm_guard_free(mpm_guard *g) {
  free(g->emax);
  free(g->kmax);
  *g = (mpm_guard){0};
}

/* Room for one more step of history. */
static int grow_history(mpm_guard *g) {
  if (g->n < g->cap) return 0;
  const size_t cap = (size_t)(2 * g->cap);
  double *e = realloc(g->emax, sizeof *e * cap);
  if (e) g->emax = e;
  double *k = e ? realloc(g->kmax, sizeof *k * cap) : NULL;
  if (!k) MPM_FAIL(MPM_ERR_MEMORY, "blow-up guard: %ld steps of history", g->n);
  g->kmax = k, g->cap *= 2;
  return 0;
}

/* The steps before an energy test may fire (a start from rest grows fast at first). */
#define GUARD_MIN_STEPS 20

int mpm_guard_check(mpm_guard *g, double t, long step, double h, int cut_short, double energy,
                    double kinetic) {
  /* Whatever the thresholds: a step of zero length repeats forever. */
  if (!(h > 0))
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run stopped at t = %.17g (step %ld): its step (%.3g s) no longer advances the "
             "time, which a double resolves to %.3g s there, so the run could never end; the "
             "step has collapsed (lower time.cfl, refine grid.dx) or the time is too large "
             "for it",
             t, step, h, nextafter(t, HUGE_VAL) - t);
  if (!isfinite(energy))
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g (step %ld): the total energy is %g; lower time.cfl, "
             "refine grid.dx, or try another time.method",
             t, step, energy);
  MPM_CALL(grow_history(g));
  g->emax[g->n] = fmax(g->emax[g->n - 1], fabs(energy));
  g->kmax[g->n] = fmax(g->kmax[g->n - 1], kinetic);
  const double half = g->emax[g->n / 2];
  const double khalf = g->kmax[g->n / 2], kfloor = MPM_GUARD_KINETIC_FLOOR * g->emax[g->n];
  g->n++;
  if (g->growth > 0 && g->n > GUARD_MIN_STEPS && fabs(energy) > g->growth * half)
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g (step %ld): the total energy %.6g J is more than "
             "time.energy_growth = %g times the largest of the first half of the steps "
             "(%.6g J): it grows geometrically; lower time.cfl, refine grid.dx, or try another "
             "time.method (raise time.energy_growth only if energy really enters the scene "
             "that fast)",
             t, step, energy, g->growth, half);
  if (g->kgrowth > 0 && g->n > GUARD_MIN_STEPS && kinetic > g->kgrowth * fmax(khalf, kfloor))
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g (step %ld): the kinetic energy %.6g J is more than "
             "time.kinetic_growth = %g times %.6g J, the largest of the first half of the "
             "steps (or %g of the largest total energy %.6g J, if larger): a velocity mode "
             "grows geometrically while the total energy (%.6g J) does not show it; a gas under "
             "its particles' pressure grows a grid-scale mode, which fluid.pressure = hybrid or "
             "a PIC share (fluid.pic_fraction, usl and musl) removes; else lower time.cfl or "
             "try another time.method (raise time.kinetic_growth only if kinetic energy really "
             "enters the scene that fast)",
             t, step, kinetic, g->kgrowth, fmax(khalf, kfloor), MPM_GUARD_KINETIC_FLOOR,
             g->emax[g->n - 1], energy);
  if (g->ratio <= 0 || g->h0 <= 0 || cut_short) return 0;
  g->low = h < g->ratio * g->h0 ? g->low + 1 : 0;
  if (g->low >= g->window)
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the run blew up at t = %.6g (step %ld): for %d steps in a row the step (now "
             "%.3g s) stayed below time.collapse_ratio = %g of the starting CFL step %.3g s; "
             "lower time.cfl, refine grid.dx, enable fluid.regularise_every for gas expanding "
             "into near vacuum, or try another time.method",
             t, step, g->low, h, g->ratio, g->h0);
  return 0;
}
