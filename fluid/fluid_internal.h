/* What the fluid module's files share: the module content and the field layout. Private to
 * fluid/. */
#ifndef FLUID_INTERNAL_H
#define FLUID_INTERNAL_H

#include "fluid_boundary.h"
#include "fluid_obstacle.h"
#include "fluid_stress.h"
#include "fluid_wall_ls.h"

#include "mpm_bc.h"
#include "mpm_config.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"
#include "mpm_module.h"
#include "mpm_transfer.h"

/* The state fields x, v, J, e are fields 0-3; C follows when APIC is on. */
enum { FLUID_X, FLUID_V, FLUID_J, FLUID_E };

typedef struct fluid_layout {
  int f_C, f_m, f_V0, f_divv, f_D; /* field indices; -1 if absent */
  int f_psi;                       /* riemann viscosity: its limiter (after divv, D) */
  int f_pending; /* method of lines: the first of this RHS's pending_divv, [pending_D],
                  * [pending_psi], which precede divv, D, psi in the same order */
  int f_rho, f_p, f_mach, f_T, f_s, f_rho_grid; /* output fields */
} fluid_layout;

typedef struct fluid_gridp fluid_gridp; /* fluid.pressure = grid (fluid_gridp.c) */

typedef struct fluid_content {
  fluid_gas gas;
  double R; /* specific gas constant, J/(kg K) */
  int ppc;
  double lp; /* GIMP half-width in cells */
  fluid_layout lay;
  mpm_transfer tr;
  double gravity[MPM_MAX_DIM];
  mpm_node_constraints cons; /* wall nodes */
  mpm_walls walls;           /* the domain's faces */
  fluid_open *open;          /* open faces (inflow, outflow, far field), or NULL */
  fluid_virtual virt;        /* virtual particles of the open faces and obstacles */
  fluid_obstacles obs;       /* static obstacles (fluid_obstacle.h) */
  fluid_wall_ls wall;        /* their least-squares wall treatment (fluid_wall_ls.h) */
  int reg_every;             /* regularise every reg_every steps (0: never) */
  int reg_min, reg_max;      /* particles per non-empty cell after regularisation */
  int refill;                /* regularisation refills cells that expansion emptied */
  int refill_every;          /* refill every refill_every steps (0: never) */
  int refill_holes;          /* refill the holes in the gas after every other step (-1: auto) */
  double merge_light;        /* merge particles below this share of their cell's heaviest */
  double merge_light_holes;  /* the same after a refill of holes alone (fluid_regularise.c) */
  double shift;              /* particle shifting coefficient kappa (0: off; fluid_shift.c) */
  int shift_every;           /* shift every shift_every steps */
  double shift_J;            /* only particles with J >= shift_J move */
  int current_rate;          /* fluid.strain_rate = current (fluid_module.c) */
  double mol_damping;        /* fluid.mol_damping (fluid_transfer.c); 0: off */
  int filter_phase;          /* its scratch grid phase (-1: none) */
  double *work;              /* its particle scratch (4 dim cap) */
  double *sub;               /* its viscous deposit: positions and stresses (cap each) */
  unsigned char *sub_lev;    /* and, refined, their levels (cap) */
  int stable_local;          /* fluid.stable_step = neighbourhood (fluid_stable.c) */
  double s_local;            /* its fastest signal for this step, m/s; < 0: not yet known */
  double *cellsum;           /* its per-cell sums and their block sums (6 nnodes) */
  mpm_lidx cap;              /* capacity of the particle scratch arrays */
  double *vsig;              /* V sigma deposited by this RHS (dim^2 cap) */
  double *scratch;           /* G2P output v, a, L ((2 dim + dim^2) cap) */
  double *vnew;              /* MUSL: the particles' new velocities (dim cap) */
  double *Cnew;              /* MUSL with APIC: their new affine velocities (dim^2 cap) */
  double *power;             /* de/dt of each particle (cap) */
  double *tscratch;   /* the classic transfer's a_p, scalars and APIC terms (see ensure_scratch) */
  double *lim;        /* the limiter's neighbour points (fluid_limiter.c) */
  mpm_lidx lim_cap;   /* their capacity */
  int volume_domain;  /* fluid.volume_rate = domain (fluid_volume.c) */
  double *vol;        /* its face points and rates */
  mpm_lidx vol_cap;   /* their capacity in particles */
  double *node;       /* nodal scratch: time-centred velocity and scalars ((dim + 3) nnodes) */
  mpm_module_ops ops; /* the module's ops: p2g_rate only with the current strain rate */
  fluid_gridp *gridp; /* fluid.pressure = grid, or NULL */
  int refined;        /* on a refinement (its particles follow the levels: fluid_relevel.c) */
  double *av_l;       /* refined: each particle's artificial viscosity length (cap) */
  unsigned char *lev; /* refined: the level of each particle's position in this RHS (cap) */
  /* refined, usl: the classic transfer's nodal scratch (as node) on the finer levels, l >= 1 */
  double *lnode[MPM_HIER_MAX_LEVELS];
} fluid_content;

