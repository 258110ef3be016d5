/* Static rigid obstacles for the gas: [obstacle.NAME] sections, each a signed-distance shape
 * (common/mpm_sdf.h) that acts as a boundary condition on the gas's nodal velocities, with no
 * particles. Private to fluid/.
 *
 * Nodes. Every box node with phi(x_i) < band (fluid.obstacle_band cells) is constrained after
 * each nodal update: slip removes the components of v_i and a_i along the outward normal of
 * the nearest surface point (bilateral: the gas can neither enter the body nor pull away
 * from it), no_slip sets v_i = a_i = 0. A constrained node that the gas barely covers (its
 * mass below FLUID_OBSTACLE_HOLD of the largest mass of any constrained node, over all
 * obstacles and ranks) is held entirely: such a node, mostly inside the body, takes the large
 * and nearly cancelling forces of the gas and of the ghosts below on a small mass, and left
 * free along the surface it made the flow past a body unstable (gas_obstacles.ini at 128
 * cells, the wedge) while a full hold costs the gas at rest nothing. Under the classic update
 * (usl, musl; the least-squares wall's too) a held slip node coasts instead: it keeps its velocity
 * of the step's start, slip-projected, and takes none of the step's force. A hold to rest is
 * there an impulse (v' = 0) that FLIP carries into the particles, so the first layer over a
 * slip face lost its tangential velocity every step (a uniform stream along a face left its
 * state by 1.10, test_refine_obstacles stream). The ERK pairs still hold it at rest (a = 0,
 * v = 0: the particles' positions follow it, their velocities do not); coasting there blew up
 * a circle on three levels and the 3-D sphere (docs/refinement.md). phi and the normals are
 * evaluated once, at build. Nodes deep inside carry no mass (no particle is seeded inside, and
 * the stencil of a particle outside reaches at most two cells in), so they cost one comparison.
 *
 * Levels and the grid pressure. On a refinement hierarchy every level constrains its active
 * nodes, and with the grid pressure (any hierarchy, or fluid.pressure = grid) the ghosts are the
 * massless nodes inside a body instead of the lattice below (fluid_obstacle_levels.c).
 *
 * Ghost pressure. Held nodes alone leave the nodes next to the surface with an incomplete
 * stencil: the gas pressure pushes them towards the body (a force of order p / dx per unit
 * volume), so gas at rest does not stay at rest and slips into the body at corners. Like the
 * mirrored pad nodes of a wall, the missing neighbours are supplied: every point of the
 * seeding lattice inside an obstacle is a ghost of volume (dx / ppc)^dim that adds
 * p_i V grad S_i to each node i near it, with p_i the mass-weighted nodal pressure of the gas
 * (-tr sigma / dim, deposited by the particles near a body). With the gas's own stencil that
 * completes the lattice, so a uniform pressure gives no nodal force anywhere: gas at rest stays
 * exactly at rest. G_i = sum_ghosts V grad S_i is computed once, at build.
 *
 * Force. The force the gas exerts on an obstacle is minus the rate at which the obstacle
 * changes the gas's momentum, summed over the nodes each rank owns and reduced over the ranks:
 *   method of lines (h = 0):  F = sum_i m_i (a_i - a_i') - sum_i p_i G_i,
 *   classic update (h > 0):   F = sum_i m_i (v_i - v_i') / h - sum_i p_i G_i,
 * where ' marks the constrained values (a_i includes the ghost force). A node of a body's reach
 * (constrained, or loaded by its ghosts) whose mass is at or below the phase's m_empty (empty,
 * or light under fluid.light_node_mass) took a_i = 0 in the nodal update: its whole force f_i
 * (gas and ghost) never reached the gas, while the gas's other nodes took the partners of its
 * internal forces, so the body took it: F gains sum f_i over those nodes. Without that a light
 * rule at the bodies' edges, whose nodes the gas only partly covers, breaks the balance below
 * (test_obstacles: by 9.4e-3 of the pulse's momentum scale with light_node_mass = 0.3); light
 * nodes away from every body stay the light rule's own loss. In the classic update the
 * constraint is an impulse: the acceleration takes the velocity change too, a_i' = a_i +
 * (v_i' - v_i) / h, so FLIP (which adds h sum S a_i'), PIC and APIC (which take sum S v_i')
 * all see the same change, and over a step P(t + h) - P(t) = -h F exactly, with P the gas
 * momentum. F points the way the
 * gas pushes the body (+x: downstream for a flow along +x). The report uses the RHS that made
 * the step (classic) or the last RHS of the step (ERK pairs: the end of the step for the FSAL
 * pairs bs32 and dp54).
 *
 * Energy. A static obstacle does no work on the gas, but its discrete action does: the ghost
 * forces work on the moving nodes near the surface, and a constraint that removes velocity
 * takes kinetic energy out. Each recorded RHS sums that rate per node, q_i = p_i G_i . v_i' plus
 * the constraint's power (mpm_impulse.h), with v_i' the final (in the classic update the
 * time-centred) nodal velocity, and gives -q_i back to the particles near the body as heat, in
 * proportion to S_i m_p / m_i: the gas's total energy is then conserved with obstacles as in a
 * closed box (test_obstacles_energy: 4.9e-5 relative drift over 67 steps without it, roundoff
 * with it). Physically it is the heat of the inelastic stop at the wall, which the continuum
 * puts into the gas by compression. It is booked under least_squares only. Under ghost the
 * held nodes stop a whole wall layer, and heating it by the kinetic energy they destroy made
 * that layer hot and thin (the wedge's first layers fell from about 0.5 to 0.14-0.26 of the
 * post-shock density), moved ghost's verified figures, and made them depend on roundoff:
 * through the hold switch, 2 ranks drifted from 1 by 7e-10 by t = 0.15 on the wedge. */
