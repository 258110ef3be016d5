/* A physics module (solid, fluid): an object with an ops table, in the SUNDIALS N_Vector
 * shape. A module owns its particles and a phase of nodal fields on the shared grid, and
 * exposes the phases of an MPM right-hand side; the coupler decides their order and owns the
 * nodal solve between a module's forces and its constraints (coupler/mpm_cycle.c):
 *
 *   zero grid phase -> p2g [-> velocity preview -> p2g_rate] -> halo reverse -> forces
 *   -> [coupling: before_solve] -> solve
 *   -> [coupling: after_solve] -> constrain -> [coupling: after_constrain] -> halo forward
 *   -> [MUSL: remap -> the same grid pass with pass = MPM_PASS_REMAP] -> g2p
 *
 * A module knows nothing of the other modules: what the phases exchange on shared nodes is
 * the coupling scheme's business. It announces what it is through its role.
 *
 * y and ydot are the module's block of the ODE state, laid out like the state fields of its
 * particle set (component-major, stride n). h is the step size of the classic MPM update
 * (the grid velocity is advanced by h before G2P) and 0 for a method-of-lines RHS. */
#ifndef MPM_MODULE_H
#define MPM_MODULE_H

#include "mpm_config.h"
#include "mpm_grid.h"
#include "mpm_particles.h"
#include "mpm_wall.h"

/* What went wrong with a particle, for recoverable RHS errors and the final message. */
typedef struct mpm_fault {
  int set;
  mpm_gidx id;
  double x[MPM_MAX_DIM];
  char cause[256];
  /* What to change, when the cause knows better than the generic advice (which a retry with a
   * smaller step would follow); "" for the generic advice. Bytes, as the ranks share faults. */
  char advice[240];
} mpm_fault;

/* Local sums over a module's particles, reduced by the caller. */
typedef struct mpm_module_sums {
  double mass, momentum[MPM_MAX_DIM], kinetic, internal;
} mpm_module_sums;

typedef struct mpm_module mpm_module;
struct mpm_hier;

/* A module's particles as another module's integrals read them (the gas's grid pressure beside
 * a solid, fluid/fluid_gridp_solid.c): n positions (component d at x[d]) and current volumes V,
 * as the module's last p2g left them. The arrays belong to the module and may move at its next
 * p2g; the view's address does not. */
typedef struct mpm_points {
  mpm_lidx n;
  const double *x[MPM_MAX_DIM];
  const double *V;
} mpm_points;

/* Which transfer a grid pass follows: the first (particles with their stress, gravity and
 * external forces) or MUSL's remap (mass and momentum only, after the first solve: no force
 * acts, the solve just turns momenta into velocities). */
typedef enum { MPM_PASS_FIRST, MPM_PASS_REMAP } mpm_pass;

/* What a module models, so that a coupling scheme finds its phases without knowing names. */
typedef enum { MPM_ROLE_SOLID, MPM_ROLE_FLUID, MPM_ROLE_COUNT } mpm_role;

typedef struct mpm_module_ops {
  int (*p2g)(mpm_module *m, double t, const double *y);
  /* The part of the deposit that reads the nodal velocity (the gas's current strain rate, for
   * its viscous stresses), method of lines only (h = 0: the solve's velocity m v / m does not
   * depend on the forces). After every module's p2g the coupler previews the solve on copies
   * of the deposits: the grid pass with the coupling scheme and every module's constraints
   * acting (as MUSL's remap pass: nothing is recorded), which leaves in each phase's v_i, ghosts
   * included, the velocity the solve will give; this op then adds to the deposit. Optional. */
  int (*p2g_rate)(mpm_module *m, double t, const double *y);
  /* After the reverse halo: complete this phase's nodal forces (fold mirrored pad nodes into
   * walls, damping, ghost and boundary forces). h is the classic step (0: method of lines). */
  int (*forces)(mpm_module *m, double t, double h, mpm_pass pass);
  /* After the nodal solve (mpm_grid_phase_update): the kinematic constraints of this phase
   * (walls, clamps, rigid bodies, obstacles, open faces), on v_i and a_i. */
  int (*constrain)(mpm_module *m, double t, double h, mpm_pass pass);
  int (*g2p)(mpm_module *m, double t, const double *y, double *ydot, double h);
  /* Largest stable step on this rank (before the CFL factor). */
  double (*stable_dt)(const mpm_module *m, const double *y);
  /* The fastest signal on this rank at state y, m/s: the largest sound speed plus |v| of a
   * particle, from y alone (no viscous share, nothing kept between calls), so that a rate the
   * RHS scales by it stays a function of the state. Optional. */
  double (*signal_speed)(const mpm_module *m, const double *y);
  /* Local check of a state: fills *fault and returns 1 if it is unphysical. */
  int (*check)(const mpm_module *m, const double *y, mpm_fault *fault);
  void (*sums)(const mpm_module *m, mpm_module_sums *s);
  /* Between accepted steps, before migration: particles leave through outflow faces and
   * enter through inflow faces. t is the time reached and h the step just taken. Sets
   * *changed to 1 if the particle set changed (count or order). The migration always follows,
   * so the op may leave its edit to it (mpm_particles_edit_deferred). Optional. */
  int (*boundary)(mpm_module *m, double t, double h, int *changed);
  /* After an accepted step and migration (history updates, regularisation, reports); every
   * particle sits on the rank that owns its cell. Same arguments as boundary. Optional. */
  int (*post_step)(mpm_module *m, double t, double h, int *changed);
  void (*destroy)(mpm_module *m);
  /* MUSL's second transfer, after the first grid pass and forward halo: compute the
   * particles' new velocities, zero this phase and deposit their mass and momentum again.
   * The coupler then runs the grid pass with MPM_PASS_REMAP, which turns the new momenta
   * into the nodal velocities (no force, no damping: the force acted in the first pass)
   * before g2p. Optional: NULL if the module has no MUSL. */
  int (*remap)(mpm_module *m, double t, const double *y, double h);
  /* Space this module keeps to itself for another module's particles (the gas's static
   * obstacles): the case-file key of the region containing x, or NULL. Optional. */
  const char *(*reserved)(const mpm_module *m, const double *x);
  /* The bodies of a module made of several (a solid's [solid.NAME] sections): their count, and
   * the name of body b in names[b] (pointers into the module) for b < max. Optional. */
  int (*bodies)(const mpm_module *m, const char **names, int max);
  /* The resultant of a nodal acceleration field a_i (valid on every box node) on each body,
   * F[b MPM_MAX_DIM + d] = sum over the body's particles of m_p sum_i S_ip a_i[d], at the positions
   * in y; this RHS's P2G has run. Optional; with bodies. */
  int (*body_loads)(mpm_module *m, const double *y, const double *const *a_i, double *F);
  /* Refresh fields derived for output only (a gas's pressure, Mach number, ...) before a
   * snapshot or checkpoint is written. Optional. */
  int (*output)(mpm_module *m);
  /* Take a moving wall that a coupling scheme offers in another module's place (mpm_wall.h; the
   * table must outlive the module): *taken = 1 if the module uses it, 0 if not. After the
   * coupling is built the sim calls it once more with src = NULL: a module that needs a wall
   * and was given none fails there with an input error. Optional. */
  int (*attach_wall)(mpm_module *m, const mpm_config *cfg, const mpm_wall_source *src, int *taken);
  /* The view of this module's particles that its p2g refreshes (mpm_points), for the sim to
   * hand to another module (beside, below). Optional. */
  const mpm_points *(*points)(mpm_module *m);
} mpm_module_ops;

