/* The interface data of a partitioned time scheme (staggered, multirate): what the gas knows of the
 * solid, and the solid of the gas, between their exchanges. The gas advances against a held
 * solid and the solid under the load the gas left it; under multirate's `coupling.exchange =
 * shared` the solid goes first, advancing the shared nodes with the gas's mass and force beside
 * its own, and the gas then takes the velocity left there (mpm_interface_share below).
 *
 * Held fields. Before the gas advances, the solid is deposited (P2G, reverse halo, forces:
 * mpm_cycle_deposit) and its nodal mass, momentum, force and mass gradient are saved here.
 * Every gas RHS restores them before the solve, so the spatial scheme meets the solid as it was
 * at the deposit, whatever the scheme wrote into the solid's nodes during the RHS before.
 *
 * Capture. While the gas advances, what the spatial scheme gives the solid is not applied: the
 * coupling adds it to `capture` (N per node) during each RHS (mpm_coupling.h). After each
 * accepted gas step the time scheme adds h capture to `impulse`: the momentum the gas gave up at
 * the interface, node by node, owed to the solid.
 *
 * Load. Before the solid advances over a coupling step H, the owed impulse becomes its load,
 * impulse / H N per node, applied after the solve of every solid RHS over that step
 * (mpm_coupling_apply_load) where the solid has mass; what a RHS applied is captured too, and an
 * accepted solid step takes h capture off the impulse. The solid receives exactly the momentum
 * the gas gave up, or it stays owed: the interface balances to roundoff, whatever the order of
 * the advances and the substeps.
 *
 * Light nodes. A node's load never accelerates it faster than it would have accelerated the
 * node's mass at the start of the advance: the load is divided by the larger of the node's mass
 * now and then (`m_start`), and what that leaves undelivered stays owed. The solid's particles
 * move during the advance, and a node at the edge of their stencils can lose nearly all its
 * mass (a B-spline weight falls quadratically to zero there): dividing the load by what is left
 * gave such a node velocities of 1e6 m/s, and through the weight's gradient, which falls only
 * linearly, strain rates that put joules into the panel in one coupling step (the shock panel,
 * multirate at time.cfl = 0.4, until 2026-11-29). With m substeps = 1 the mass never changes
 * within the advance, so the rule changes nothing there.
 *
 * What the rule withholds moves on. After the solid's advance, the momentum still owed on a node
 * whose solid mass fell during it (or is gone) moves to the node of the 3^dim block around it
 * where the solid now has the most mass (mpm_interface_rehome). Left where it was, it piled up on
 * nodes the solid had left, over many coupling steps, and came down whole on the next particle
 * whose stencil edge touched the node again: on the shock panel at 0.5 mm (multirate, the
 * wake, 2 ms) loads of 0.02-0.4 N met nodes of 1e-15 kg, velocities of 1e5-5e8 m/s, and one
 * coupling step booked 12.75 J of interface energy (the node's m v^2 / 2) and put 0.11 J into the
 * panel. Moving it by a cell keeps the momentum exact; where the solid lost no mass nothing
 * moves, so m = 1 is unchanged.
 *
 * Constraints. A loaded RHS gives the solid its load (and, with shared nodes, the exchange) after
 * the solve and before the solid's constraints; where a clamp, a wall or a rigid body then
 * overrides a component of a node's velocity, the constraint takes the impulse and the node moves
 * as it says. The exchange's power there is booked at the constrained velocity
 * (mpm_coupling_book_constrained), not at the velocity the exchange left: on the clamped slab of
 * tests/verification/test_multirate_face.py that velocity, booked substep after substep on nodes
 * the clamp holds at rest, made +0.176 J of W (31 % of the total energy, monolithic -4.0e-3 J).
 * The RHS keeps what it needs for that: the power its exchanges booked per node and component,
 * and the solid's nodal velocity and acceleration as they left it (mpm_interface_solved).
 *
 * Only owned nodes matter: a cycle acts on every box node, but the forward halo overwrites the
 * ghosts, and the balance counts owners only. Invariant: the arrays span the grid's box nodes,
 * which never change during a run. */
#ifndef MPM_INTERFACE_H
#define MPM_INTERFACE_H

#include "mpm_grid.h"
#include "mpm_particles.h"

