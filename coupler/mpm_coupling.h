/* Spatial coupling schemes: what happens on the nodes where the solid and the gas both have
 * mass, between the modules' forces and their constraints (see mpm_cycle.h). An object with an
 * ops table, registered by name (mpm_coupling_register.c) and chosen with
 * `[coupling] scheme = NAME`: a new scheme is one file that exports its type plus one line in
 * the register. The modules never see each other; only a scheme touches both phases.
 *
 * Hooks, in the order the cycle calls them, once per grid pass (pass tells which: the first
 * transfer, or MUSL's remap where no force acts):
 *   before_solve     the phases' m_i, mv_i, f_i (and normal_i, if asked) are summed over the
 *                    ranks (optional);
 *   after_solve      v_i and a_i are set on every node (v = mv/m + h a, a = f/m); a scheme
 *                    may correct them where the phases meet;
 *   after_constrain  each module has applied its walls, clamps, obstacles; a scheme may
 *                    reconcile the phases there (optional).
 * Then, in the method of lines' first pass, a scheme that asks for it (MPM_COUPLING_RELAXES:
 * `velocity`, `traction`) relaxes the phases' own velocities towards each other at the shared
 * nodes. There a particle moves with the nodal velocity but keeps its own velocity as a state,
 * which takes the nodal acceleration only, so the shared velocity a scheme sets never reaches it
 * (the classic update's impulse carries it, once a step): each phase takes the force k m_s m_g /
 * (m_s + m_g) (u_other - u_own), u the phases' deposited velocities mv / m, k = relax_rate, in
 * every component no constraint set after the solve (along the normal alone where the scheme ties
 * the phases along it, relax_normal). Every hook acts on all box nodes (owners hold the summed
 * values; ghosts are overwritten by the forward halo that follows, so what a scheme writes there
 * does not matter).
 *
 * The balance. Whatever a scheme changes goes through mpm_coupling_exchange(), an impulse in
 * the classic update (common/mpm_impulse.h, as the gas's static obstacles apply theirs), which
 * records per phase, on the nodes this rank owns, the momentum rate the interface gives that
 * phase, F = sum m (a' - a), and the energy rate it puts into the phase as the gas's energy
 * balance counts its forces' work (time-centred in the classic update; in the method of lines
 * the work on v plus the internal forces' work on the kinematic correction v - v').
 * F_solid + F_fluid = 0 to roundoff for every scheme; P_solid + P_fluid is the energy the
 * coupling creates (> 0) or destroys. The gas's total energy changes by exactly its P (with
 * walls and without other forces); a solid's only up to its own transfer's error (FLIP does not
 * conserve energy). The changes of MUSL's remap pass are not recorded: no force acts there. */
#ifndef MPM_COUPLING_H
#define MPM_COUPLING_H

#include "mpm_config.h"
#include "mpm_hier.h"
#include "mpm_impulse.h"
#include "mpm_interface.h"
#include "mpm_module.h"

typedef struct mpm_coupling mpm_coupling;

/* What a scheme needs: the solid's mass gradient deposited (for interface normals); the gas held
 * to the solid's constraints (after the modules' constraints, in every component of the velocity
 * that the solid's own constraint changed at a shared node, the gas takes the solid's: all of
 * them at a clamp or a rigid body, the normal one at a solid's slip wall, where the gas's own
 * wall holds the same; mpm_coupling_follow_solid). `traction`, which holds the gas along the normal
 * alone, needs the latter: at a clamped root on a wall the solid's normal points into the wall, and
 * the gas slid through the root along it. `contact` does not take it: on the main job at 2 mm it
 * trapped gas in the clamped root, where its step fell to 5e-9 s by 2.5 ms (43 000 steps, against
 * 30 188 for the whole run without it). MPM_COUPLING_RATE: the scheme reads relax_rate (the key
 * coupling.mol_rate, in its keys) and relaxes the phases itself, not at every shared node
 * (`sharp`, at its interface points). */
