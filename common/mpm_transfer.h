/* The particle-grid velocity transfer shared by the MPM modules: the [transfer] settings
 * checked against the time method, the G2P call over a module's state, and the FLIP/PIC
 * (or APIC) update of the particle velocity in rate form.
 *
 * The classic update (usl, musl) advances y by h ydot with one RHS per step, so a
 * transfer that replaces the velocity by v_new is written as the rate (v_new - v) / h. The
 * method-of-lines RHS of the ERK pairs (h = 0) has no step to replace over: it takes the
 * pure FLIP rate dv/dt = sum S a_i, and the settings reject PIC fractions and APIC there. */
#ifndef MPM_TRANSFER_H
#define MPM_TRANSFER_H

#include "mpm_config.h"
#include "mpm_grid.h"
#include "mpm_particles.h"

typedef struct mpm_transfer {
  int classic; /* time.method is usl or musl */
  int musl;    /* MUSL: a second transfer before positions move (module remap op) */
  int apic;    /* transfer.velocity = apic: affine velocity C per particle (state field) */
  double pic;  /* transfer.pic_fraction: 0 FLIP ... 1 PIC */
} mpm_transfer;

/* Read time.method and the [transfer] keys; APIC or a PIC fraction without the classic
 * update, or both together, is an input error naming the key. pic_key, if given and set,
 * is a module's own PIC fraction, in place of transfer.pic_fraction. */
int mpm_transfer_from_config(mpm_transfer *t, const mpm_config *cfg, const char *pic_key);

/* G2P over a particle set whose positions are field 0 of state y: v_out = sum S v_i,
 * a_out = sum S a_i of phase, and L_out, C_out as in mpm_g2p_args (NULL: not wanted). */
void mpm_transfer_g2p(const mpm_grid *grid, int phase, const mpm_particles *p, const double *y,
                      double lp, double *const *v_out, double *const *a_out, double *L_out,
                      double *C_out);

/* The PIC share of the classic update, over vdot that holds sum S a_i on entry:
 * v_new = (1 - a)(v + h sum S a_i) + a sum S v_i^{n+1}, as the rate (v_new - v) / h; xdot
 * (field 0 of ydot) holds sum S v_i^{n+1}. a = 1 is the APIC velocity update. */
void mpm_transfer_blend(const mpm_particles *p, const double *y, double *ydot, double a, double h);

#endif
