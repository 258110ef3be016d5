/* The solid module's private state, shared by its files (solid_module.c: keys, seeding, the RHS
 * phases; solid_constraints.c: walls, clamps, rigid bodies, surface tractions). Private to
 * solid/. */
#ifndef SOLID_INTERNAL_H
#define SOLID_INTERNAL_H

#include "mpm_bc.h"
#include "mpm_config.h"
#include "mpm_expr.h"
#include "mpm_geometry.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"
#include "mpm_module.h"
#include "mpm_transfer.h"
#include "solid_bulk_viscosity.h"
#include "solid_material.h"
#include "solid_prestress.h"

#include <stdio.h>

/* Field indices: x, v, F are always fields 0-2; sigma (rate-form stress) and hist (material
 * history) exist only when some body's model needs them, divv (tr D) only when some body has a
 * bulk viscosity (see solid_layout). */
enum { F_X, F_V, F_F };

/* Where a bulk viscosity keeps tr D (solid_bulk_viscosity.h): nowhere (no body has one); in the
 * state (usl, musl: the lagged rate, advanced as (new - old) / h); or, under the method of
 * lines, in the fields pending_divv (each RHS's current rate) and divv (committed after an
 * accepted step, for the stable step), both outside the state. */
enum { SOLID_BULKQ_NONE, SOLID_BULKQ_STATE, SOLID_BULKQ_PENDING };

typedef struct {
  char section[96];
  solid_material *mat;
  double rho;
  double c;            /* elastic wave speed of the model at rho (for the stable step) */
  double v[3];         /* rigid bodies: the prescribed velocity */
  mpm_region *region;  /* rigid bodies: the seeded region (the nodes it holds); else NULL */
  solid_prestress pre; /* the seeded state that carries the initial stress */
  solid_bulkq q;       /* its bulk viscosity (off unless set) */
} solid_body;

typedef struct {
  int f_sigma, f_C, f_divv, f_m, f_V0, f_body, f_hist, f_fixed, f_fext,
      f_pending; /* field indices (-1 if absent) */
  int nhist;     /* history components per particle */
} solid_layout;

/* The solid's empty particle set and its layout (solid_module.c): sigma if any model is in
 * rate form, C with APIC, divv (and pending_divv) as bulkq says (SOLID_BULKQ_*), hist of nhist
 * components (the model with the most history; 0: none), fixed with clamps, fext with
 * tractions. */
int solid_particles_new(mpm_particles **p, int dim, solid_layout *lay, int has_rate, int apic,
                        int bulkq, int nhist, int fixed, int fext);

/* A surface traction [traction.NAME]: constant nominal traction t (Pa) on the particles of
 * the deformable bodies inside `region` at seeding. Seeding counts what it tagged here. */
typedef struct {
  char name[64];
  mpm_region *region;
  double t[3];
  mpm_gidx tagged; /* particles tagged on this rank */
  double force[3]; /* their total force on this rank */
  mpm_gidx off_id; /* smallest id of a tagged particle off its body's surface, or -1 */
  double off_x[3]; /* its position */
} solid_traction;

/* The projected dilatation (solid_dilatation.c): which bodies take it, the grid phase its
 * deposit fills, and its per-particle scratch (the projecting particles; V, tr L and the
 * projection, 3 cap). */
typedef struct {
  int on, phase;
  unsigned char *body;
  mpm_lidx cap, *idx;
  double *work;
} solid_dilatation;

typedef struct {
  int nbodies;
  solid_body *body;
  solid_layout lay;
  mpm_node_constraints cons; /* wall and clamp nodes */
  /* On a hierarchy: the clamps' nodes of each finer level (lcons[0] unused; the walls of the
   * finer levels are the hierarchy's own, mpm_hier_walls_fold and _apply). */
  mpm_node_constraints lcons[MPM_HIER_MAX_LEVELS];
  int nclamps;
  mpm_region **clamp; /* clamped regions */
  int nrigid;         /* rigid bodies */
  int ntractions;
  solid_traction *traction;
  double gravity[MPM_MAX_DIM];
  double gauge;           /* physics.gauge_pressure, Pa: in the forces (solid_p2g) */
  double damping;         /* mass-proportional damping rate alpha, 1/s: f_i -= alpha (m v)_i */
  mpm_transfer tr;        /* [transfer] settings and the time method's kind */
  double *vnew;           /* MUSL: the particles' new velocities (dim n) */
  double *zero;           /* the bulk viscosity's current rate: zeros (cap), its deposit's m, v */
  double lp;              /* GIMP half-width in cells */
  mpm_lidx cap;           /* capacity of the scratch arrays */
  double *vsig, *scratch; /* V sigma (dim^2 n); G2P output v, a, L ((2 dim + dim^2) n) */
  mpm_lidx *idx, *count;  /* particle indices grouped by body; counts per body */
  /* The particles' view for the gas's grid pressure (mpm_points), refreshed by each p2g once
   * the points op has handed it out (pts_on); pts_buf holds its volumes (cap). */
  mpm_points pts;
  int pts_on;
  double *pts_buf;
  mpm_module_ops ops; /* the module's table: solid_ops, with p2g_rate for the current rate */
  solid_dilatation dil;
} solid_content;

