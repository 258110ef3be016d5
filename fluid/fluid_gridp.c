/* fluid.pressure = grid: the gas's pressure acts through the nodes, integrated exactly over the
 * grid's spans, in place of the particles' one-point quadrature.
 *
 * The method. Each particle deposits its volume V_p and V_p p_p; the nodal pressure is
 * p_j = sum_p V_p N_j(x_p) p_p / V_j, V_j = sum_p V_p N_j(x_p), a volume-weighted mean, and
 * p_h = sum_j N_j p_j the field it spans. The nodal force is f_i = integral of p_h grad N_i (-grad
 * p in weak form), and the nodal volume rate D_j = integral of N_j div v_h, both exact
 * (common/mpm_span.h). A particle's volume grows by its share of its nodes' rates, in proportion
 * to its volume, dV_p/dt = V_p sum_j N_j(x_p) D_j / V_j, and its internal energy by the pressure's
 * work on that volume, de_p/dt = -p_p dV_p/dt / m_p. Why volume, not mass: particles of one mass
 * but very different volumes share a node where refill and merges have worked (near vacuum, the
 * main job's wake), and a share by mass hands the small one the large one's volume change. With
 * the weights by mass (before 2026-12-03) a double rarefaction refilled every step crushed such
 * a particle to J = 1.5e-3 beside neighbours at J = 2e3 (its energy went negative at t = 0.04),
 * and the main job stopped at 0.59 ms with J <= 0 in the wake; by volume both run (Sod's L1 moved
 * by under 0.2 %). Summed over the
 * particles that work is -sum_j p_j D_j, minus the nodal forces' power sum_i f_i . v_i (the two
 * span integrals are adjoint), so total energy stays exact as with the particles' quadrature; so
 * does momentum (sum_i grad N_i = 0), and mass is untouched. The viscous stresses (physical and
 * artificial) stay on the particles. Why: a constant pressure then gives no force and a constant
 * velocity no volume change at any node whose support lies inside the gas, whatever the
 * particles' positions; the particles' quadrature is exact there only by the symmetry of a
 * uniform lattice, which the corners of a refined region break (docs/refinement.md).
 *
 * On a refinement hierarchy (mpm_hier.h) the deposit of V p is restricted with the volume, the
 * nodal pressure is formed on the active nodes and prolonged, each level integrates over its own
 * spans (those of its region not refined further; level 0 over the domain, halved at the walls),
 * and the level forces and rates are restricted onto the active nodes, the transposes of the
 * prolongations: the composite basis is integrated exactly. A level that stores a whole period
 * (mpm_hier.h, periodic axes) integrates each span once, over [0, N_l) along that axis; the
 * restriction folds what lands on its images. On more than one rank level 0 integrates each
 * rank's owned spans and rank 0 alone the finer levels (alike on every rank), so that the
 * restriction's sum over the ranks (mpm_hier.h, ranks) counts every span once.
 *
 * Walls. Level 0's pad nodes take part like any node (their pressure and rate from their own
 * unfolded volume); the walls then fold their forces as they fold the particles' deposits. A finer
 * level reaching a wall (mpm_hier.h, walls) does the same with its nodes beyond the wall, and
 * integrates only its spans inside it (the wall is a knot of every finer level).
 *
 * Open faces (fluid_open_grid_forces): the span force holds the boundary term p_h N_i n on every
 * face; an open face replaces it by its exterior pressure, integrated exactly over the face, so a
 * uniform stream through inflow, outflow and far-field faces stays uniform to roundoff. The
 * volume rate integrates the domain only, as at a wall.
 *
 * The classic update (usl, musl). The particles deposit V and V p and, beside it, the viscous and
 * artificial stresses of the lagged strain rate; the force acts in the solve as above; the volume
 * rate is integrated at the time-centred nodal velocity vbar (fluid_transfer.c), whose gradient
 * heats the viscous stresses too. The pressure's work over the step, -h sum_j p_j D_j(vbar), is
 * then -h sum_i f_i . vbar_i, exactly the grid's kinetic energy gain from these forces, so usl
 * keeps total energy to roundoff as with the particles' quadrature. MUSL books the same work from
 * its first pass (fluid_module.c, fluid_remap) and moves the volume with the same rate; only the
 * positions follow its remapped velocity.
 *
 * The relaxation (fluid.pressure_relax = beta > 0; the grid pressure only, by default on a
 * hierarchy only). All particles at a node share its volume rate in proportion to their
 * volumes, and a particle's pressure enters the force only through the nodes' means p_j, so
 * nothing pulls a particle whose pressure differs from its neighbours' back to theirs, and the
 * drift of volumes between particles (their paths through different nodes) accumulates. On the
 * 3-D sphere at Mach 0.8 (cases/sphere_m08.ini, one flow-through) particles reached 21 times the
 * free stream's density at J = 0.03 while the nodal density stayed near the free stream's. The
 * relaxation exchanges volume between the particles sharing a node, towards its pressure:
 *   dV_p/dt += V_p sum_j N_j(x_p) kappa_j (p_p - p_j),
 *   m_p de_p/dt += -V_p sum_j N_j(x_p) kappa_j p_j (p_p - p_j),
 * kappa_j = 1 / (beta dx_l Z_j), Z_j = sqrt(gamma p_j rho_j) the node's acoustic impedance
 * (rho_j its gas mass over V_j; beside a wall the mirrored pad nodes fold their mass into the
 * nodes inside, so rho_j reads high there, up to 2^dim times in a corner, and the relaxation is
 * slower by up to its square root), dx_l its level's spacing: a pressure difference decays as
 * exp(-c t / (beta dx_l)), over beta times a cell's sound-crossing time. Both sums vanish at
 * every node, since p_j V_j = sum_p N_j V_p p_p, whatever kappa_j >= 0 is: the gas's volume and
 * its internal energy are unchanged, each node's exchange being valued at its own pressure (so
 * mass, momentum and total energy stay as exact as without it). Per particle m de + p dV = V
 * sum_j N_j kappa_j (p_p - p_j)^2 >= 0 in the rates: entropy never falls (the irreversible
 * equilibration of pressure inside a node, as in a multi-material cell); the classic update's
 * explicit step keeps that while h c / (beta dx) < 2, hence beta >= 1 (read_relax). The
 * particles gather kappa, kappa p and kappa p^2 (relax_fields), from the deposit's own V_j and
 * V_j p_j, which nothing overwrites: the open faces', a solid's or an obstacle's pressure does not
 * enter. A contact (equal pressures) is left alone; at a shock it adds dissipation. It also
 * damps smooth waves, at first order in dx: a resolved wave's particle pressures differ from
 * their nodes' smoothed means by (k dx)^2 / 4 of its amplitude, which the exchange relaxes like a
 * pressure diffusion of about c dx / (4 beta) (a standing wave at 100 cells per wavelength loses
 * 12 % more of its kinetic energy over 5 periods at beta = 4; docs/refinement.md). Hence its
 * default holds on a hierarchy, where the grid pressure is the gas's and its runs are long, and
 * not on a uniform grid, where the grid pressure is a choice made beside solids for acoustics.
 *
 * Obstacles. The massless nodes inside a body are its ghosts: each node with mass takes its own
 * pressure times the integral of their prolonged mask against grad N_i, and the adjoint rate
 * (ghost_forces here, fluid_obstacle_levels.c).
 *
 * A solid. Its region is taken out of both span integrals by its own quadrature, the nodal
 * pressure continued into it from the gas's nodes (fluid_gridp_solid.c). Both integrals read the
 * gas's own phase (its nodal velocity, zero where it has no mass), so they hold under contact's
 * separate fields as under the shared velocity: the gas's p dV stays its forces' work, and at a
 * prestressed body's face the correction's force is the lattice sum of the solid's mass-gradient
 * normal, which contact cancels (a body at rest stays at rest, test_gridp_beside).
 *
 * Scope (check_scope refuses the rest): the method-of-lines ERK pairs with the current strain
 * rate or the classic update, the quadratic B-spline, beside a solid the monolithic or multirate
 * time scheme (multirate's held exchange, not shared) and any coupling scheme, no shifting, the
 * point volume rate, open faces with their default exterior (copies, not gauge). On a hierarchy
 * beside a solid, auto keeps the particles' pressure (fluid_gridp_refine).
 *
 * fluid.pressure = hybrid: the particles' pressure, defect-corrected by the grid's. The
 * particles' quadrature of the pressure's force is exact for a linear pressure only on a uniform
 * lattice; once the particles leave their seeding lattice a uniform pressure p0 gives
 * sum_p V_p p0 grad N_i(x_p) != 0, an indefinite stiffness proportional to p0 that the acoustic
 * motion pumps (a grid-scale transverse mode, docs/gas.md). The hybrid takes the particles'
 * quadrature of the defect p_p - p_h(x_p) and the exact span integral of p_h:
 *   f_i = sum_p V_p (p_p - p_h(x_p)) grad N_i(x_p) + F_i,   F_i = integral of p_h grad N_i,
 *   dV_p/dt = V_p div v_h(x_p) + V_p sum_j N_j(x_p) (D_j - D^Q_j) / V_j,
 * with p_h and p_j as above, D_j = integral of N_j div v_h and D^Q_j = sum_q V_q N_j(x_q)
 * div v_h(x_q), the particles' quadrature of D_j. Energy: with de_p/dt = -p_p dV_p/dt / m_p,
 *   sum_p p_p dV_p/dt = sum_p V_p p_p div v_h(x_p) + sum_j p_j (D_j - D^Q_j)
 * (sum_p V_p N_j(x_p) p_p / V_j = p_j), and the forces' power is
 *   sum_i v_i . f_i = sum_p V_p p_p div v_h(x_p) - sum_j p_j D^Q_j + sum_j p_j D_j
 * (sum_i v_i . grad N_i(x) = div v_h(x), p_h(x_p) = sum_j N_j(x_p) p_j, and the span integrals
 * are adjoint): the two are equal term by term, so total energy stays exact as with either
 * pressure alone. A uniform pressure p_p = p0 gives p_j = p0 and p_h = p0 at every particle
 * whose nodes all have mass, so the particles' share vanishes whatever their positions and only
 * the exact span force remains (no shuffling stiffness); on a uniform lattice, where the
 * particles' quadrature of p_h is nearly the span integral, the force is nearly the particles'.
 * The corrections are those of a solid's region (fluid_gridp_solid.c) with the gas's own
 * particles as the points; the particles keep -V p in their stress (viscous stresses as ever).
 * Without a solid the force's correction is no deposit of its own: the deposit of V and V p
 * forms the nodal pressure at once, and the particles deposit their stress with +V p_h(x_p) on
 * its diagonal (fluid_gridp_stress), -V (p - p_h) in all; their vsig, which the energy rate
 * reads, is left as it was. Beside a solid the nodal pressure waits for the forces, since its
 * continuation reads the solid's points of the same state.
 * Beside a solid the continuation is the grid pressure's, D^Q taken out before its transpose,
 * carried on through the whole solid (fluid_gridp_solid.c, deep), and the span forces on the
 * nodes where the gas has no mass go to the solid (fluid_module_hands_over; the coupler's
 * hand_over) instead of being dropped: momentum stays exact (cases/fsi_box.ini, |P - P0| 3e-16
 * of sqrt(2 M K) where dropping them drifted by 5e-5 under usl and 2e-4 under bs32), and a gas
 * at rest against a prestressed solid stays at rest, the span force inside the solid being
 * the negative of its prestress's node by node. The work of the forces handed over is not in
 * the gas's volume rate, which reads the gas's velocity (zero there): total energy is exact to
 * that work (cases/fsi_box.ini under bs32: 2.0e-6 of the total, against 8.6e-7 with the
 * particles' pressure).
 * Open faces are the grid pressure's: the exterior pressure integrated over the face, the pad
 * nodes' pressure set from it; a uniform stream gives p_p = p_h(x_p), so the particles' share
 * vanishes there too (measured: inflow to outflow, |v - v0| 3e-15 at t = 2, the particle
 * pressure 1e-13). Scope: the grid pressure's, without refinement or obstacles, and beside a solid
 * the monolithic time scheme, or multirate under an ERK pair (MRIStep); not contact, which was
 * not measured with it (hybrid_scope).
 *
 * The filled share (fluid.hybrid_fill = theta, 0.5 by default; without a solid). The grid part
 * is weighted node by node, p_j -> phi_j p_j, phi_j = min(1, V_j / (theta W_j)), W_j the
 * integral of N_j over the domain, and the rate's correction alike, (D_j - D^Q_j) -> phi_j (D_j -
 * D^Q_j): the two sums above then both carry phi_j p_j, so total energy stays exact for any
 * weights; phi = 1 is the hybrid, phi = 0 the particles' pressure. Why: where the particles
 * fill little of a node's support (a near vacuum, gas leaving a wall) V_j is small while the
 * node's exact rate D_j, an integral over its whole support, is not, so the rate's correction
 * per unit volume (D_j - D^Q_j) / V_j grows as the particles shrink there and feeds itself: gas
 * leaving a slip wall (cases/wall_rarefaction.ini, refilled) crushed the particles in the wall's
 * cell to J = 1e-115 at 200 cells and stopped at 400. Weighted, every share 0.42-6.7 / 0.72-3.1
 * / 0.80-3.2 of the exact density at 200 / 400 / 800 cells. A gas that fills its nodes keeps
 * phi = 1 (Toro 3 and the acoustic pulse bit for bit; Sod's contact dips to V_j = 0.43 W_j,
 * where the weight moved its L1 by -0.6 to -2.5 % at 200-800 cells and +0.8 % at 1600). theta =
 * 0.25 left the wall's densities at 0.26-25 times the exact one. */
