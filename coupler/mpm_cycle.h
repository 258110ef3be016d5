/* The MPM cycle: one right-hand side of the coupled modules, the algorithm on one screen.
 *
 *   for each module: zero its phase, p2g
 *   [a module with p2g_rate: the grid pass (remap, h = 0) on copies of the deposits, then
 *    p2g_rate, which reads the velocity it leaves (mpm_module.h)]
 *   grid pass (first):  halo reverse -> forces -> [held: restore] -> coupling before_solve
 *                       -> solve -> coupling after_solve (or, loaded: the load) -> constrain
 *                       -> coupling after_constrain -> halo forward
 *   MUSL only:          remap -> grid pass (remap)
 *   for each module: g2p
 *
 * The solve is the coupler's: v_i = mv_i / m_i + h a_i, a_i = f_i / m_i on every phase
 * (mpm_grid_phase_update); each module completes its forces before it and constrains its
 * nodes after it, and the coupling scheme acts between.
 *
 * A module on a refinement hierarchy (mpm_module.h, hier; a gas or a solid alone, one rank) has its
 * phase zeroed on every level, deposits composite (mpm_hier_p2g), and the coupler restricts
 * the deposits onto the active nodes before the reverse halo (again after p2g_rate, which
 * deposits more), solves on every level (mpm_hier_phase_update) and prolongs v and a after the
 * forward halo; forces and constraints act on level 0, and the module's G2P reads every level
 * (mpm_hier_g2p). The preview's copies are level 0's: the grid pass writes only v and a on the
 * finer levels. Without a hierarchy each of these costs one pointer test per module and call.
 *
 * A time scheme calls the cycle with the state blocks of the modules it advances, in one of
 * three modes (mpm_timescheme.h):
 *   joint   every module advances and the spatial scheme acts on all of them (monolithic);
 *   held    the modules advance against a partner held at its last deposit (mpm_interface.h):
 *           its nodal fields are restored before the solve and it is solved and constrained
 *           with them, the spatial scheme acts as in a joint cycle, and what it gives the held
 *           partner is captured instead of applied (the partner takes no G2P);
 *   loaded  the modules advance alone, under the interface load captured from the partner's
 *           last advance (no spatial scheme hook runs); with shared nodes (mpm_interface.h)
 *           the nodes where the gas has mass also advance as shared nodes;
 *   follow  the gas advances alone and takes the velocity the solid's substeps left on the
 *           shared nodes (coupling.exchange = shared; no spatial scheme hook runs). */
#ifndef MPM_CYCLE_H
#define MPM_CYCLE_H

#include "mpm_coupling.h"
#include "mpm_interface.h"
#include "mpm_module.h"

/* Modules one cycle (and one integrator) advances at most. */
#define MPM_MAX_MODULES 4

typedef enum { MPM_CYCLE_JOINT, MPM_CYCLE_HELD, MPM_CYCLE_LOADED, MPM_CYCLE_FOLLOW } mpm_cycle_mode;

typedef struct mpm_cycle {
  mpm_grid *grid;
  mpm_module **mod; /* the modules this cycle advances */
  int nmod;
  mpm_coupling *coupling; /* NULL: the modules do not interact */
  int musl;               /* run MUSL's second transfer */
  mpm_cycle_mode mode;
  mpm_interface *iface; /* held and loaded: the interface data */
} mpm_cycle;

/* The joint cycle over these modules (every module advances, the spatial scheme acts). */
static inline mpm_cycle mpm_cycle_joint(mpm_grid *grid, mpm_module **mod, int nmod,
                                        mpm_coupling *coupling) {
  return (mpm_cycle){
      .grid = grid, .mod = mod, .nmod = nmod, .coupling = coupling, .mode = MPM_CYCLE_JOINT};
}

/* One RHS at (t, y): y[k] and ydot[k] are module k's state blocks; h is the classic step (0:
 * method of lines). */
int mpm_cycle_rhs(const mpm_cycle *c, double t, double *const *y, double *const *ydot, double h);

/* The first half of a cycle, for a module about to be held: zero its phase, P2G from y (its
 * velocity preview without the coupling), reverse halo and its forces (first pass). Its nodal
 * fields then hold what mpm_interface_hold saves. Collective. */
int mpm_cycle_deposit(const mpm_cycle *c, double t, double *const *y);

#endif