typedef struct mpm_interface {
  mpm_grid *grid;
  int phase; /* the held phase (the solid's) */
  double *m, *mv[MPM_MAX_DIM], *f[MPM_MAX_DIM], *normal[MPM_MAX_DIM]; /* held nodal fields */
  double *capture[MPM_MAX_DIM]; /* during a held or loaded RHS: the force into the solid, N */
  double *booked[MPM_MAX_DIM];  /* ... and the power booked for it, W, per node and component */
  double *v_solved[MPM_MAX_DIM], *a_solved[MPM_MAX_DIM]; /* a loaded RHS: the solid's nodal v and
                                                            a before its constraints */
  double *impulse[MPM_MAX_DIM]; /* owed to the solid since its last load, N s per node */
  double *load[MPM_MAX_DIM];    /* the load of the solid's current advance, N per node */
  double t_mid;                 /* the midpoint of that advance, s */
  double *trend[MPM_MAX_DIM];   /* with interpolation: d load / dt, N/s per node (else NULL) */
  double *prev[MPM_MAX_DIM];    /* the load of the advance before, and its length */
  double span_prev;
  double *now[MPM_MAX_DIM];   /* load + trend (t - t_mid) for one RHS */
  double *m_start;            /* the solid's nodal mass at the first RHS of its current advance */
  double *moved[MPM_MAX_DIM]; /* scratch of mpm_interface_rehome (allocated at its first call) */
  int start_due;              /* m_start is taken at the next loaded RHS */
  /* The predictor (mpm_interface_want_predictor; else NULL): the held solid's nodal velocity
   * and mass at the hold before (vprev, mprev, at time t_prev, < 0: none yet) and the
   * acceleration predicted from them at the current hold (at t_hold), m/s^2 per node. */
  double *vprev[MPM_MAX_DIM], *mprev, *accel[MPM_MAX_DIM];
  double t_prev, t_hold;
  /* The shared nodes (mpm_interface_want_shared; else NULL): the gas's nodal mass and force at
   * the coupling step's start, the nodes' velocity as the solid's last accepted substep left
   * them (and this RHS's), and which nodes the solid reached (accepted, this RHS's). */
  double *m_gas, *f_gas[MPM_MAX_DIM], *v_gas[MPM_MAX_DIM], *v_now[MPM_MAX_DIM];
  unsigned char *touched, *touched_now;
} mpm_interface;

int mpm_interface_new(mpm_interface **ifc, mpm_grid *grid, int phase);
void mpm_interface_destroy(mpm_interface **ifc);

/* Save the held phase's m, mv, f (and mass gradient) as they are now. */
void mpm_interface_hold(mpm_interface *ifc);
/* Put them back into the held phase. */
void mpm_interface_restore(const mpm_interface *ifc);

/* The predictor (coupling.predictor = linear). A held solid is otherwise met as it was at the
 * hold, advanced over each gas step by its own nodal force at the hold (its internal force: on
 * a stiff, fast solid a quantity of its own fast time scale, which one gas step of many fast
 * ones turns into a face velocity that need not be the solid's). With the predictor the gas
 * meets the solid's nodal velocity extrapolated linearly from its last two holds: at each gas
 * RHS at t with step h the held node has momentum m (v + a (t - t_hold)) and force m a, with
 * a = (v - v_prev) / (t_hold - t_prev) - load / m, the solid's mean acceleration over its last
 * advance less what the gas's load gave it then (the spatial scheme adds the gas's exchange
 * of this step itself: left in, the load counted twice and the predictor's error on the
 * stiff piston was 5-9 times the held solid's), so that the solve gives v + a (t + h - t_hold).
 * Where the node had no solid mass at the hold before (or at the first hold) the held force stays.
 * It changes only what the gas sees: what it gives up is still captured and owed, so the
 * interface balances exactly as before. The previous hold's velocity, mass and time are state
 * (checkpointed with the rest). */
int mpm_interface_want_predictor(mpm_interface *ifc);
/* At a hold at time t (after mpm_interface_hold): the acceleration from this hold and the last,
 * and this hold becomes the last. */
void mpm_interface_predict_hold(mpm_interface *ifc, double t);
/* After mpm_interface_restore in a held RHS at t: the held phase's momentum and force as the
 * predictor has them (nothing without a predictor). */
void mpm_interface_predict(const mpm_interface *ifc, double t);