#include "fluid_internal.h"
#include "fluid_module.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_log.h"
#include "mpm_span.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct fluid_gridp {
  int phase;  /* grid phase whose m_i and mv_i[0] take the deposits of V and V p */
  int nlev;   /* levels (1 without a hierarchy) */
  double *mp; /* the pressure p of each particle (cap) */
  double *s;  /* sum_j N_j D_j / V_j at each particle (cap) */
  mpm_lidx cap;
  /* Per level: nodal pressure, then rate per unit volume (P), forces (F, dim), rates (D), the
   * nodal volume V_j they divide by (M; no wall folds it), and the spans it skips. */
  double *P[MPM_HIER_MAX_LEVELS], *F[MPM_HIER_MAX_LEVELS][MPM_MAX_DIM], *D[MPM_HIER_MAX_LEVELS];
  double *M[MPM_HIER_MAX_LEVELS];
  double *G[MPM_HIER_MAX_LEVELS][MPM_MAX_DIM]; /* the obstacles' span ghost GH (with obstacles) */
  unsigned char *skip[MPM_HIER_MAX_LEVELS];
  mpm_span_set set[MPM_HIER_MAX_LEVELS];
  int beside_solid;      /* the case has a solid: its region is taken out (sol) */
  fluid_gridp_solid sol; /* fluid_gridp_solid.c */
  int hybrid;            /* fluid.pressure = hybrid: the gas's own correction (own, pts) */
  fluid_gridp_solid own;
  mpm_points pts; /* the gas's particles of the deposit's state: positions, V (cap) */
  double *V;      /* each particle's volume V0 J, the weight of its deposit (cap) */
  /* The hybrid without a solid: the deposit forms P at once (early), and the particles deposit
   * the defect's stress sig, their vsig with +V p_h(x_p) (load) on its diagonal. */
  int early;
  double *load, *sig; /* (cap), (dim * dim * cap) */
  /* The hybrid without a solid: its grid part at node j is weighted by min(1, V_j / (fill W_j)),
   * W_j the integral of N_j over the domain (level 0 only; NULL: unweighted). Not on a
   * hierarchy (refined set): a composite basis function beside a finer region is truncated, so
   * its integral is not the uniform grid's W_j, and a full node would read as partly empty. */
  double fill, *W;
  int refined;
  /* fluid.pressure_relax = beta (0: off): the nodal fields kappa, kappa p and kappa p^2 of the
   * relaxation on every level (R), and at the particles (r[1..3]; r[0] is s). */
  double relax, gamma;
  double *R[MPM_HIER_MAX_LEVELS][3];
  double *r[4];
};