/* What the classic step's transfer gives each particle (component-major, stride n). */
typedef struct fluid_step_out {
  double *vhat[MPM_MAX_DIM]; /* sum S v_i^{n+1} (the velocity that moves it) */
  double *vnew[MPM_MAX_DIM]; /* its new velocity (FLIP/PIC blend or APIC) */
  double *C;                 /* APIC: its new affine velocity (dim^2), else NULL */
  double *L;                 /* gradient of the time-centred nodal velocity (dim^2) */
  double *heat; /* its share of the transfer's energy defect, J/kg (fluid_transfer.c) */
} fluid_step_out;

/* G2P of the classic step h after the grid update, on every level of a hierarchy
 * (fluid_transfer.c). */
int fluid_classic_transfer(mpm_module *m, const double *y, double h, const fluid_step_out *o);
/* The wall rule for the method of lines (fluid_transfer.c), in the right-hand side of state y:
 * relaxes the particles' velocity into a wall face at (1 - keep) 2 c / dx, subtracting from
 * vdot, and adds the kinetic energy removed to power (de/dt). */
void fluid_wall_rate_mol(const mpm_module *m, const double *y, double *const *vdot, double *power);
/* The method of lines' damping of the particle velocity the grid does not see (fluid_transfer.c,
 * fluid.mol_damping): subtracts it from vdot and adds the kinetic energy it removes to power.
 * work: 4 dim n doubles of particle scratch. */
int fluid_mol_damping(mpm_module *m, const double *y, double *const *vdot, double *power,
                      double *work);

/* The riemann viscosity's limiter psi (fluid_stress.h) of every particle of state y, from
 * the nodal velocity v_i whose gradient at the particles is L (dim^2 components of n)
 * (fluid_limiter.c). */
int fluid_limiter(mpm_module *m, const double *y, const double *const *v_i, const double *L,
                  double *psi);

/* fluid.volume_rate = domain: the divergence of the nodal velocity v_i (whose gradient at the
 * particles is L, dim^2 components of n) over each particle's domain, for dJ/dt; *rate points
 * to n values in the module's scratch (fluid_volume.c). */
int fluid_volume_rate(mpm_module *m, const double *y, const double *const *v_i, const double *L,
                      const double **rate);

/* fluid.pressure = grid (fluid_gridp.c). init: in the build, after the other settings and the
 * walls, sets it up (its grid phase) when the key asks for grid, refusing what it does not carry
 * with the key at fault; refine: on a refinement hierarchy, where auto means grid and particle is
 * refused, sets it up if init did not and gives the hierarchy its phase; deposit: in the RHS's
 * P2G after fluid_stress_pressure, keeps m p and zeroes the pressure's stress in b; forces:
 * before the walls fold the deposit (first pass), adds the nodal pressure's force; nodal_rate:
 * after the solve, the nodal volume rate per unit mass on every level of the nodal velocity v
 * (NULL: the phase's v_i; usl: its time-centred one), into s for the G2P that fills the
 * particles' rate (fluid_gridp_rate_out); work: adds the pressure's de/dt to power,
 * then turns that rate into dJ/dt / J in place (hybrid: adding tr L, the particles' velocity
 * gradient whose work energy_rate booked). hybrid: the same with the particles' quadrature of
 * p - p_h kept in their stress (fluid_gridp.c); without a solid (and a hierarchy) its deposit
 * forms the nodal pressure at once and stress returns the stress to deposit, vsig with the
 * defect's load V p_h(x_p) on its diagonal (vsig itself otherwise; vsig is left as it is). */
int fluid_gridp_init(mpm_module *m, const mpm_config *cfg);
/* physics.gauge_pressure outside what carries it: MPM_ERR_INPUT naming the key (fluid_gauge.c). */
int fluid_gauge_check(const mpm_module *m, const mpm_config *cfg);

/* Does the gas take the hybrid pressure with its grid part weighted by the filled share
 * (fluid.hybrid_fill > 0, without a solid)? */