#ifndef FLUID_OBSTACLE_H
#define FLUID_OBSTACLE_H

#include "mpm_config.h"
#include "mpm_diag.h"
#include "mpm_grid.h"
#include "mpm_hier.h"
#include "mpm_impulse.h"
#include "mpm_sdf.h"
#include "mpm_shape.h"

#include "fluid_surface.h"

/* Constrained nodes with less than this fraction of the largest constrained node's mass are held
 * entirely (see Nodes above). 0.3: gas_obstacles.ini at 128 cells and the wedge run with 0.3
 * and 0.6 alike, and fail without it; gas at rest stays exactly at rest either way. */
#define FLUID_OBSTACLE_HOLD 0.3

typedef struct fluid_obstacle {
  char name[64];
  char shape_key[256]; /* obstacle.NAME.shape, for messages (as long as the keys it builds) */
  mpm_sdf sdf;
  int no_slip;
  int has_ref;             /* reference area given: write Cd and Cl */
  double q_ref_area;       /* 1/2 rho U^2 A */
  double q_ref;            /* 1/2 rho U^2 */
  fluid_surface surf;      /* surface pressure output (surface_interval), or n = 0 */
  double flow[3], lift[3]; /* unit drag and lift directions */
  mpm_lidx count;          /* constrained nodes */
  mpm_lidx *node;          /* box index */
  double *normal;          /* dim per node */
  unsigned char *owned;    /* counted in the force */
  /* Levels >= 1 of a hierarchy (fluid_obstacle_levels.c): the active nodes with
   * phi < band h_l and their normals (index 0 unused; the level-0 nodes are the above). */
  struct {
    mpm_lidx count, *node;
    double *normal;
  } fine[MPM_HIER_MAX_LEVELS];
} fluid_obstacle;

typedef struct fluid_obstacles {
  int count;
  fluid_obstacle *ob;
  unsigned char open[MPM_MAX_DIM][2]; /* the gas's open faces: ghosts continue beyond them */
  mpm_rhs_records rec;                /* the latest RHS and the one before (mpm_impulse.h) */
  double *f[2];                       /* their forces on this rank, dim per obstacle */
  int coast;                          /* held nodes keep v^n, slip-projected (the classic update) */
  int heat;    /* book the obstacles' work as heat (least_squares; see Energy above) */
  double hold; /* nodes below this fraction of the largest mass are held (FLUID_OBSTACLE_HOLD) */
  int ppc;
  double lp;       /* GIMP half-width of the particles and ghosts, cells */
  mpm_lidx gcount; /* nodes with a ghost force */
  mpm_lidx *gnode; /* box index */
  double *G;       /* sum V grad S of the ghosts (dim per node) */
  unsigned char *gowned;
  int *gob;                 /* the obstacle each ghost force belongs to (the nearest) */
  mpm_lidx lcount;          /* owned nodes in the bodies' reach (constrained or ghost), each once */
  mpm_lidx *lnode;          /* box index: an empty or light one hands its force to the body */
  int *lob;                 /* the obstacle it belongs to */
  unsigned char *near;      /* per box node as a cell's lower corner: a particle in it reaches a
                               ghost node or, when the heat is booked, a constrained node */
  unsigned char *listed;    /* per box node as a cell's lower corner: near, or in another pass's
                               reach (fluid_obstacles_list_cells) */
  mpm_lidx nlist, list_cap; /* the particles in listed cells at the latest deposit: */
  mpm_lidx *list;           /* their indices, ascending, */
  mpm_lidx *list_cell;      /* and cells (box index of the lower corner) */
  const double *list_x;     /* the positions they were found at (x[0]; NULL: no list) */
  mpm_lidx list_n;          /* and the particle count */
  unsigned char *own;       /* per box node: owned by this rank */
  double *sm;               /* nodal m and m p (p = -tr sigma / dim, with q) of the particles near
                               a body, then m p with the thermodynamic p alone (nsm nnodes) */
  int nsm;                  /* 3 if an obstacle writes its surface pressure, else 2 */
  double *q;                /* per box node: the rate at which the obstacles put energy into the gas
                               in the latest recorded RHS (ghost work and constraint power), W, then
                               per unit nodal mass, W/kg (fluid_obstacles_work) */
  /* The span ghost (fluid_obstacle_levels.c): with the grid pressure (fluid.pressure = grid,
   * and any refinement) the ghosts are the massless nodes inside a body; per level l of
   * nlev: inside[l] marks the box nodes inside a body (phi < 0, mirrored into the domain across
   * a wall), nob[l] the nearest obstacle of a node (-1: not yet found); the reach of the finer
   * levels (rcount, rnode, rob: the constrained active nodes, each once). */
  int span, nlev;
  const mpm_hier *hier; /* NULL: level 0 alone */
  double band;          /* fluid.obstacle_band, cells */
  unsigned char *inside[MPM_HIER_MAX_LEVELS];
  int *nob[MPM_HIER_MAX_LEVELS];
  mpm_lidx rcount[MPM_HIER_MAX_LEVELS], *rnode[MPM_HIER_MAX_LEVELS];
  int *rob[MPM_HIER_MAX_LEVELS];
  char path[4096]; /* obstacles.csv */
  mpm_diag *csv;
} fluid_obstacles;