static int refuse(const mpm_config *cfg, const char *key, const char *why, int hybrid) {
  if (hybrid)
    return mpm_config_fail(cfg, key,
                           "the hybrid pressure (fluid.pressure = hybrid, on the grid pressure's "
                           "scope) %s; change this key, or set fluid.pressure = particle",
                           why);
  return mpm_config_fail(cfg, key,
                         "the grid pressure (fluid.pressure = grid, or auto with refinement) %s; "
                         "change this key, or set fluid.pressure = particle without refinement",
                         why);
}

/* The first key of a case outside a pressure's scope and why (key NULL: in scope). The scope
 * tests only find it, so that auto can decline silently where an explicit choice refuses. */
typedef struct scope_miss {
  const char *key, *why;
} scope_miss;

static int miss(scope_miss *s, const char *key, const char *why) {
  s->key = key, s->why = why;
  return 0;
}

/* What the hybrid does not carry beyond the grid pressure's scope (key fluid.pressure).
 * Multirate beside a solid under an ERK pair is MRIStep, whose slow right-hand side is the joint
 * cycle: every stage deposits both modules, as the monolithic cycle does. Measured there
 * (bs32, mri_gark_erk33a): the fsi box's momentum 3.3e-16, a pre-stressed slab at rest to
 * 2.3e-13 of c over 1,002 steps, the resonator at 800 cells per metre 1-D to 1.3e-13 of c over
 * 20 periods (test_hybrid_pressure, test_prestress, test_fsi_resonator_mri). Under the classic
 * update multirate is the held exchange, and there the hybrid's momentum drifted by 1e-4 on the
 * fsi box. */
static int hybrid_scope(const fluid_content *fc, const mpm_config *cfg, scope_miss *s) {
  const char *const *names;
  int count;
  s->key = NULL;
  MPM_CALL(mpm_config_instances(cfg, "obstacle", &names, &count));
  if (count > 0)
    return miss(s, "fluid.pressure", "does not carry obstacles (remove the [obstacle.*] sections)");
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &count));
  if (count == 0) return 0;
  const char *time = "monolithic", *scheme = "velocity";
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  MPM_CALL(mpm_config_get_string(cfg, "coupling.scheme", &scheme));
  if (strcmp(time, "multirate") == 0 && fc->tr.classic)
    return miss(s, "fluid.pressure",
                "does not carry a solid under coupling.time = multirate with the classic update "
                "(its held exchange drifts the momentum by 1e-4): use an ERK pair (time.method "
                "= bs32) or coupling.time = monolithic");
  /* Staggered is outside the grid pressure's scope (grid_scope). The grid pressure's contact
   * (test_gridp_beside) was not measured with the particles' share beside it. */
  if (strcmp(scheme, "contact") == 0 || strcmp(scheme, "sharp") == 0)
    return miss(s, "fluid.pressure",
                "does not carry a solid under coupling.scheme = contact or sharp (not "
                "measured): use velocity or traction");
  return 0;
}

/* The grid pressure's scope, which the hybrid shares. */
static int grid_scope(const fluid_content *fc, const mpm_config *cfg, const mpm_grid *g,
                      scope_miss *s) {
  s->key = NULL;
  if (!fc->tr.classic && !fc->current_rate)
    return miss(s, "fluid.strain_rate", "needs the current strain rate (the default)");
  if (g->shape != MPM_SHAPE_QUADRATIC)
    return miss(s, "grid.shape", "integrates the quadratic B-spline's spans");
  if (fc->volume_domain)
    return miss(s, "fluid.volume_rate", "sets the volume rate itself (from the nodes)");
  if (fc->shift > 0.0) return miss(s, "fluid.shift", "is not carried with shifting");
  if (fc->gas.gauge != 0.0)
    return miss(s, "physics.gauge_pressure",
                "integrates the whole pressure and takes no gauge (the "
                "particles' pressure does)");
  const char *const *names;
  int count;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &count));
  const char *time = "monolithic";
  if (count > 0) MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  /* Beside a solid the gas reads the solid's particles in its forces (fluid_gridp_solid.c), as
   * the solid's last deposit left them: the monolithic cycle deposits both at every stage, and
   * multirate's held exchange deposits the solid at the coupling step's start and holds it
   * (its nodes and its points) while the gas advances (coupler/mpm_partitioned.c, hold);
   * MRIStep's slow right-hand side is the joint cycle. Staggered is not measured. */
  if (strcmp(time, "monolithic") != 0 && strcmp(time, "multirate") != 0)
    return miss(s, "coupling.time",
                "beside a solid is carried by the monolithic and multirate time schemes only "
                "(not staggered): use coupling.time = monolithic or multirate");
  const char *exchange = "held";
  if (strcmp(time, "multirate") == 0)
    MPM_CALL(mpm_config_get_string(cfg, "coupling.exchange", &exchange));
  /* shared: the solid advances first and the gas's one step, from the step's start, would read
   * the solid's points of its last substep, a later state than the gas's. */
  if (strcmp(exchange, "shared") == 0)
    return miss(s, "coupling.exchange",
                "reads the solid's particles of the gas's own state, and with shared nodes the "
                "solid has moved on when the gas steps: use coupling.exchange = held");
  int open = 0;
  for (int d = 0; d < g->dim; ++d)
    for (int k = 0; k < 2; ++k) open |= mpm_wall_is_open_gas(fc->walls.face[d][k]);
  const char *exterior = "copies";
  if (open) MPM_CALL(mpm_config_get_string(cfg, "freestream.exterior", &exterior));
  if (strcmp(exterior, "gauge") == 0)
    return miss(s, "freestream.exterior",
                "integrates the open faces' exterior pressure over the face and does not carry "
                "gauge (the particle pressure's gauge points)");
  return 0;
}