int fluid_gridp_weighted(const fluid_content *fc);
int fluid_gridp_refine(mpm_module *m, const mpm_config *cfg, mpm_hier *h); /* h may be NULL */
void fluid_gridp_destroy(fluid_content *fc);
/* Forget the per-level arrays: the hierarchy changed (a regrid). */
void fluid_gridp_reset(fluid_content *fc);
int fluid_gridp_deposit(mpm_module *m, const double *y, const fluid_batch *b);
const double *fluid_gridp_stress(const mpm_module *m, const double *vsig);
int fluid_gridp_forces(mpm_module *m);
int fluid_gridp_nodal_rate(mpm_module *m, const mpm_hier_nodal *v, mpm_hier_scalars *s);
/* The particles' arrays the G2P fills with the nodal scalars of nodal_rate, and their count
 * (1, or 4 with fluid.pressure_relax). */
double *const *fluid_gridp_rate_out(const fluid_content *fc, int *ns);
void fluid_gridp_work(const mpm_module *m, const double *y, const double *L, double *power);

/* The grid pressure beside a solid (fluid_gridp_solid.c): the solid's region, its points
 * (m->beside), taken out of the span integrals. phase: a grid phase of the fluid's for the
 * solid's deposits; A, B: scalars per level; buf: scratch per solid point. init adds the phase
 * (before the hierarchy's phases are added); pressure continues P (every level, before the
 * prolongation) into the active nodes without gas mass M from the gas nodes' pressures; force
 * adds the solid quadrature's correction to the gas phase's f_i (P prolonged); rate subtracts its
 * adjoint from the restricted rates D and hands the continued nodes' rates to the gas nodes
 * (the continuation's transpose; vel: the velocity read, NULL the gas phase's). Each does
 * nothing while m->beside is NULL. fluid_gridp_prolong (fluid_gridp.c) fills level 0's ghosts
 * of the level scalars a[l] and prolongs them into the inactive nodes. */
typedef struct fluid_gridp_solid {
  int phase;
  int deep;  /* continue through the whole solid (the hybrid; fluid_gridp_solid_pressure) */
  double *W; /* with deep: each node's geometric volume (fluid_gridp_geometric_volume) */
  const mpm_points *pts; /* the points read: m->beside, or the gas's own (hybrid) */
  mpm_lidx cap;
  double *buf, *A[MPM_HIER_MAX_LEVELS], *B[MPM_HIER_MAX_LEVELS];
  unsigned char *lev; /* on a hierarchy: each point's level (cap), vouched for its transfers */
  /* the levels vouched for before (the gas's), restored after the points' transfers */
  const double *saved_x;
  mpm_lidx saved_n;
  const unsigned char *saved_lev;
} fluid_gridp_solid;
int fluid_gridp_prolong(mpm_module *m, double **a);
/* W_j = the integral over the domain of N_j on level 0's nodes (*W allocated here). */
int fluid_gridp_geometric_volume(const mpm_grid *g, double **W);
int fluid_gridp_solid_init(fluid_gridp_solid *s, mpm_grid *g);
void fluid_gridp_solid_free(fluid_gridp_solid *s);
int fluid_gridp_solid_pressure(mpm_module *m, fluid_gridp_solid *s, double *const *P,
                               const double *const *M);
int fluid_gridp_solid_force(mpm_module *m, fluid_gridp_solid *s, double *const *P);
int fluid_gridp_solid_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                           double *const *D, const double *const *M);
/* The two quadrature corrections of the points s->pts (any points, not only a solid's): force
 * adds -sum_s V_s p_h(x_s) grad N_i(x_s) to the gas phase's f_i (P prolonged), rate subtracts
 * sum_s V_s N_j(x_s) div v_h(x_s) from D (vel: the velocity read, NULL the gas phase's). */
int fluid_gridp_points_force(mpm_module *m, fluid_gridp_solid *s, double *const *P);
/* V_s p_h(x_s) at the points into *load (scratch of s, valid until its next call): the force's
 * load, for a caller that deposits it with its own stress. */
int fluid_gridp_points_load(mpm_module *m, fluid_gridp_solid *s, double *const *P, double **load);
int fluid_gridp_points_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                            double *const *D);

/* The gas's empty particle set and its layout: C with apic, D with viscous, psi with limiter,
 * and the lagged strain rate in the state (lag_in_state, the classic update) or after a
 * pending copy (the method of lines) (fluid_module.c). */
int fluid_particles_new(mpm_particles **p, int dim, fluid_layout *lay, int apic, int viscous,
                        int limiter, int lag_in_state);

/* Seed every [gas.NAME] region into the (empty) particle set (fluid_seed.c). */
int fluid_seed(mpm_module *m, const mpm_config *cfg);