enum {
  MPM_COUPLING_NORMALS = 1,
  MPM_COUPLING_HOLDS = 2,
  MPM_COUPLING_RELAXES = 4,
  MPM_COUPLING_RATE = 8
};

typedef struct mpm_coupling_ops {
  /* Read the scheme's own keys, allocate its content. Optional. */
  int (*create)(mpm_coupling *c, const mpm_config *cfg);
  /* The grid and the phases by role are known. Optional. */
  int (*setup)(mpm_coupling *c);
  int (*before_solve)(mpm_coupling *c, double t, double h, mpm_pass pass);
  int (*after_solve)(mpm_coupling *c, double t, double h, mpm_pass pass);
  int (*after_constrain)(mpm_coupling *c, double t, double h, mpm_pass pass);
  /* MPM_COUPLING_RELAXES: 1 and the unit normal n where the scheme ties the phases at shared
   * node l along n alone (the relaxation then acts along n), 0 where it ties every component.
   * Optional (NULL: every component everywhere). */
  int (*relax_normal)(const mpm_coupling *c, mpm_lidx l, double *n);
  void (*destroy)(mpm_coupling *c);
} mpm_coupling_ops;

/* The key of the method of lines' relaxation (MPM_COUPLING_RELAXES), which each scheme that
 * relaxes lists among its keys (declared once in the schema). In units of the slowest module's
 * signal rate (its fastest sound speed plus |v| over the cell size): no step is longer than
 * time.cfl times its inverse, so h k stays below 2 time.cfl, inside bs32's real stability interval
 * (-2.5, 0) for time.cfl < 1.25, as the gas's wall rate argues (fluid/fluid_transfer.c). The
 * default is as fast as that allows, so that the phases' velocities meet within a few steps: at 1
 * the Mach 2 face of test_multirate_face_mri read 1.9 % below u* under MRIStep at time.cfl = 0.4,
 * at 2 0.6 % (58 % above without it). */
#define MPM_COUPLING_MOL_RATE_KEY(schemes)                                                         \
  {                                                                                                \
    "coupling.mol_rate", MPM_KEY_REAL, "2", 0, 2, 0, 0, NULL,                                      \
        schemes                                                                                    \
        ", ERK pairs: the rate at which the phases' own velocities relax towards each other "      \
        "at the shared nodes (sharp: along the normal at its interface points), in units of "      \
        "the slowest module's signal rate (its fastest sound "                                     \
        "speed plus |v| over the cell size); the method of lines moves a particle with the "       \
        "shared nodal velocity but gives its own velocity only the nodal acceleration (0: off; "   \
        "the classic update's impulse does this once a step and ignores the key)",                 \
        0, "-"                                                                                     \
  }

typedef struct mpm_coupling_type {
  const char *name;
  const char *help;         /* one line for the key's documentation */
  unsigned needs;           /* MPM_COUPLING_* flags */
  const mpm_key_spec *keys; /* the scheme's own [coupling] keys (may be NULL) */
  int nkeys;
  const mpm_coupling_ops *ops;
} mpm_coupling_type;

/* Bodies whose interface force is reported one by one (a solid of more bodies reports the
 * resultant only). */
#define MPM_COUPLING_MAX_BODIES 16

/* The interface record of one RHS evaluation on this rank (first pass only). */
typedef struct mpm_coupling_record {
  double force[MPM_ROLE_COUNT][MPM_MAX_DIM];         /* momentum rate into each phase, N */
  double power[MPM_ROLE_COUNT];                      /* its power on that phase's nodes, W */
  double gas_inside;                                 /* gas mass on nodes inside the solid, kg */
  double body[MPM_COUPLING_MAX_BODIES][MPM_MAX_DIM]; /* the solid's force per body, N */
  double owed[MPM_MAX_DIM]; /* a staggered scheme: momentum the gas gave up at the interface
                               that the solid has yet to receive, N s (mpm_interface.h) */
} mpm_coupling_record;