/* Refuse an explicit grid or hybrid outside its scope; the first key found is named. */
static int check_scope(const fluid_content *fc, const mpm_config *cfg, const mpm_grid *g,
                       int hybrid) {
  scope_miss s;
  MPM_CALL(grid_scope(fc, cfg, g, &s));
  if (s.key) return refuse(cfg, s.key, s.why, hybrid);
  if (hybrid) MPM_CALL(hybrid_scope(fc, cfg, &s));
  if (s.key)
    return mpm_config_fail(cfg, s.key, "hybrid %s; use fluid.pressure = grid or particle", s.why);
  return 0;
}

/* fluid.pressure_relax: beta, whose default (the key unset) holds on a hierarchy only; below 1
 * refused (beta < time.cfl would let the classic update's explicit relaxation overshoot, the
 * rate being c / (beta dx)). The hybrid does not relax: an explicit key is refused there. */
static int read_relax(fluid_gridp *gp, const mpm_config *cfg, int hybrid) {
  const int set = mpm_config_has(cfg, "fluid.pressure_relax");
  MPM_CALL(mpm_config_get_real(cfg, "fluid.pressure_relax", &gp->relax));
  if (set && hybrid && gp->relax > 0.0)
    return mpm_config_fail(cfg, "fluid.pressure_relax",
                           "relaxes the grid pressure's particles; the hybrid (fluid.pressure = "
                           "hybrid, or auto for a gas alone on a uniform grid) keeps the "
                           "particles' own pressure in their force: remove the key, or set "
                           "fluid.pressure = grid");
  if (set && gp->relax > 0.0 && gp->relax < 1.0)
    return mpm_config_fail(cfg, "fluid.pressure_relax",
                           "below 1 relaxes faster than a step can follow (the rate is c / (beta "
                           "dx)); use 0 (off) or at least 1");
  if (hybrid || (!set && !gp->refined)) gp->relax = 0.0;
  if (hybrid) return 0;
  if (gp->relax > 0.0)
    mpm_log(MPM_LOG_INFO, "pressure relaxation: beta = %g (fluid.pressure_relax%s)", gp->relax,
            set ? "" : ", its default on a hierarchy");
  else
    mpm_log(MPM_LOG_INFO, "pressure relaxation: off (fluid.pressure_relax%s)",
            set ? " = 0" : " unset: off on a uniform grid");
  return 0;
}

/* An explicit fluid.pressure_relax > 0 where the gas does not take the grid pressure. */
static int relax_unused(const fluid_content *fc, const mpm_config *cfg) {
  double beta = 0.0;
  if (fc->gridp || !mpm_config_has(cfg, "fluid.pressure_relax")) return 0;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.pressure_relax", &beta));
  if (beta == 0.0) return 0; /* off, as the particles' pressure is */
  return mpm_config_fail(cfg, "fluid.pressure_relax",
                         "relaxes the grid pressure's particles, and this gas takes the "
                         "particles' pressure (fluid.pressure = particle, or auto beside a "
                         "solid, or outside the hybrid's scope: the log says which); remove the "
                         "key, or set fluid.pressure = grid");
}

/* Check the scope, then set the grid pressure up with its grid phase. */
static int enable(mpm_module *m, const mpm_config *cfg, int hybrid) {
  fluid_content *fc = m->content;
  MPM_CALL(check_scope(fc, cfg, m->grid, hybrid));
  MPM_ALLOC(fc->gridp, 1);
  memset(fc->gridp, 0, sizeof *fc->gridp);
  fc->gridp->hybrid = hybrid;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.hybrid_fill", &fc->gridp->fill));
  fc->gridp->gamma = fc->gas.gamma;
  int levels = 1;
  if (mpm_config_has(cfg, "refine.levels"))
    MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &levels));
  fc->gridp->refined = levels > 1;
  MPM_CALL(read_relax(fc->gridp, cfg, hybrid));
  const char *const *names;
  int count;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &count));
  fc->gridp->beside_solid = count > 0;
  if (count > 0) MPM_CALL(fluid_gridp_solid_init(&fc->gridp->sol, m->grid));
  fc->gridp->sol.deep = hybrid; /* init zeroes it */
  /* The hybrid's corrections deposit into a phase of their own, or share the solid region's
   * (the grid holds at most four phases): the two instances never interleave their deposits. */
  if (hybrid && count > 0) fc->gridp->own.phase = fc->gridp->sol.phase;
  if (hybrid && count == 0) MPM_CALL(fluid_gridp_solid_init(&fc->gridp->own, m->grid));
  fc->gridp->own.pts = &fc->gridp->pts;
  return mpm_grid_add_phase(m->grid, "fluid_pressure", &fc->gridp->phase);
}

/* Under the classic update no preview precedes the forces (coupler/mpm_cycle.c), so the open
 * faces' characteristic pressure (fluid_open_grid_forces) reads the nodal velocity the previous
 * step left, which a checkpoint does not hold. Measured with the hybrid under usl: a uniform
 * Mach 0.5 stream through farfield faces drifts by 2.7e-2 over 4 s (test_gas_boundaries; bs32
 * 1.1e-15), and a restart of cases/acoustic_pulse.ini differs from the straight run by 1.2e-17
 * (test_restart_cases), the grid pressure's alike. Auto keeps the particles' pressure there. */
static int lagged_faces(const fluid_content *fc, const mpm_grid *g) {
  int lagged = 0;
  for (int d = 0; fc->tr.classic && d < g->dim; ++d)
    for (int k = 0; k < 2; ++k)
      lagged |= fc->walls.face[d][k] == MPM_WALL_FARFIELD ||
                fc->walls.face[d][k] == MPM_WALL_SUBSONIC_INFLOW;
  return lagged;
}