/* Keys of [obstacle.NAME] and fluid.obstacle_band. */
extern const mpm_key_spec fluid_obstacle_keys[];
extern const int fluid_obstacle_nkeys;

/* Read every [obstacle.NAME] and find its nodes on grid. open marks the gas's open faces
 * [axis][lo, hi]: a body that crosses one continues beyond it (its ghosts there stand in for
 * the body outside the domain). */
int fluid_obstacles_build(fluid_obstacles *o, const mpm_config *cfg, const mpm_grid *grid, int ppc,
                          const unsigned char (*open)[2]);
/* In P2G: deposit m and m p of the n particles near a body (positions per component, masses, V0
 * and J, and the V sigma of the stress phase, dim^2 components of n), and for the surface output
 * the thermodynamic pressure from e (specific internal energy) and gamma. */
void fluid_obstacles_deposit(fluid_obstacles *o, const mpm_grid *grid, mpm_lidx n,
                             const double *const *x, const double *m, const double *V0,
                             const double *J, const double *vsig, const double *e, double gamma);
/* Before the nodal update (after the reverse halo): sum the nodal pressures over the ranks,
 * add the ghost forces to f_i and, with record, start the force record of this RHS at time t.
 * Collective. */
int fluid_obstacles_begin(fluid_obstacles *o, mpm_grid *grid, int phase, double t, double h,
                          int record);
/* 1 if x lies inside an obstacle (phi < 0): no gas particle is seeded there. */
int fluid_obstacles_inside(const fluid_obstacles *o, const double *x);
/* The index of the first obstacle that contains x, or -1. */
int fluid_obstacles_which(const fluid_obstacles *o, const double *x);
/* Return the gas particles an update carried into a body (phi < 0), as the domain's walls
 * return theirs (fluid_walls_return): each is mirrored across the body's surface along the
 * normal at the nearest surface point, x - 2 phi n, or, where the mirror point lies in another
 * body (or the same one, at a re-entrant corner) or beyond a closed face of the grid's domain,
 * set on that surface point, 1e-6 of a cell outside. Positions only: mass, momentum and energy
 * are unchanged. The nodal constraint stops the gas's velocity at the body's nodes, but a
 * particle moves with its stencil's velocities, so one near the surface drifted in (up to 0.65
 * of a level-2 cell around the sphere of cases/sphere_m08.ini at 20 cells, 680 particles by
 * t = 5) and came out with a state no gas outside had. Returns the count moved (this rank). */
mpm_lidx fluid_obstacles_return(const fluid_obstacles *o, const mpm_grid *grid, mpm_particles *p,
                                int field_x);
/* Constrain the obstacle nodes of phase after a nodal update with step h (0: method of lines);
 * with record, add the removed momentum and the forces of the empty or light nodes of the bodies'
 * reach (see Force above) to the force record begun by fluid_obstacles_begin. */
int fluid_obstacles_apply(fluid_obstacles *o, mpm_grid *grid, int phase, double h, int record);
/* Book the obstacles' work as heat from now on (see Energy above). */
void fluid_obstacles_book_heat(fluid_obstacles *o, const mpm_grid *g);
/* The particles near a body. fluid_obstacles_deposit() goes over every particle and lists those
 * in a listed cell (near, or added here by another pass that visits the particles near the
 * bodies, fluid_wall_ls), with their cells, so that the later passes of the same RHS visit the
 * list instead of every particle. Add the cells flagged (nonzero) in flag (per box node as a
 * cell's lower corner) to the listed ones. */