struct mpm_coupling {
  const mpm_coupling_type *type;
  void *content;
  mpm_grid *grid;
  mpm_module *module[MPM_ROLE_COUNT]; /* by role; NULL if absent */
  int phase[MPM_ROLE_COUNT];          /* their grid phases */
  unsigned char *owned;               /* per box node: counted in the balance */
  mpm_coupling_record rec[2];         /* the latest RHS and the one before (mpm_impulse.h) */
  mpm_rhs_records which;              /* their times and which is the latest */
  int recording;                      /* inside a first pass: exchanges are recorded */
  int hand_over; /* the gas's forces where it has no mass and the solid has go to the solid
                    (set by the sim: fluid_module_hands_over; mpm_coupling.c, hand_over) */
  int nbodies;   /* solid bodies reported one by one (0: one body, or more than
                    MPM_COUPLING_MAX_BODIES: the resultant only) */
  const char *body_name[MPM_COUPLING_MAX_BODIES];
  double *da[MPM_MAX_DIM]; /* with nbodies: the solid's interface acceleration per node */
  double *held_v[MPM_MAX_DIM], *held_a[MPM_MAX_DIM]; /* MPM_COUPLING_HOLDS: the solid's v and a
                                                        as after_solve left them */
  unsigned char *wall_axes; /* MPM_COUPLING_NORMALS: per box node, bit d set where the node lies
                               on a wall face across axis d (slip, no_slip) */
  mpm_interface *capture;   /* non-NULL: what the solid is given goes there instead (held) */
  double relax_share;       /* MPM_COUPLING_RELAXES or _RATE: k in units of the signal rate
                             * (coupling.mol_rate) */
  double relax_rate;        /* k, 1/s (0: none); set before each RHS by the integrator
                               (coupler/mpm_integrator.c) */
  /* On a refinement hierarchy (mpm_coupling_set_hier; 0 levels: the grid alone): every hook and
   * the interpenetration run on each level in turn, grid and owned set to the level's, so that a
   * scheme acts on the active nodes of every level (coupler/mpm_coupling_levels.c). */
  int nlev;
  mpm_grid *lev_grid[MPM_HIER_MAX_LEVELS];
  unsigned char *lev_owned[MPM_HIER_MAX_LEVELS];     /* level 0: owned; finer: active, not images */
  unsigned char *lev_wall_axes[MPM_HIER_MAX_LEVELS]; /* finer levels: 0 (no walls beside a solid)*/
  double *lev_held[MPM_HIER_MAX_LEVELS][2][MPM_MAX_DIM]; /* held_v, held_a per level */
};

/* The registered types, `none` first; count in *n. */
const mpm_coupling_type *const *mpm_coupling_types(int *n);

/* coupling.scheme and every registered scheme's keys. */
int mpm_coupling_add_schema(mpm_config *cfg);

/* Build the scheme the case names for these modules. With fewer than two phases (or scheme
 * = none) *c is NULL: no coupler work at all; a coupling key in a one-phase scene, a key of
 * another scheme, or a scheme the scene cannot use is an input error. Collective. */
int mpm_coupling_new(mpm_coupling **c, const mpm_config *cfg, mpm_grid *grid, mpm_module **modules,
                     int nmodules);
void mpm_coupling_destroy(mpm_coupling **c);

/* Put the scheme on the levels of hierarchy h (the modules' own, mpm_refine.h; NULL: the grid
 * alone), between the restriction and the prolongation: after the nodal solve of every level the
 * scheme acts on the active nodes of each level in turn, where both phases' composite masses sit
 * (restricted onto them), and the prolongation then hands both phases the same velocity wherever
 * their composite weights meet only shared nodes. The exchanges are per node, so the balance of
 * coupling.csv holds summed over every level's active nodes; a scheme's per-node state (the
 * walls' axes, the held velocities) is kept per level too. Refuses (MPM_ERR_INPUT, naming the
 * key) what is not carried: several bodies reported one by one, and traction's least-squares
 * wall (coupler/mpm_coupling_levels.c). A no-op for a NULL c. */