/* fluid.pressure = auto. With refinement the grid pressure (fluid_gridp_refine: the particles'
 * quadrature disturbs the gas at the refined regions' corners). Beside a solid under the classic
 * update the particles' pressure: its PIC share keeps the gas beside the solid stable
 * (fluid_module.c, pic_auto), and the hybrid there costs 1.5-2.4 times a step (docs/gas.md).
 * Elsewhere the hybrid wherever its scope holds: a gas alone gets no grid-scale mode from the
 * uniform part of its pressure and Sod's L1 falls; beside a solid under the ERK pairs, which
 * take no PIC share, the particles' pressure grows that mode from roundoff (the resonator at
 * 800 cells per metre under bs32: the guard stopped it at t = 1.53; the hybrid held it at
 * 6.8e-14 of c over 20 periods, test_fsi_resonator long). Outside the scope the particles'
 * pressure, silently.
 * One log line says which and why. */
static int choose_auto(mpm_module *m, const mpm_config *cfg) {
  const char *const *names;
  int nsolid, levels = 1;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &nsolid));
  if (mpm_config_has(cfg, "refine.levels"))
    MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &levels));
  const int classic = ((const fluid_content *)m->content)->tr.classic;
  if (nsolid > 0 && (classic || levels > 1)) {
    mpm_log(MPM_LOG_INFO, "pressure: particle (fluid.pressure = auto, beside a solid%s)",
            classic ? " under the classic update" : " on a hierarchy");
    return 0;
  }
  /* On a hierarchy the hybrid's particle share reflects waves at a box's edges and corners
   * (an acoustic pulse crossing a level-1 box under usl: energy fraction 1.27e-3 against the
   * grid pressure's 5.6e-4; test_refine_usl_pulse), so auto takes the grid pressure there
   * (fluid_gridp_refine enables it); the hybrid is a choice (docs/refinement.md). */
  if (levels > 1) {
    mpm_log(MPM_LOG_INFO, "pressure: grid (fluid.pressure = auto, refine.levels = %d)", levels);
    return 0;
  }
  /* The hybrid's own limits first: they hold whatever the grid pressure's keys say. */
  scope_miss s;
  MPM_CALL(hybrid_scope(m->content, cfg, &s));
  if (!s.key) MPM_CALL(grid_scope(m->content, cfg, m->grid, &s));
  if (!s.key && lagged_faces(m->content, m->grid))
    miss(&s, "time.method",
         "reads the previous step's nodal velocity at farfield and subsonic_inflow faces under "
         "usl and musl");
  /* Measured (cases/double_rarefaction.ini, 200 cells, usl, fluid.shift = 0): with merges and
   * splits and the nodal means by mass the hybrid stopped at t = 0.040 (refill every step) or
   * 0.064 (no refill), e < 0 at the centre's near vacuum. By volume (the header) it reaches
   * t = 0.15, but with refill every step in 874 steps and 18 retries against the particles'
   * pressure's 390 and 1: regularised scenes keep the particles' pressure. */
  if (!s.key && ((const fluid_content *)m->content)->reg_every > 0)
    miss(&s, "fluid.regularise_every",
         "takes twice the steps with merges, splits and refills in a near vacuum (the double "
         "rarefaction)");
  if (s.key) {
    mpm_log(MPM_LOG_INFO, "pressure: particle (fluid.pressure = auto: the hybrid %s%s%s)", s.why,
            strcmp(s.key, "fluid.pressure") ? "; key " : "",
            strcmp(s.key, "fluid.pressure") ? s.key : "");
    return 0;
  }
  mpm_log(MPM_LOG_INFO, "pressure: hybrid (fluid.pressure = auto: %s, in the hybrid's scope)",
          nsolid > 0 ? "a gas beside a solid under an ERK pair" : "a gas without a solid");
  return enable(m, cfg, 1);
}

int fluid_gridp_weighted(const fluid_content *fc) {
  return fc->gridp && fc->gridp->hybrid && !fc->gridp->beside_solid && !fc->gridp->refined &&
         fc->gridp->fill > 0.0;
}

int fluid_gridp_init(mpm_module *m, const mpm_config *cfg) {
  const char *form;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.pressure", &form));
  const int hybrid = strcmp(form, "hybrid") == 0;
  if (strcmp(form, "auto") == 0)
    MPM_CALL(choose_auto(m, cfg));
  else if (strcmp(form, "grid") == 0 || hybrid)
    return enable(m, cfg, hybrid);
  int levels = 1;
  if (mpm_config_has(cfg, "refine.levels"))
    MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &levels));
  return levels > 1 ? 0 : relax_unused(m->content, cfg); /* refined: fluid_gridp_refine */
}

int fluid_gridp_refine(mpm_module *m, const mpm_config *cfg, mpm_hier *h) {
  const char *form, *const *solids;
  int nsolid;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.pressure", &form));
  MPM_CALL(mpm_config_instances(cfg, "solid", &solids, &nsolid));
  if (strcmp(form, "hybrid") == 0 && nsolid > 0)
    return h ? mpm_config_fail(cfg, "fluid.pressure",
                               "hybrid does not carry refinement beside a solid (not measured); "
                               "use fluid.pressure = grid, or set refine.levels = 1")
             : 0;
  /* Beside a solid auto keeps the particles' pressure (the sim then keeps the levels' faces off
   * corners in the gas, coupler/mpm_refine.c, bands); grid takes the solid's region out of its
   * span integrals (fluid_gridp_solid.c) and runs in any box. */
  if (nsolid > 0 && strcmp(form, "grid") != 0) {
    MPM_CALL(relax_unused(m->content, cfg));
    return h ? mpm_hier_add_phases(h) : 0;
  }
  if (strcmp(form, "particle") == 0)
    return mpm_config_fail(cfg, "fluid.pressure",
                           "the particles' quadrature is not exact at the corners of a refined "
                           "region and disturbs the gas there (docs/refinement.md); remove the "
                           "key or set fluid.pressure = grid");
  if (!((fluid_content *)m->content)->gridp) MPM_CALL(enable(m, cfg, 0));
  return h ? mpm_hier_add_phases(h) : 0;
}

int fluid_module_reads_beside(const mpm_module *m) {
  const fluid_gridp *gp = ((const fluid_content *)m->content)->gridp;
  return gp && gp->beside_solid;
}

int fluid_module_hands_over(const mpm_module *m) {
  const fluid_gridp *gp = ((const fluid_content *)m->content)->gridp;
  return gp && gp->beside_solid && gp->hybrid;
}

void fluid_gridp_reset(fluid_content *fc) {
  fluid_gridp *gp = fc->gridp;
  if (!gp) return;
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l) {
    free(gp->P[l]), free(gp->D[l]), free(gp->M[l]), free(gp->skip[l]);
    gp->P[l] = gp->D[l] = gp->M[l] = NULL, gp->skip[l] = NULL;
    for (int d = 0; d < MPM_MAX_DIM; ++d) free(gp->F[l][d]), gp->F[l][d] = NULL;
    for (int d = 0; d < MPM_MAX_DIM; ++d) free(gp->G[l][d]), gp->G[l][d] = NULL;
    for (int j = 0; j < 3; ++j) free(gp->R[l][j]), gp->R[l][j] = NULL;
  }
  free(gp->W), gp->W = NULL;
  fluid_gridp_solid_free(&gp->sol); /* its level scalars are sized by the hierarchy's levels */
  fluid_gridp_solid_free(&gp->own);
}

