/* Time integration of the coupled modules: the ERK pairs with ARKODE's ERKStep (or, multirate,
 * MRIStep with a fast partition of its own, mpm_integrator_new_multirate), the fixed-step
 * methods (one stage, and SSP-RK2) directly.
 *
 * The ODE state is every module's state block of its particle set. For ERKStep it is an
 * MPIManyVector with one serial subvector per module, each wrapping that block (no copy). The
 * RHS is the MPM cycle owned by the coupler: P2G of every module, reverse halo, grid update,
 * forward halo, G2P.
 *
 * Methods: the classic MPM update (USL, and MUSL with its second transfer) and forward Euler
 * are one stage, y += h f, with a fixed step set before every step from the stability limit;
 * the classic update's grid velocity is advanced by that step before G2P. SSP-RK2 is two such
 * stages of the method-of-lines RHS averaged with the start (Shu-Osher form) at the same fixed
 * step. The integrator takes these itself. The adaptive methods are embedded ERK pairs with
 * error control and the same stability limit.
 *
 * Failures: an unphysical stage (NaN, J <= 0, a particle outside the domain or too far out
 * of its box), or such a state at the end of a direct step or its stage, is seen on every rank.
 * ERKStep 6.4 cannot retry after a recoverable explicit RHS failure, so the integrator restarts
 * itself (and retries a direct step) from the last accepted state with a quarter of the step, up
 * to max_retries times for one step or until the step falls below 1e-6 of the CFL step (a barrier
 * no step size removes), and then fails with a message that names the particle, its position and
 * the cause. */
#ifndef MPM_INTEGRATOR_H
#define MPM_INTEGRATOR_H

#include "mpm_config.h"
#include "mpm_cycle.h"

typedef enum {
  MPM_METHOD_USL,         /* classic MPM update, fixed step from the CFL limit */
  MPM_METHOD_MUSL,        /* the same with MUSL's second transfer (nodal velocities from the
                             updated particle momenta) before positions and F are moved */
  MPM_METHOD_EULER,       /* forward Euler, fixed CFL step: unstable for undamped waves, for
                             stability studies */
  MPM_METHOD_RALSTON21,   /* Ralston ERK 2(1): unstable for undamped waves, for comparison */
  MPM_METHOD_BS32,        /* Bogacki-Shampine 3(2) */
  MPM_METHOD_ZONNEVELD43, /* Zonneveld 4(3) */
  MPM_METHOD_DP54,        /* Dormand-Prince 5(4) */
  MPM_METHOD_SSPRK2,      /* Shu-Osher SSP-RK2 (Heun), two stages, fixed CFL step */
  MPM_METHOD_COUNT
} mpm_method;

extern const mpm_key_spec mpm_integrator_keys[];
extern const int mpm_integrator_nkeys;

typedef struct mpm_integrator mpm_integrator;

/* An integrator of the modules of `cycle`, whose RHS is that cycle (copied; its musl flag is
 * set from time.method). The caller keeps the grid, modules, coupling and interface alive. */
int mpm_integrator_new(mpm_integrator **it, const mpm_config *cfg, const mpm_cycle *cycle);
/* A multirate integrator (ARKODE MRIStep) over the joint cycle, for the ERK pairs: module
 * fast_k of the cycle is the fast partition, its own dynamics alone (its forces and grid
 * update without the coupling), and the slow partition is the joint RHS less that, so the two
 * sum to the monolithic RHS. Both take fixed steps: the slow step is time.cfl of the other
 * modules' stability limit, the fast module substeps `substeps` times in it (0: the fewest
 * its own limit allows) with the time method's Butcher table; table is the MRI coupling
 * (an ARKODE_MRITableID). */
int mpm_integrator_new_multirate(mpm_integrator **it, const mpm_config *cfg, const mpm_cycle *cycle,
                                 int fast_k, int substeps, int table);
void mpm_integrator_destroy(mpm_integrator **it);

/* (Re)start the integration at (t, current particle state) with first step h0 (0: let
 * ARKODE choose; the direct methods take their CFL step). A fresh ERKStep instance each
 * time, so a run that passes through a checkpoint and a run restarted from it take the same
 * steps. */
int mpm_integrator_start(mpm_integrator *it, double t, double h0);

/* Take one accepted step, not past tstop. *t is the new time, *h the step taken. */
int mpm_integrator_step(mpm_integrator *it, double tstop, double *t, double *h);

/* The particle sets changed (count, order or storage): re-wrap the state. Collective. */
int mpm_integrator_resize(mpm_integrator *it, double t);

/* The fast module's substeps in one step of a multirate integrator as coupling.substeps sets
 * them; 0 when they follow the stable steps, or for any other integrator. */
int mpm_integrator_substeps(const mpm_integrator *it);

/* The CFL step of the current state: time.cfl times the modules' stability limit, 0 if
 * nothing limits it. Collective. */
int mpm_integrator_cfl_step(mpm_integrator *it, double *h);

/* Step ARKODE would try next, or the direct methods' last step (for checkpoints). */
double mpm_integrator_next_step(const mpm_integrator *it);

/* Counters since creation: steps, RHS evaluations, failed (error-test) steps, retries. */
void mpm_integrator_counts(const mpm_integrator *it, long *steps, long *rhs, long *fails,
                           long *retries);

const char *mpm_method_name(mpm_method m);

/* Is m a classic MPM update (fixed CFL step known to the RHS)? */
static inline int mpm_method_is_classic(mpm_method m) {
  return m == MPM_METHOD_USL || m == MPM_METHOD_MUSL;
}

/* Does the integrator take m's steps itself (fixed CFL steps, no ERKStep)? */
static inline int mpm_method_is_direct(mpm_method m) {
  return mpm_method_is_classic(m) || m == MPM_METHOD_EULER || m == MPM_METHOD_SSPRK2;
}

#endif
