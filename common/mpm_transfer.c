/* Shared velocity-transfer helpers (see mpm_transfer.h). */
#include "mpm_transfer.h"

#include "mpm_error.h"
#include "mpm_kernels.h"

#include <string.h>

int mpm_transfer_from_config(mpm_transfer *t, const mpm_config *cfg, const char *pic_key) {
  const char *method, *velocity;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  MPM_CALL(mpm_config_get_string(cfg, "transfer.velocity", &velocity));
  if (!pic_key || !mpm_config_has(cfg, pic_key)) pic_key = "transfer.pic_fraction";
  MPM_CALL(mpm_config_get_real(cfg, pic_key, &t->pic));
  t->musl = strcmp(method, "musl") == 0;
  t->classic = t->musl || strcmp(method, "usl") == 0;
  t->apic = strcmp(velocity, "apic") == 0;
  if (t->apic && !t->classic)
    return mpm_config_fail(cfg, "transfer.velocity",
                           "APIC replaces the particle velocity once per step of the classic "
                           "update; use time.method = usl or musl, or velocity = flip with %s",
                           method);
  if (t->apic && t->pic > 0)
    return mpm_config_fail(cfg, pic_key,
                           "APIC has no PIC fraction; set pic_fraction = 0 or velocity = flip");
  if (t->pic > 0 && !t->classic)
    return mpm_config_fail(cfg, pic_key,
                           "a PIC fraction is defined per step of the classic update; use "
                           "time.method = usl or musl, or pic_fraction = 0 with %s",
                           method);
  return 0;
}

void mpm_transfer_g2p(const mpm_grid *grid, int phase, const mpm_particles *p, const double *y,
                      double lp, double *const *v_out, double *const *a_out, double *L_out,
                      double *C_out) {
  const mpm_grid_phase *ph = &grid->phase[phase];
  mpm_g2p_args a = {.n = p->n, .lp = lp, .L_out = L_out, .C_out = C_out};
  for (int d = 0; d < p->dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[0] + d) * p->n;
    a.v_i[d] = ph->v_i[d];
    a.a_i[d] = ph->a_i[d];
    a.v_out[d] = v_out[d];
    a.a_out[d] = a_out[d];
  }
  mpm_kernels_get(p->dim)->g2p(grid, &a);
}

void mpm_transfer_blend(const mpm_particles *p, const double *y, double *ydot, double a, double h) {
  for (int d = 0; d < p->dim; ++d) {
    const double *v = y + (size_t)(p->offset[1] + d) * p->n;
    const double *xdot = ydot + (size_t)(p->offset[0] + d) * p->n;
    double *vdot = ydot + (size_t)(p->offset[1] + d) * p->n;
    for (mpm_lidx i = 0; i < p->n; ++i) vdot[i] = (1.0 - a) * vdot[i] + a / h * (xdot[i] - v[i]);
  }
}