void fluid_gridp_destroy(fluid_content *fc) {
  fluid_gridp *gp = fc->gridp;
  if (!gp) return;
  fluid_gridp_reset(fc);
  free(gp->mp), free(gp->s), free(gp->V), free(gp->load), free(gp->sig);
  for (int j = 1; j < 4; ++j) free(gp->r[j]);
  free(gp);
  fc->gridp = NULL;
}

static const mpm_grid *level_grid(const mpm_module *m, int l) {
  return m->hier ? m->hier->level[l].grid : m->grid;
}

/* Along d, the spans of level l >= 1 inside the walls (mpm_hier.h, walls: a wall is a knot of
 * the level, between spans 2^(l-1) - 1 and 2^(l-1) at the low face and N_l + 2^(l-1) - 1 and
 * N_l + 2^(l-1) at the high one), so that the level integrates the domain only, as level 0
 * does with its halved face spans. */
static void wall_spans(const mpm_hier *h, int l, int d, mpm_span_set *s) {
  const int half = 1 << (l - 1), N = h->level[0].grid->ncells[d] << l;
  if (h->wall[d][0]) s->lo[d] = MPM_MAX(s->lo[d], half);
  if (h->wall[d][1]) s->hi[d] = MPM_MIN(s->hi[d], N + half - 1);
}

/* The integral over [0, r] of the quadratic B-spline centred at 0, r in cells (odd in r). */
static double bspline2_integral(double r) {
  const double a = fabs(r), sgn = r < 0.0 ? -1.0 : 1.0;
  if (a >= 1.5) return 0.5 * sgn;
  if (a <= 0.5) return sgn * (0.75 * a - a * a * a / 3.0);
  const double b = 1.5 - a; /* 1/2 minus the tail beyond a, (1.5 - a)^3 / 6 */
  return sgn * (0.5 - b * b * b / 6.0);
}

/* W_j = integral over the domain of N_j on level 0's nodes: dx^dim inside, less where the
 * support crosses a wall or open face (periodic axes wrap and lose nothing). */
int fluid_gridp_geometric_volume(const mpm_grid *g, double **W) {
  MPM_ALLOC(*W, (size_t)g->nnodes);
  for (mpm_lidx k = 0; k < g->nnodes; ++k) {
    mpm_lidx r = k;
    double w = 1.0;
    for (int d = 0; d < g->dim; ++d) {
      const int i = g->box_lo[d] + (int)(r % g->box_n[d]);
      r /= g->box_n[d];
      const double lo = -i, hi = g->ncells[d] - i; /* the domain's faces, in cells from node i */
      w *= g->dx * (g->periodic[d] ? 1.0 : bspline2_integral(hi) - bspline2_integral(lo));
    }
    (*W)[k] = w;
  }
  return 0;
}

/* The per-level arrays and span sets, on first use (the hierarchy is static). */
static int ensure_levels(mpm_module *m, fluid_gridp *gp) {
  if (gp->P[0]) return 0;
  const mpm_hier *h = m->hier;
  gp->nlev = h ? h->nlevels : 1;
  if (fluid_gridp_weighted(m->content)) MPM_CALL(fluid_gridp_geometric_volume(m->grid, &gp->W));
  MPM_CALL(fluid_obstacles_levels(&((fluid_content *)m->content)->obs, m->grid, h, 1));
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const size_t nn = (size_t)g->nnodes;
    MPM_ALLOC(gp->P[l], nn);
    MPM_ALLOC(gp->D[l], nn);
    MPM_ALLOC(gp->M[l], nn);
    for (int d = 0; d < g->dim; ++d) MPM_ALLOC(gp->F[l][d], nn);
    for (int d = 0; ((fluid_content *)m->content)->obs.count && d < g->dim; ++d)
      MPM_ALLOC(gp->G[l][d], nn);
    for (int j = 0; gp->relax > 0.0 && j < 3; ++j) MPM_ALLOC(gp->R[l][j], nn);
    if (l == 0) {
      if (h) {
        MPM_ALLOC(gp->skip[0], nn);
        memcpy(gp->skip[0], h->level[0].refined, nn);
      }
      gp->set[0] = mpm_span_owned(g, gp->skip[0]);
      continue;
    }
    MPM_ALLOC(gp->skip[l], nn);
    for (size_t n = 0; n < nn; ++n)
      gp->skip[l][n] = !h->level[l].covered[n] || h->level[l].refined[n];
    mpm_span_set *s = &gp->set[l];
    *s = (mpm_span_set){.skip = gp->skip[l]};
    for (int d = 0; d < g->dim; ++d) { /* the spans in [0, N_l) where the level wraps */
      const int N = h->level[l].period[d];
      s->lo[d] = N ? 0 : g->box_lo[d], s->hi[d] = N ? N - 1 : g->box_lo[d] + g->box_n[d] - 1;
      wall_spans(h, l, d, s);
    }
    /* With more than one rank, rank 0 integrates the finer levels and the others give zeros: the
     * restriction sums the ranks' shares (mpm_hier.h). */
    if (m->grid->rank != 0) s->hi[0] = s->lo[0] - 1;
  }
  return 0;
}

static int ensure_particles(fluid_gridp *gp, mpm_lidx cap, int dim) {
  if (gp->cap >= cap && gp->mp) return 0;
  free(gp->mp), free(gp->s), free(gp->V), free(gp->load), free(gp->sig);
  gp->mp = gp->s = gp->V = gp->load = gp->sig = NULL;
  for (int j = 1; j < 4; ++j) free(gp->r[j]), gp->r[j] = NULL;
  MPM_ALLOC(gp->mp, (size_t)cap);
  MPM_ALLOC(gp->s, (size_t)cap);
  for (int j = 1; gp->relax > 0.0 && j < 4; ++j) MPM_ALLOC(gp->r[j], (size_t)cap);
  gp->r[0] = gp->s;
  MPM_ALLOC(gp->V, (size_t)cap);
  if (gp->hybrid) MPM_ALLOC(gp->load, (size_t)cap);
  if (gp->hybrid) MPM_ALLOC(gp->sig, (size_t)dim * dim * cap);
  gp->cap = cap;
  return 0;
}

/* out[l] = num[l] / V_j on the active nodes with gas, 0 elsewhere. */
static void per_volume(const mpm_module *m, const fluid_gridp *gp, double *const *num,
                       double *const *out) {
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const double *vol = gp->M[l];
    const unsigned char *act = m->hier ? m->hier->level[l].active : NULL;
    for (mpm_lidx k = 0; k < g->nnodes; ++k)
      out[l][k] = (!act || act[k]) && vol[k] > 0.0 ? num[l][k] / vol[k] : 0.0;
  }
}

/* The hybrid's weight of its grid part (see the header): a[j] *= min(1, V_j / (fill W_j)) on
 * level 0. */