void fluid_obstacles_list_cells(fluid_obstacles *o, const mpm_grid *grid,
                                const unsigned char *flag);
/* The list of the latest deposit if it was made at the positions x[0] of n particles (count and
 * cells into *count and *cells), else NULL: the caller then goes over every particle. */
const mpm_lidx *fluid_obstacles_listed(const fluid_obstacles *o, const double *x0, mpm_lidx n,
                                       mpm_lidx *count, const mpm_lidx **cells);
/* The RHS is done with the list (the positions may change before the next deposit). */
void fluid_obstacles_list_done(fluid_obstacles *o);
/* After the last constraint of a recorded RHS: add the ghost forces' work on the final nodal
 * velocities (time-centred in the classic update) to the nodal energy rates q, divide them by
 * the nodal masses and copy the owners' values into the ghost nodes. Collective. */
int fluid_obstacles_work(fluid_obstacles *o, mpm_grid *grid, int phase, double h);
/* Book the energy the obstacles put into the gas as heat: each particle near a body takes
 * -sum_i S_i q_i / m_i into its de/dt (power, n values), so that a static obstacle leaves the
 * gas's total energy unchanged: summed over the particles this is -sum_i q_i. In the classic
 * update (h > 0) the cooling of one step stops at half the particle's internal energy e. */
void fluid_obstacles_heat(const fluid_obstacles *o, const mpm_grid *grid, mpm_lidx n,
                          const double *const *x, const double *e, double h, double *power);
/* After an accepted step from t - h to t: reduce the recorded forces and write one row per
 * obstacle to obstacles.csv (opened at the first call; appended after a restart). Collective. */
int fluid_obstacles_report(fluid_obstacles *o, const mpm_grid *grid, double t, double h);
void fluid_obstacles_free(fluid_obstacles *o);

/* ---- on every level, and with the grid pressure (fluid_obstacle_levels.c) ---------------- */

/* phi at x (and the outward normal), nearest over the periodic images of x along g's periodic
 * axes. */
double fluid_obstacle_phi(const mpm_sdf *sdf, const mpm_grid *g, const double *x, double *normal);
/* Constrain count nodes (box indices node, normals normal, owned NULL: all owned) of phase ph
 * as fluid_obstacles_apply does; adds the owned share of the force to f and the power to q. */
void fluid_obstacle_constrain(const mpm_lidx *node, const double *normal,
                              const unsigned char *owned, mpm_lidx count, int no_slip,
                              mpm_grid_phase *ph, int dim, double h, double hold_below, int coast,
                              double *f, double *q);
/* Set the obstacles up on the levels of h (NULL: level 0 alone) for the span ghost, span 1
 * with the grid pressure; drops what an earlier hierarchy left. grid: level 0. */
int fluid_obstacles_levels(fluid_obstacles *o, const mpm_grid *grid, const mpm_hier *h, int span);
void fluid_obstacles_levels_free(fluid_obstacles *o);
/* Span ghost, level l (grid g, active mask act or NULL, the nodal mass M after the deposit):
 * U = 1 on the active massless nodes inside a body, else 0. */
void fluid_obstacles_span_mask(const fluid_obstacles *o, int l, const mpm_grid *g, const double *M,
                               const unsigned char *act, double *U);
/* Span ghost, level l: add P_i GH_i (GH: the integral of the prolonged mask times grad N_i,
 * restricted) to phase's f_i on the active nodes with mass, and minus it to the nearest
 * obstacle's recorded force (owned nodes). */
void fluid_obstacles_span_force(fluid_obstacles *o, int l, mpm_grid *g, int phase, const double *P,
                                const double *M, const unsigned char *act, const double *const *GH);
/* With the grid pressure: the surface output's sums of this RHS, each point from the nodes
 * around it of the finest level whose region holds it (M: nodal mass, MP: m p, per level;
 * grids: the levels' grids). */
void fluid_obstacles_span_surface(fluid_obstacles *o, const mpm_grid *const *grids,
                                  const double *const *M, const double *const *MP);
/* Span ghost, level l: D_i -= v_i . GH_i on the active nodes with mass (the ghosts move with the
 * node they act on: the adjoint of the ghost force, and a uniform stream keeps D = 0). */
void fluid_obstacles_span_rate(const mpm_grid *g, int phase, const double *M,
                               const unsigned char *act, const double *const *GH, double *D);
/* Constrain the finer levels' nodes after the solve (see fluid_obstacles_apply). Collective. */
int fluid_obstacles_apply_levels(fluid_obstacles *o, int phase, double h, int record);

#endif
