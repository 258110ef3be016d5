/* The MPM cycle: one right-hand side of the coupled modules, the algorithm on one screen.
 *
 *   for each module: zero its phase, p2g
 *   grid pass (first):  halo reverse -> forces -> coupling before_solve -> solve
 *                       -> coupling after_solve -> constrain -> coupling after_constrain
 *                       -> halo forward
 *   MUSL only:          remap -> grid pass (remap)
 *   for each module: g2p
 *
 * The solve is the coupler's: v_i = mv_i / m_i + h a_i, a_i = f_i / m_i on every phase
 * (mpm_grid_phase_update); each module completes its forces before it and constrains its
 * nodes after it, and the coupling scheme acts between. A time scheme calls the cycle with the
 * state blocks of the modules it advances. */
#ifndef MPM_CYCLE_H
#define MPM_CYCLE_H

#include "mpm_coupling.h"
#include "mpm_module.h"

typedef struct mpm_cycle {
  mpm_grid *grid;
  mpm_module **mod;
  int nmod;
  mpm_coupling *coupling; /* NULL: the modules do not interact */
  int musl;               /* run MUSL's second transfer */
} mpm_cycle;

/* One RHS at (t, y): y[k] and ydot[k] are module k's state blocks; h is the classic step (0:
 * method of lines). */
int mpm_cycle_rhs(const mpm_cycle *c, double t, double *const *y, double *const *ydot, double h);

#endif