static void fill_weight(const mpm_module *m, const fluid_gridp *gp, double *a) {
  if (!gp->W) return;
  const double *V = gp->M[0];
  for (mpm_lidx k = 0; k < m->grid->nnodes; ++k) {
    const double full = gp->fill * gp->W[k];
    if (V[k] < full) a[k] *= V[k] / full;
  }
}

/* The nodal pressure P of the deposits of V and V p on every level (continued into a solid's
 * region, its open faces' pad nodes set, prolonged), and the volumes M it divides by. */
static int nodal_pressure(mpm_module *m) {
  fluid_content *fc = m->content;
  fluid_gridp *gp = fc->gridp;
  double *Q[MPM_HIER_MAX_LEVELS][MPM_MAX_DIM] = {{NULL}};
  if (m->hier) mpm_hier_restrict(m->hier, gp->phase);
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid_phase *ph = &level_grid(m, l)->phase[gp->phase];
    Q[l][0] = ph->m_i, Q[l][1] = ph->mv_i[0];
  }
  MPM_CALL(mpm_grid_halo_reverse(m->grid, Q[0], 2));
  /* Each level's volume sum_p V_p N_j, as the pressure and the rates divide by it. */
  for (int l = 0; l < gp->nlev; ++l)
    memcpy(gp->M[l], Q[l][0], sizeof(double) * (size_t)level_grid(m, l)->nnodes);
  double *q[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < gp->nlev; ++l) q[l] = Q[l][1];
  per_volume(m, gp, q, gp->P);
  fill_weight(m, gp, gp->P[0]);
  fluid_open_grid_pressure(fc->open, gp->P[0]);
  if (gp->beside_solid)
    MPM_CALL(fluid_gridp_solid_pressure(m, &gp->sol, gp->P, (const double *const *)gp->M));
  return fluid_gridp_prolong(m, gp->P);
}

int fluid_gridp_deposit(mpm_module *m, const double *y, const fluid_batch *b) {
  fluid_content *fc = m->content;
  fluid_gridp *gp = fc->gridp;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  MPM_CALL(ensure_levels(m, gp));
  MPM_CALL(ensure_particles(gp, fc->cap, dim));
  /* vsig holds -V p on its diagonal (fluid_stress_pressure): keep p, deposit no stress (the
   * hybrid keeps it, and the particles' positions and volumes for its correction). */
  for (mpm_lidx i = 0; i < n; ++i) {
    gp->V[i] = b->V0[i] * b->J[i];
    gp->mp[i] = -b->vsig[i] / gp->V[i];
  }
  if (gp->hybrid) {
    gp->pts = (mpm_points){.n = n, .V = gp->V};
    for (int d = 0; d < dim; ++d) gp->pts.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n;
  } else {
    memset(b->vsig, 0, sizeof(double) * (size_t)dim * dim * n);
  }
  if (m->hier) {
    mpm_hier_phase_zero(m->hier, gp->phase);
  } else { /* the arrays the two-scalar deposit fills, the only ones nodal_pressure reads */
    const size_t bytes = sizeof(double) * (size_t)m->grid->nnodes;
    memset(m->grid->phase[gp->phase].m_i, 0, bytes);
    memset(m->grid->phase[gp->phase].mv_i[0], 0, bytes);
  }
  /* The lean two-scalar deposit (mpm_kernels.h): V into m_i, V p into mv_i[0]. */
  mpm_p2g_args a = {.n = n, .m = gp->V, .s = gp->mp, .lp = fc->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n;
  int rc = 0;
  fluid_p2g_any(m, gp->phase, &a, &rc);
  MPM_CALL(rc);
  /* The hybrid without a solid: the force's correction -sum_p V_p p_h(x_p) grad N_i joins the
   * particles' own deposit (fluid_gridp_stress), one deposit fewer. Beside a solid the nodal
   * pressure waits for the forces: its continuation reads the solid's points of this state. */
  gp->early = gp->hybrid && !gp->beside_solid;
  if (!gp->early) return 0;
  MPM_CALL(nodal_pressure(m));
  double *load;
  MPM_CALL(fluid_gridp_points_load(m, &gp->own, gp->P, &load));
  memcpy(gp->load, load, sizeof(double) * (size_t)n);
  return 0;
}

const double *fluid_gridp_stress(const mpm_module *m, const double *vsig) {
  const fluid_gridp *gp = ((const fluid_content *)m->content)->gridp;
  if (!gp || !gp->early) return vsig;
  const int dim = m->grid->dim;
  const size_t n = (size_t)m->particles->n;
  memcpy(gp->sig, vsig, sizeof(double) * (size_t)dim * dim * n);
  for (int d = 0; d < dim; ++d)
    for (size_t i = 0; i < n; ++i) gp->sig[(size_t)(d * dim + d) * n + i] += gp->load[i];
  return gp->sig;
}

/* Restrict level arrays a[l][0 .. nf) onto the active nodes (finest level first) and sum level
 * 0's ghosts into their owners. */
static int restrict_all(mpm_module *m, double *a[][MPM_MAX_DIM], int nf) {
  for (int l = m->hier ? m->hier->nlevels - 1 : 0; l >= 1; --l)
    mpm_hier_restrict_level(m->hier, l, a[l], a[l - 1], nf);
  return mpm_grid_halo_reverse(m->grid, a[0], nf);
}

/* Fill level 0's ghosts from their owners and prolong the scalar a[l] into the inactive
 * nodes. */
int fluid_gridp_prolong(mpm_module *m, double **a) {
  MPM_CALL(mpm_grid_halo_forward(m->grid, &a[0], 1));
  for (int l = 1; m->hier && l < m->hier->nlevels; ++l)
    mpm_hier_prolong_level(m->hier, l, (const double *const *)&a[l - 1], &a[l], 1);
  return 0;
}

/* The obstacles' span ghost (fluid_obstacle_levels.c): the mask of the massless nodes inside a
 * body, prolonged, integrated against grad N_i over each level's spans and restricted (GH, kept
 * for the rate), into the force p_i GH_i of every node with mass. D is scratch here. */
static int ghost_forces(mpm_module *m, fluid_gridp *gp) {
  fluid_obstacles *o = &((fluid_content *)m->content)->obs;
  const int dim = m->grid->dim;
  if (o->count == 0) return 0;
  const mpm_grid *grids[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < gp->nlev; ++l) { /* V p of the active nodes for the surface output */
    const mpm_grid *g = grids[l] = level_grid(m, l);
    for (mpm_lidx k = 0; k < g->nnodes; ++k) gp->D[l][k] = gp->M[l][k] * gp->P[l][k];
  }
  fluid_obstacles_span_surface(o, grids, (const double *const *)gp->M,
                               (const double *const *)gp->D);
  for (int l = 0; l < gp->nlev; ++l)
    fluid_obstacles_span_mask(o, l, level_grid(m, l), gp->M[l],
                              m->hier ? m->hier->level[l].active : NULL, gp->D[l]);
  MPM_CALL(fluid_gridp_prolong(m, gp->D));
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    for (int d = 0; d < dim; ++d) memset(gp->G[l][d], 0, sizeof(double) * (size_t)g->nnodes);
    mpm_span_force(g, &gp->set[l], gp->D[l], gp->G[l]);
  }
  MPM_CALL(restrict_all(m, gp->G, dim));
  for (int l = 0; l < gp->nlev; ++l)
    fluid_obstacles_span_force(o, l, m->hier ? m->hier->level[l].grid : m->grid, m->phase, gp->P[l],
                               gp->M[l], m->hier ? m->hier->level[l].active : NULL,
                               (const double *const *)gp->G[l]);
  return 0;
}