int mpm_coupling_set_hier(mpm_coupling *c, const mpm_config *cfg, const mpm_hier *h);
/* Free what mpm_coupling_set_hier allocated (mpm_coupling_destroy). */
void mpm_coupling_levels_free(mpm_coupling *c);
/* Run fn once per level (the grid alone without a hierarchy), with c->grid, c->owned and the
 * per-node state set to the level's; stops at the first error. */
typedef int (*mpm_coupling_level_fn)(mpm_coupling *c, double t, double h, mpm_pass pass);
int mpm_coupling_each_level(mpm_coupling *c, mpm_coupling_level_fn fn, double t, double h,
                            mpm_pass pass);

/* The hooks, each a no-op for NULL or an op the scheme leaves out; timed as coupling. */
int mpm_coupling_before_solve(mpm_coupling *c, double t, double h, mpm_pass pass);
int mpm_coupling_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass);
int mpm_coupling_after_constrain(mpm_coupling *c, double t, double h, mpm_pass pass);
/* The latest record's gas_inside, from the phases' nodal masses as they stand (the
 * after_constrain hook's first pass does it; a follow cycle, which runs no hooks, calls it). */
void mpm_coupling_record_inside(mpm_coupling *c);

/* A staggered scheme's load (mpm_interface.h): after the solid's solve, accelerate the solid
 * wherever it has mass by load (N per box node, dim arrays) over the larger of its nodal mass
 * and m_start (the light-node rule of mpm_interface.h), as an exchange (recorded as the
 * interface force on the solid: load m / max(m, m_start); in the classic update as the
 * impulse h times that). Starts this RHS's record like before_solve. */
int mpm_coupling_apply_load(mpm_coupling *c, double t, double h, const double *const *load,
                            const double *m_start);

/* While ifc is set (the first pass of a held or loaded cycle), every exchange into the solid and
 * every force recorded for it is also added to ifc->capture: what the gas gave the held solid,
 * or what the load gave the solid. NULL ends it.
 * A no-op for a NULL c. */
static inline void mpm_coupling_capture(mpm_coupling *c, mpm_interface *ifc) {
  if (c) c->capture = ifc;
}

/* After the first grid pass (forward halo done): split the solid's interface force of this RHS
 * over its bodies, from the solid's state block y_solid. A no-op with one body. Collective. */
int mpm_coupling_body_loads(mpm_coupling *c, const double *y_solid);

/* ---- for the schemes ---------------------------------------------------------------------- */

/* Set phase `role`'s v_i and a_i at box node l to v and a (dim values each; a NULL a keeps the
 * acceleration in the method of lines), recording the exchange (see the balance above). h: the
 * classic step (0: method of lines). In the classic update the acceleration takes the velocity
 * change as an impulse, a' = a + (v' - v) / h, whatever a is given, so FLIP and PIC particles see
 * the same change. */
void mpm_coupling_exchange(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *v,
                           const double *a, double h);
/* The same, and the force the phase received there in f (dim values). */
void mpm_coupling_exchange_force(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *v,
                                 const double *a, double h, double *f);

/* After the modules' constraints: the gas takes the solid's velocity and acceleration at shared
 * node l in the components whose bit is set in `axes` (bit d: component d; MPM_ALL_AXES: all),
 * as an external constraint (the shared field obeys the solid's constraint there), and the
 * solid's constraint takes the reaction, recorded as the gas's force on the solid. Does nothing
 * where they agree. */
#define MPM_ALL_AXES ((1u << MPM_MAX_DIM) - 1)
void mpm_coupling_follow_solid(mpm_coupling *c, mpm_lidx l, double h, unsigned axes);

/* coupling.exchange = shared (mpm_interface.h, the shared nodes), in a loaded RHS after
 * mpm_coupling_apply_load: every node where the gas had mass at the coupling step's start (m_gas,
 * f_gas, its nodal mass and force then; v_gas, the node's velocity as the last accepted substep
 * left it) advances as a shared node, v = (m_s v_s + m_gas v_gas + h f_gas) / (m_s + m_gas),
 * the solid's part as an exchange (recorded, captured as delivered), written to v_out; where the
 * solid has no mass, v_out = v_gas + h f_gas / m_gas. touched[l] = 1 where the solid had mass. */