struct mpm_module {
  char name[32];
  const mpm_module_ops *ops;
  mpm_role role;
  void *content;
  mpm_particles *particles;
  mpm_grid *grid;
  int phase; /* index of this module's nodal fields on grid */
  /* Faces [axis][lo, hi] a particle may cross during a step: the module removes it between
   * steps (the gas's open faces). Elsewhere a particle outside the domain is a fault. */
  unsigned char open[MPM_MAX_DIM][2];
  /* How far (in cells) a particle may lie beyond a closed (wall) face at the end of a stage
   * without a fault; the module's boundary op returns it between steps (the gas, whose
   * particles are pressed into the corners of walls and bodies; 0 elsewhere). */
  double wall_slack;
  /* This module's own stability limit (dx / (c + |v|) or its estimate, before time.cfl), the
   * minimum over the ranks, as the integrator last estimated it (at the start of each step of
   * the classic update); 0 until then or without a limit. A module whose per-step operations
   * stand for a rate (the gas's PIC share) scales them by h over a fixed fraction of it, so
   * that another module setting a smaller step (a stiff solid under monolithic coupling), a
   * retry, a step cut short at an output time or another time.cfl changes what they do per
   * unit time by nothing. */
  double h_limit;
  long step; /* accepted steps of the run (a restart continues the count); set by the sim
              * before boundary and post_step */
  /* > 0: post_step at the steps that are multiples of this reads the cell occupancy of every
   * phase (mpm_cells.h), which the sim counts after every module's migration. */
  int cells_every;
  /* The RHS reads what post_step commits (a lagged strain rate, a plastic history), so a
   * step's last stage is stale once the step is accepted: the integrator's fixed steps start
   * from a fresh first stage instead of reusing it (mpm_integrator.c). */
  int commits_history;
  /* The static refinement hierarchy over grid this module's phase lives on (mpm_hier.h), set
   * by the sim after the modules are built; NULL without refinement. The coupler then zeroes,
   * restricts, solves and prolongs the phase on every level (coupler/mpm_cycle.c). */
  struct mpm_hier *hier;
  /* Another module's particles, set by the sim when both are built (the solid's points beside a
   * gas; their p2g runs before this module's forces in every cycle); NULL if none. */
  const mpm_points *beside;
};

/* Call ops->destroy and free the module; accepts NULL. */
void mpm_module_destroy(mpm_module **m);

/* Nodal update of one phase on every box node: v = mv/m, a = f/m, then v += h a; nodes
 * with m below a tiny fraction of the largest nodal mass of the whole grid get v = a = 0.
 * Collective (the largest mass is reduced over the ranks, so the result does not depend on
 * the decomposition). */
int mpm_grid_phase_update(mpm_grid *grid, int phase, double h);
/* The same update on ngrids grids at once, as if their nodes were one grid's: the largest
 * nodal mass and the mean of the light rule are taken over all of them, with the empty and
 * light fractions of grids[0]'s phase; collective over grids[0]'s communicator (the others may
 * have none: box grids, whose nodes all count as owned). A refinement hierarchy's levels: the
 * light rule compares each node with the mean at its own spacing, every node's mass counted in
 * the mean as (dx_0 / dx_k)^dim times its own (a uniform gas gives every level the same). */
int mpm_grid_phase_update_many(mpm_grid *const *grids, int ngrids, int phase, double h);

/* Record a fault at particle i of p (positions from y) with a printf-style cause; returns 1. */
int mpm_fault_at(mpm_fault *fault, const mpm_particles *p, const double *y, mpm_lidx i,
                 const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* Shared particle checks: NaN in the state, a particle outside the domain (beyond a
 * non-periodic face, or more than a cell beyond an open one; beyond a periodic face it stays
 * until migration wraps it), or one that
 * has drifted more than one cell beyond this rank's cells during a step. */
int mpm_module_check_positions(const mpm_module *m, const double *y, mpm_fault *fault);

#endif