int fluid_gridp_forces(mpm_module *m) {
  fluid_content *fc = m->content;
  fluid_gridp *gp = fc->gridp;
  const int dim = m->grid->dim;
  if (!gp->early) MPM_CALL(nodal_pressure(m));
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    for (int d = 0; d < dim; ++d) memset(gp->F[l][d], 0, sizeof(double) * (size_t)g->nnodes);
    mpm_span_force(g, &gp->set[l], gp->P[l], gp->F[l]);
  }
  const double *v0[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d) v0[d] = m->grid->phase[m->phase].v_i[d];
  MPM_CALL(fluid_open_grid_forces(fc->open, m->grid, gp->P[0], v0, gp->F[0]));
  MPM_CALL(restrict_all(m, gp->F, dim));
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const mpm_grid_phase *ph = &g->phase[m->phase];
    for (int d = 0; d < dim; ++d)
      for (mpm_lidx k = 0; k < g->nnodes; ++k) ph->f_i[d][k] += gp->F[l][d][k];
  }
  if (gp->beside_solid) MPM_CALL(fluid_gridp_solid_force(m, &gp->sol, gp->P));
  if (gp->hybrid && !gp->early) MPM_CALL(fluid_gridp_points_force(m, &gp->own, gp->P));
  return ghost_forces(m, gp);
}

/* The relaxation's nodal fields kappa_j, kappa_j p_j and kappa_j p_j^2 (see the header) on the
 * active nodes with gas, from the deposit's own V_j and V_j p_j (not the pressure the open faces,
 * a solid's continuation or the obstacles set: the identities rest on the deposit's), prolonged,
 * as scalars 1 to 3 of s. */
static int relax_fields(mpm_module *m, fluid_gridp *gp, mpm_hier_scalars *s) {
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const double *Vp = g->phase[gp->phase].mv_i[0], *mass = g->phase[m->phase].m_i;
    const double *V = gp->M[l];
    const unsigned char *act = m->hier ? m->hier->level[l].active : NULL;
    double *k0 = gp->R[l][0], *k1 = gp->R[l][1], *k2 = gp->R[l][2];
    for (mpm_lidx k = 0; k < g->nnodes; ++k) {
      k0[k] = k1[k] = k2[k] = 0.0;
      if ((act && !act[k]) || !(V[k] > 0.0) || !(mass[k] > 0.0) || !(Vp[k] > 0.0)) continue;
      const double p = Vp[k] / V[k], Z = sqrt(gp->gamma * p * mass[k] / V[k]);
      k0[k] = 1.0 / (gp->relax * g->dx * Z), k1[k] = k0[k] * p, k2[k] = k1[k] * p;
    }
  }
  for (int l = 0; l < gp->nlev; ++l)
    for (int j = 0; j < 3; ++j) s->s_i[l][1 + j] = gp->R[l][j];
  MPM_CALL(mpm_grid_halo_forward(m->grid, gp->R[0], 3));
  for (int l = 1; m->hier && l < m->hier->nlevels; ++l)
    mpm_hier_prolong_level(m->hier, l, (const double *const *)gp->R[l - 1], gp->R[l], 3);
  return 0;
}

int fluid_gridp_nodal_rate(mpm_module *m, const mpm_hier_nodal *vel, mpm_hier_scalars *s) {
  fluid_content *fc = m->content;
  fluid_gridp *gp = fc->gridp;
  double *D[MPM_HIER_MAX_LEVELS][MPM_MAX_DIM] = {{NULL}};
  for (int l = 0; l < gp->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const double *v[MPM_MAX_DIM];
    for (int d = 0; d < g->dim; ++d) v[d] = vel ? vel->v_i[l][d] : g->phase[m->phase].v_i[d];
    memset(gp->D[l], 0, sizeof(double) * (size_t)g->nnodes);
    mpm_span_divergence(g, &gp->set[l], v, gp->D[l]);
    D[l][0] = gp->D[l];
  }
  MPM_CALL(restrict_all(m, D, 1));
  if (gp->hybrid) MPM_CALL(fluid_gridp_points_rate(m, &gp->own, vel, gp->D)); /* before sol's */
  if (gp->beside_solid)
    MPM_CALL(fluid_gridp_solid_rate(m, &gp->sol, vel, gp->D, (const double *const *)gp->M));
  for (int l = 0; fc->obs.count && l < gp->nlev; ++l)
    fluid_obstacles_span_rate(level_grid(m, l), m->phase, gp->M[l],
                              m->hier ? m->hier->level[l].active : NULL,
                              (const double *const *)gp->G[l], gp->D[l]);
  per_volume(m, gp, gp->D, gp->P); /* P now holds the rate per unit volume */
  fill_weight(m, gp, gp->P[0]);
  MPM_CALL(fluid_gridp_prolong(m, gp->P));
  memset(s, 0, sizeof *s);
  for (int l = 0; l < gp->nlev; ++l) s->s_i[l][0] = gp->P[l];
  if (gp->relax > 0.0) MPM_CALL(relax_fields(m, gp, s));
  return 0;
}

void fluid_gridp_work(const mpm_module *m, const double *y, const double *L, double *power) {
  const fluid_content *fc = m->content;
  const fluid_gridp *gp = fc->gridp;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const double *J = y + (size_t)p->offset[FLUID_J] * n;
  for (mpm_lidx i = 0; i < n; ++i) power[i] -= gp->mp[i] * V0[i] * J[i] / mass[i] * gp->s[i];
  /* The relaxation: its work at the nodes' pressures, then its volume rate joins s (the work
   * above read s without it). */
  if (gp->relax > 0.0) {
    const double *a = gp->r[1], *b = gp->r[2], *c = gp->r[3];
    for (mpm_lidx i = 0; i < n; ++i) {
      power[i] -= V0[i] * J[i] / mass[i] * (gp->mp[i] * b[i] - c[i]);
      gp->s[i] += gp->mp[i] * a[i] - b[i];
    }
  }
  if (!gp->hybrid) return;
  for (int d = 0; d < p->dim; ++d) /* the point rate, whose work energy_rate has booked */
    for (mpm_lidx i = 0; i < n; ++i) gp->s[i] += L[(size_t)(d * p->dim + d) * n + i];
}

double *const *fluid_gridp_rate_out(const fluid_content *fc, int *ns) {
  const fluid_gridp *gp = fc->gridp;
  if (ns) *ns = gp->relax > 0.0 ? 4 : 1;
  return gp->r;
}