/* The fastest signal the nodes carry, from mass-weighted sums over the 3^dim cells around
 * every owned cell (fluid_stable.c); the particles must sit on the ranks owning their cells.
 * Collective. */
int fluid_neighbourhood_signal(const mpm_module *m, double *smax);

/* Which refill step `step` takes: 2 every cell that expansion emptied (a multiple of
 * refill_every), 1 only the cells of holes in the gas (refill_holes), 0 none. */
static inline int fluid_refill_due(const fluid_content *fc, long step) {
  if (fc->refill_every > 0 && step % fc->refill_every == 0) return 2;
  return fc->refill_holes ? 1 : 0;
}

/* Refill emptied cells when step is a multiple of refill_every (else, with refill_holes, only
 * the cells of holes in the gas), then merge and split particles
 * so that every non-empty cell holds reg_min to reg_max of them when it is a multiple of
 * reg_every, conserving mass, momentum and total energy. Sets
 * *changed if this rank's set changed (fluid_regularise.c). Collective. */
int fluid_regularise(mpm_module *m, long step, int *changed);

/* Shift the particles down the gradient of the nodal volume fraction when step is a multiple
 * of shift_every and shift > 0; only positions change (fluid_shift.c). Sets *changed if any
 * particle moved. Collective. */
int fluid_shift(mpm_module *m, long step, double h, int *changed);

/* After an accepted step of a refined gas (regrid 0) or a regrid (1): split the particles that
 * entered a finer level and merge, 2^dim at a time, those that left one (between regrids in
 * batches: fluid_relevel.c); sets *changed when the set changed. Collective. */
int fluid_relevel(mpm_module *m, int regrid, int *changed);

/* The level of size of gas particle i (0 .. MPM_HIER_MAX_LEVELS - 1) from its reference volume,
 * V0_0 = (dx / ppc)^dim being level 0's: round(log2(V0_0 / V0) / dim) (fluid_relevel.c). */
int fluid_size_level(const mpm_module *m, double V0_0, mpm_lidx i);

/* Seed the finer levels of m->hier (fluid_seed.c): drop the level-0 particles inside them and
 * seed each level's own region on its lattice. Collective. */
int fluid_seed_refined(mpm_module *m, const mpm_config *cfg);

/* The transfers of a module that may be refined (fluid_refine.c): P2G of a into phase, on
 * the grid or composite (an error goes to *rc, which is left alone on success), and the G2P of
 * v, a and L (L_out may be NULL) from m's phase at the positions of state y, and of the nodal
 * scalars s->s_i[l][j], j < ns, of every level l into s_out[j]. */
void fluid_p2g_any(mpm_module *m, int phase, const mpm_p2g_args *a, int *rc);
int fluid_g2p_phase(mpm_module *m, const double *y, double *const *v_out, double *const *a_out,
                    double *L_out, const mpm_hier_scalars *s, double *const *s_out, int ns);
/* The grid spacing of the finest level (the grid's without refinement). */
double fluid_finest_dx(const mpm_module *m);
/* The levels of the positions of state y (mpm_hier_levels: remembered while they do not move),
 * NULL without a hierarchy or out of memory. */
const unsigned char *fluid_position_levels(const mpm_module *m, const double *y);
/* The level of particle i's position in state y, found afresh (m->hier set). */
int fluid_position_level_of(const mpm_module *m, const double *y, mpm_lidx i);
/* The level particle i of state y deposits on (its position's): lev[i] from
 * fluid_position_levels, found afresh when lev is NULL; 0 without a hierarchy. (Inline: every
 * particle, several times a step.) */
static inline int fluid_position_level(const mpm_module *m, const unsigned char *lev,
                                       const double *y, mpm_lidx i) {
  if (!m->hier) return 0;
  return lev ? lev[i] : fluid_position_level_of(m, y, i);
}
/* On a refinement, at the start of an RHS: the level of each particle's position in state y
 * into fc->lev, handed to the hierarchy for this RHS's transfers (mpm_hier_levels_known; the
 * RHS's last phase forgets them), and each particle's artificial viscosity length, its level's
 * spacing, into fc->av_l (capacity fc->cap); a no-op unrefined. */
void fluid_av_lengths(mpm_module *m, const double *y);
/* Free the classic transfer's nodal scratch of the finer levels (a regrid, or the end). */
void fluid_lnode_free(fluid_content *fc);
/* Refuse, naming the key, every gas setting the refined levels do not carry (fluid_refine.c). */
int fluid_refine_check(const mpm_module *m, const mpm_config *cfg);

/* Refresh the output fields rho, p, mach, T, s from the particle data (before output). */
int fluid_output_fields(mpm_module *m);

#endif