/* "SECTION.NAME" into key. */
static inline void solid_key(char *key, size_t size, const char *section, const char *name) {
  snprintf(key, size, "%s.%s", section, name);
}

/* A body's `velocity` key: dim values (solid_module.c). */
int solid_body_velocity(const mpm_config *cfg, const char *section, int dim, double v[3]);

/* What seeding body b reads from its section (solid_seed_open); free with solid_seed_close. */
typedef struct solid_seed {
  int b, ppc;
  const char *geom;   /* its [geometry.NAME] */
  mpm_region *region; /* that region */
  mpm_expr *vfield;   /* velocity_field, or NULL: the constant v0 */
  double v0[3];
  char vkey[160]; /* the velocity_field key */
} solid_seed;
int solid_seed_open(mpm_module *m, const mpm_config *cfg, int b, solid_seed *s);
/* Log each body's seeded volume against its geometry's, and warn where they differ by more
 * than 2 % (a face off the particle lattice); after the last seeding (solid_module.c). */
int solid_seed_report(mpm_module *m, const mpm_config *cfg);
void solid_seed_close(solid_seed *s);
/* Append n particles of body s->b at x (component-major, stride n) with ids id, on a lattice
 * of spacing `spacing` (volume spacing^dim): the body's initial state, clamps and tractions. */
int solid_seed_append(mpm_module *m, const mpm_config *cfg, const solid_seed *s, mpm_lidx n,
                      const double *x, const mpm_gidx *id, double spacing);

/* ---- solid_refine.c: the solid on a refinement hierarchy (m->hier; docs/refinement.md) ---- */

/* P2G of the solid's phase: through the hierarchy when m->hier is set, else the plain kernel. */
int solid_deposit(mpm_module *m, const mpm_p2g_args *a);
/* G2P of the solid's phase (a's v_i, a_i: level 0's arrays), likewise. */
int solid_gather(mpm_module *m, const mpm_g2p_args *a);
/* The spacing of the finest level (the grid's without a hierarchy). */
double solid_finest_dx(const mpm_module *m);

/* ---- solid_bulkq_rate.c: the bulk viscosity under the method of lines ------------------------ */

/* p2g_rate (mpm_module.h): tr L of the previewed nodal velocity into pending_divv, and the bulk
 * viscosity of the compressed particles deposited as forces only. */
int solid_bulkq_p2g_rate(mpm_module *m, double t, const double *y);
/* After an accepted step: the pending rate becomes divv, which the stable step reads. */
void solid_bulkq_commit(const mpm_module *m);

/* ---- solid_constraints.c ------------------------------------------------------------------ */

/* Walls on the domain faces and clamped regions: the nodes they hold, listed once. */
int solid_read_constraints(mpm_module *m, const mpm_config *cfg);
/* A rigid body's prescribed velocity and region. */
int solid_read_rigid(mpm_module *m, const mpm_config *cfg, solid_body *body);
/* The [traction.NAME] sections. */
int solid_read_tractions(mpm_module *m, const mpm_config *cfg);
/* After seeding: every traction loaded particles on its bodies' surfaces only (collective). */
int solid_check_tractions(mpm_module *m, const mpm_config *cfg);
/* Is x inside a clamped region? */
int solid_in_clamp(const solid_content *sc, const double *x);
/* The clamps' nodes on the finer levels of m->hier (none without one), rebuilt for a new
 * hierarchy: every node of a level's box that a clamp holds, by the level-0 rule at the
 * level's spacing. */
int solid_clamp_levels(mpm_module *m);
/* At seeding: add the tractions' force on a particle at xp of body region `body` to f. */
void solid_traction_force(solid_content *sc, const mpm_region *body, int dim, double h,
                          const double *xp, mpm_gidx id, double *f);
/* After the nodal solve: a rigid body holds the nodes inside its moving region at time t. */
void solid_hold_rigid_nodes(const solid_body *body, mpm_grid *g, int phase, double t);
/* In G2P: clamped particles keep their place and velocity (zero: seeded at rest); rigid bodies
 * move with theirs. */
void solid_hold_fixed(const mpm_particles *p, int f_fixed, double *ydot);
void solid_move_rigid(const solid_content *sc, const mpm_particles *p, double *ydot);
/* MUSL's new particle velocities: a rigid body's keep its velocity. */
void solid_rigid_velocity(const solid_content *sc, int dim, mpm_lidx n, double *v);

#endif