void mpm_coupling_apply_shared(mpm_coupling *c, double h, const double *m_gas,
                               const double *const *f_gas, const double *const *v_gas,
                               double *const *v_out, unsigned char *touched);
/* A loaded RHS (classic update), after the solid's constraints: on every owned node and
 * component where a constraint changed the velocity the exchanges (the load, the shared nodes)
 * left (ifc->v_solved), the constraint took their impulse, and their power on the solid is booked
 * time-centred at the velocity it left, force (v^n + v) / 2, in place of what they booked
 * (ifc->booked), as the solid's wall books an impulse a constraint takes (mpm_solid_wall.c).
 * The force stays the interface's: the balance is unchanged (mpm_interface.h, constraints). */
void mpm_coupling_book_constrained(mpm_coupling *c, const mpm_interface *ifc, double h);
/* The gas's half of the same, in its step over the coupling step t -> t + h (a follow RHS): the
 * gas takes velocity v at every node marked in touched where it has mass, as an exchange, and
 * what it gives up there is captured for the solid. Starts this RHS's record. */
void mpm_coupling_follow_shared(mpm_coupling *c, double t, double h, const double *const *v,
                                const unsigned char *touched);

/* Record, without changing any field, that phase role received force f (dim values) at node l
 * and moves there with velocity v: the reaction a constraint takes for a phase (a clamped or
 * rigid solid holding the gas) counts as interface force. */
void mpm_coupling_record_force(mpm_coupling *c, mpm_role role, mpm_lidx l, const double *f,
                               const double *v);

/* Is there mass of phase role at node l (as the last nodal solve decided)? */
static inline int mpm_coupling_has_mass(const mpm_coupling *c, mpm_role role, mpm_lidx l) {
  const mpm_grid_phase *ph = &c->grid->phase[c->phase[role]];
  return ph->m_i[l] > ph->m_empty;
}

/* Do both phases have mass at node l? */
static inline int mpm_coupling_shared(const mpm_coupling *c, mpm_lidx l) {
  return mpm_coupling_has_mass(c, MPM_ROLE_SOLID, l) && mpm_coupling_has_mass(c, MPM_ROLE_FLUID, l);
}

/* The phase of role r. */
static inline mpm_grid_phase *mpm_coupling_phase(const mpm_coupling *c, mpm_role r) {
  return &c->grid->phase[c->phase[r]];
}

/* The unit outward normal of the solid at node l from its deposited mass gradient, or 0 if
 * the gradient vanishes there. */
int mpm_coupling_solid_normal(const mpm_coupling *c, mpm_lidx l, double *n);

/* The same, but 0 also where the normal is not resolved: |grad m_s| dx < kappa m_s, a node
 * inside the solid (for a straight face the nodes on it give 1.5 with the quadratic B-spline and
 * two particles per cell, the nodes a cell or more inside 0.1-0.5). And on a domain wall (slip,
 * no_slip) the gradient's component across the wall is dropped first: a solid that meets a wall
 * (a bar standing on the floor) is cut off there by the wall, not by a surface the gas can
 * reach, and that component pointed the normal into the wall, so that `traction`, holding the
 * gas along the normal, let it slide along the wall into the bar's root. (`contact` keeps the
 * plain normal: with the wall rule its main-job figures at 4 mm moved, 6 836 steps against
 * 7 173 and the tip at 1.5 ms 7.47 against 7.38 mm, and it was not re-measured at 3 and 2 mm.) */
int mpm_coupling_solid_surface(const mpm_coupling *c, mpm_lidx l, double kappa, double *n);

/* ---- the interface report (coupling.csv) --------------------------------------------------- */

/* After an accepted step from t - h to t: reduce the record of the RHS that made the step and
 * return, summed over the ranks, the momentum rate into the solid and the fluid (dim each), the
 * power on each side and the interpenetration. Collective; a NULL c gives zeros. */
int mpm_coupling_step_record(mpm_coupling *c, double t, mpm_coupling_record *out);

#endif