/* The shared nodes (coupling.exchange = shared). The default exchange holds the solid for the
 * gas's step and gives the solid the gas's impulse as a load spread over its substeps. Where the
 * solid is light beside the gas (a soft slab under a shock: its face nodes carry a few per cent
 * of the gas's nodal mass there), a face node alone under that load rings at the solid's own
 * frequency around the velocity the gas met, and the velocity scheme's inelastic merge at the
 * next step takes the ringing's energy out (tests/verification/test_multirate_face.py). With
 * shared nodes the solid goes first, and on every node where the gas has mass its substeps
 * advance the node as the joint solve would, with the gas's nodal mass beside the solid's and
 * the gas's nodal force of the step's start: the fast partition carries the interface's inertia
 * and the slow one's force, as in a multirate (MRI) method. The gas's step then takes, on the
 * nodes the solid reached, the velocity the substeps left there. What the solid received and the
 * gas gave up are captured on both sides, so the owed momentum keeps the balance exact. */
int mpm_interface_want_shared(mpm_interface *ifc);
/* At the coupling step's start, after the gas's deposit (mpm_cycle_deposit): take the gas's
 * nodal mass, force and velocity from its phase. */
void mpm_interface_share(mpm_interface *ifc, int gas_phase);

/* A gas or solid RHS begins: nothing captured (or booked) yet. */
void mpm_interface_capture_begin(mpm_interface *ifc);
/* A loaded RHS, after its exchanges and before the solid's constraints: keep the solid's nodal
 * velocity and acceleration (v_solved, a_solved). */
void mpm_interface_solved(mpm_interface *ifc);
/* A step of size h was accepted. The gas's: what its RHS captured is owed to the solid,
 * impulse += h capture (sign +1). The solid's: what its RHS delivered of the load (captured on
 * the nodes where the solid had mass) is owed no more, impulse -= h capture (sign -1). */
void mpm_interface_capture_accept(mpm_interface *ifc, double h, int sign);

/* Allocate what interpolated loads need (below). */
int mpm_interface_want_trend(mpm_interface *ifc);

/* The solid is about to advance from t0 over H under load = impulse / H; the impulse stays owed
 * until the solid's accepted steps deliver it (above), so whatever a step could not deliver (a
 * node the solid has left) is still owed after the advance (mpm_interface_rehome then moves it
 * to a node the solid holds). With interpolate, its substeps see
 * the load's linear trend, the change from the last load over the distance between the two
 * advances' midpoints: load + trend (t - t_mid), whose mean over equal substeps is the load. */
void mpm_interface_load(mpm_interface *ifc, double t0, double H, int interpolate);
/* The load of a solid RHS at t with classic step h (the trend at the step's midpoint; h = 0:
 * at t). */
const double *const *mpm_interface_load_at(mpm_interface *ifc, double t, double h);
/* The solid's nodal mass at the start of its advance (the light-node rule above): the first
 * call after mpm_interface_load takes it from the solid's phase as it is now (after a loaded
 * RHS's deposit and reverse halo), later calls return it. */
const double *mpm_interface_mass_start(mpm_interface *ifc);
/* After the solid's advance: the momentum still owed on each owned node where the solid's mass
 * is below what it was at the start of the advance, or zero, goes to the node of the 3^dim block
 * around it (within this rank's box) with the most solid mass now, if that is another node; the
 * moves are summed into their owners. Collective. */
int mpm_interface_rehome(mpm_interface *ifc, const unsigned char *owned);
/* The momentum owed to the solid on the nodes this rank owns (dim values; the caller reduces):
 * the gas gave it up, the solid has not yet received it. */
void mpm_interface_owed(const mpm_interface *ifc, const unsigned char *owned, double *J);

/* ---- checkpoints ---------------------------------------------------------------------------
 * What an interface carries from one coupling step to the next is state: the momentum owed to
 * the solid and, with interpolated loads, the last load and its span. A checkpoint stores it as
 * a particle set, one particle per owned node that carries any (x: the node, v: the owed
 * impulse, L: the last load, span; with the predictor, the last hold's velocity and mass), so that
 * a restart on any number of ranks finds it by position, after migration, on the node it came from.
 */

/* An empty set with that layout, and its name in a checkpoint. With the predictor
 * (predictor = 1) each particle also carries the node's velocity and mass at the last hold,
 * that hold's time and the load of the last advance (P, Pm, tp, Q). */
#define MPM_INTERFACE_PHASE "interface"
int mpm_interface_particles_new(mpm_particles **p, int dim, int predictor);
/* Fill p (from mpm_interface_particles_new) with this rank's owned nodes that carry state. */
int mpm_interface_pack(const mpm_interface *ifc, const unsigned char *owned, mpm_particles *p);
/* Put the state of p (migrated to the owners of its nodes) back on the nodes. */
void mpm_interface_unpack(mpm_interface *ifc, const mpm_particles *p);

#endif
