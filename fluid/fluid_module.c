/* Fluid module: the phases of an MPM right-hand side for a compressible ideal gas, its case
 * keys and its construction.
 *
 * Per particle: dx/dt = sum S v_i, dv/dt = sum S a_i (or the FLIP/PIC/APIC update of the
 * classic step), dJ/dt = J tr L, de/dt = grid power per unit mass (below). The stress
 * deposited at P2G is the ideal-gas pressure plus the viscous and artificial viscous terms
 * of a strain rate D. In the classic update that is the previous step's rate, stored in the
 * fields divv and D: the stress is updated last, as in USL. The ERK pairs take the rate of the
 * state itself (current_rate, below), so that their RHS is a function of y alone; with
 * fluid.strain_rate = lagged they read the fields instead, the rate of the previous step.
 *
 * Energy. Each particle's internal energy takes the work its stress does on the grid,
 * (V sigma : L) / m per unit mass, with L the gradient of the same nodal velocity that moves
 * the particles. Summed over the particles that is minus the power of the internal nodal
 * forces, sum_i f_i . v_i. In the method-of-lines RHS the particles' kinetic energy gains
 * exactly sum_i f_i . v_i (sum_p m_p v_p . sum_i S a_i = sum_i a_i . (m v)_i), so the semi-
 * discrete system conserves mass, momentum and total energy, with or without walls (a wall
 * node has no normal velocity and no normal acceleration; mirrored pad nodes fold back
 * symmetrically). The classic update replaces v by v_new over the step h; its kinetic energy
 * then changes by m (|v_new|^2 - |v|^2) / 2, which the grid work does not match: the
 * transfer loses (PIC, APIC) or moves (FLIP) energy. Each particle therefore also takes
 *   h sum_i S_ip (a_i . v_i^{n+1}) - (|v_new|^2 - |v|^2) / 2,
 * whose sum over the particles (weighted by m_p) closes the budget exactly: total energy is
 * conserved to roundoff by usl and musl with any transfer, and the kinetic energy the
 * transfer removes becomes heat in the particles it was taken from. */
#include "fluid_module.h"

#include "fluid_eos.h"
#include "fluid_internal.h"

#include "mpm_cells.h"
#include "mpm_error.h"
#include "mpm_kernels.h"
#include "mpm_log.h"
#include "mpm_timer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const mpm_key_spec fluid_keys[] = {
    {"fluid.gamma", MPM_KEY_REAL, "1.4", 1, HUGE_VAL, 1, 0, NULL,
     "ratio of specific heats c_p / c_v of the ideal gas, > 1 (air: 1.4)", 0, "-"},
    {"fluid.R", MPM_KEY_REAL, "287.05", 0, HUGE_VAL, 1, 0, NULL,
     "specific gas constant, J/(kg K), for the temperature and entropy output (air: 287.05)", 0,
     "J/(kg K)"},
    {"fluid.viscosity", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "dynamic viscosity mu, Pa s (0: inviscid; air: 1.8e-5)", 0, "Pa s"},
    {"fluid.av_form", MPM_KEY_ENUM, "vnr", 0, 0, 0, 0, "vnr|riemann",
     "form of the artificial viscosity q, in compression only, with du = l |tr D|, l = grid.dx: "
     "vnr (von Neumann-Richtmyer + Landshoff: q = rho du (c_lin c + c_quad du)) or riemann "
     "(Kuropatenko's two-shock form q = rho du (1 - psi) (c_quad a du + sqrt(c_quad^2 a^2 du^2 "
     "+ c_lin^2 c^2)), a = (gamma + 1) / 4, with a Christensen limiter psi that switches it off "
     "in smooth compression; see docs/gas.md)",
     0, NULL},
    {"fluid.av_linear", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 0, 0, NULL,
     "linear artificial viscosity coefficient c_lin (see av_form; default 0.5 with vnr, "
     "1 with riemann)",
     1, "-"},
    {"fluid.av_quadratic", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 0, 0, NULL,
     "quadratic artificial viscosity coefficient c_quad (see av_form; default 2 with vnr, "
     "4 with riemann)",
     1, "-"},
    {"fluid.pic_fraction", MPM_KEY_REAL, NULL, 0, 1, 0, 0, NULL,
     "the gas's own PIC share of the particle velocity update, in place of "
     "transfer.pic_fraction (default: that if set, else 0.02 for a gas beside a solid under "
     "its particles' pressure, which it keeps from growing a grid-scale mode, else 0), for a "
     "step at the gas's own stable step at time.cfl = 0.4 (any other step takes the share "
     "that damps as much per unit time, so neither time.cfl nor a stiffer module's step "
     "changes the damping); damps the gas's particle noise without damping the solid; "
     "classic update only",
     1, "-"},
    {"fluid.strain_rate", MPM_KEY_ENUM, "current", 0, 0, 0, 0, "current|lagged",
     "ERK pairs: the strain rate the artificial and physical viscosity see: current (of the "
     "state itself: a second deposit and a gather, about 1.6x the gas's work per RHS) or lagged "
     "(of the previous step: cheaper, but it holds every ERK pair to first order in time "
     "wherever the artificial viscosity acts); the classic update always lags",
     0, NULL},
    {"fluid.mol_damping", MPM_KEY_REAL, "0", 0, 1, 0, 0, NULL,
     "ERK pairs: the rate, in units of c / dx, at which the particle velocity the grid does not "
     "see (v_p - sum S v_i, filtered once more through the grid so that smooth flow keeps it) "
     "relaxes, its kinetic energy becoming the particle's heat (0: off). Stops a transverse "
     "grid-scale mode that the method of lines grows from roundoff where particles sit off "
     "their lattice (docs/gas.md; 0.1 cures it); mass, momentum and total energy stay exact",
     0, "-"},
    {"fluid.volume_rate", MPM_KEY_ENUM, "point", 0, 0, 0, 0, "point|domain",
     "the rate dJ/dt = J tr L that moves a gas particle's volume: point (the nodal velocity's "
     "divergence at the particle) or domain (its flux through the faces of the particle's "
     "domain, a box of side min((J V0)^(1/dim), dx): keeps J with the particles' spacing where "
     "the velocity ripples at the grid scale, as in hot gas at rest on the grid; only J, and so "
     "the density and pressure, reads it; see docs/gas.md)",
     0, NULL},
    {"fluid.pressure", MPM_KEY_ENUM, "auto", 0, 0, 0, 0, "auto|particle|grid|hybrid",
     "where the pressure's force is integrated: particle (each particle's V p at its point, "
     "the classic MPM quadrature), grid (the nodal pressure, a volume-weighted mean of the "
     "particles', integrated exactly over the grid's cells, with each particle's volume "
     "following its nodes' volume rate: gas at rest and uniform streams stay exact across "
     "refined regions, and beside a solid its region is taken out by the solid's quadrature; "
     "ERK pairs, usl or musl, quadratic shape; beside a solid coupling.time monolithic or "
     "multirate with the held exchange, any coupling.scheme), hybrid (the particles' pressure "
     "with the grid's as a defect correction: the particles integrate p - p_h, the grid p_h "
     "exactly, so a uniform pressure exerts no force whatever the particles' positions; the "
     "grid's scope without obstacles, beside a solid monolithic or multirate under an ERK "
     "pair (MRIStep), not contact, without refinement, its filled share (fluid.hybrid_fill) off on "
     "a hierarchy; docs/gas.md, "
     "docs/refinement.md) or auto (without a solid: grid with refine.levels > 1, where particle is "
     "refused, else hybrid where its scope holds (and no fluid.regularise_every; under usl "
     "and musl no farfield or subsonic_inflow face) and particle outside it, silently; beside "
     "a solid under usl and musl particle, whose PIC share keeps the gas stable there "
     "(fluid.pic_fraction), under the ERK pairs, which take no PIC share, hybrid where its "
     "scope holds and particle outside it; the log says which); see docs/gas.md",
     0, NULL},
    {"fluid.hybrid_fill", MPM_KEY_REAL, "0.5", 0, 1, 0, 0, NULL,
     "the hybrid pressure without a solid: the share of a node's volume the particles must fill "
     "for its grid part to act whole; below it the grid part is weighted by the share, so the "
     "particles' own pressure takes over where the gas is torn or nearly empty (a near vacuum, "
     "gas leaving a wall), total energy exact at every weight (0: unweighted; see "
     "fluid/fluid_gridp.c)",
     0, NULL},
    {"fluid.pressure_relax", MPM_KEY_REAL, "4", 0, HUGE_VAL, 0, 0, NULL,
     "the grid pressure (fluid.pressure = grid, and auto on a hierarchy): relax each "
     "particle's pressure towards its nodes' over this many times the time a sound wave takes "
     "to cross a cell of its level, by volume exchanged between particles sharing nodes (the "
     "gas's volume, mass, momentum and total energy as exact as without it, entropy never "
     "falling); without it nothing pulls a particle's volume back to its neighbours' and over "
     "long runs their densities drift apart. It damps smooth waves at first order in dx, so the "
     "default 4 holds on a refinement hierarchy only (unset on a uniform grid: off); 0: off, "
     "else at least 1; not with the hybrid or the particles' pressure (see "
     "docs/refinement.md)",
     0, "-"},
    {"fluid.ppc", MPM_KEY_INT, "2", 1, 8, 0, 0, NULL,
     "gas particles per cell per direction at seeding", 0, "-"},
    {"fluid.regularise_every", MPM_KEY_INT, "0", 0, HUGE_VAL, 0, 0, NULL,
     "merge and split gas particles every N accepted steps, conserving mass, momentum and "
     "total energy (0: never; the seed paper uses 30)",
     0, "-"},
    {"fluid.refill", MPM_KEY_BOOL, "true", 0, 0, 0, 0, NULL,
     "with regularisation: give every empty cell next to the gas (and free of other "
     "material and obstacles) half of a neighbour's heaviest particle, conserving mass, "
     "momentum and energy, so that strong expansions and wakes keep no empty cell",
     0, NULL},
    {"fluid.refill_every", MPM_KEY_INT, "0", 0, HUGE_VAL, 0, 0, NULL,
     "refill every N accepted steps, apart from the merges and splits (0: with each "
     "regularisation, every fluid.regularise_every steps); a wake that expansion empties "
     "faster than regularise_every steps refill it keeps empty cells between refills",
     0, "-"},
    {"fluid.refill_holes", MPM_KEY_ENUM, "auto", 0, 0, 0, 0, "auto|true|false",
     "after every step with no other refill, refill the holes in the gas: empty cells next to "
     "gas with an empty neighbour along every axis and no obstacle within a cell (gaps two "
     "cells across, which near vacuum opens and an ordinary expansion does not), conserving "
     "mass, momentum and energy; auto: where the gas takes the hybrid pressure with its filled "
     "share (a gas alone), whose particles beside a wall the refills do not crush (beside "
     "solids and obstacles the particles' pressure, refilled, blew up on the forward step); "
     "false leaves a gas expanding into near vacuum to tear; fluid.refill = false turns it off "
     "too (see fluid/fluid_regularise.c)",
     0, NULL},
    {"fluid.merge_light", MPM_KEY_REAL, "0", 0, 0.5, 0, 0, NULL,
     "with regularisation or refill: at each of them, a gas particle lighter than this "
     "fraction of the heaviest particle in its cell merges with it and the two split into "
     "equal halves, conserving mass, momentum, total energy and volume (0: off); unset, it is "
     "off there, and after a refill of holes (fluid.refill_holes) that made children it is "
     "0.125, which keeps the halved children of a near vacuum from setting the step; see "
     "fluid/fluid_regularise.c",
     0, "-"},
    {"fluid.shift", MPM_KEY_REAL, "0", 0, 0.5, 0, 0, NULL,
     "particle shifting coefficient kappa: each gas particle moves down the gradient of the "
     "gas's nodal volume fraction phi at the rate kappa dx (c + |v|), so that particles that "
     "cluster under strong expansion spread out again (0: off; 0.375 in the cases that use it, "
     "at most 0.5: 0.5 was already erratic on the double rarefaction; "
     "only positions change, so mass, momentum and energy are kept exactly; see "
     "fluid/fluid_shift.c)",
     0, "-"},
    {"fluid.shift_expansion", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "with fluid.shift: only particles whose volume has grown by at least this factor since "
     "seeding (J >= this) move (0: every particle). 1.2 keeps uniform flow free of the noise "
     "shifting adds there, but the thin plate of cases/plate_across.ini then blew up at "
     "dx = 0.005: shifting its compressed particles is what keeps it stable",
     0, "-"},
    {"fluid.shift_every", MPM_KEY_INT, "1", 1, HUGE_VAL, 0, 0, NULL,
     "shift the gas particles every N accepted steps (with fluid.shift > 0)", 0, "-"},
    {"fluid.empty_node_mass", MPM_KEY_REAL, "1e-14", 0, 1e-2, 0, 0, NULL,
     "a gas node holding less than this fraction of the largest gas nodal mass is empty: no "
     "velocity, no acceleration, and its force is dropped (1e-14: roundoff only). In a near "
     "vacuum the few light particles at such nodes take huge accelerations and heat; 1e-4 "
     "keeps them at the gas's own speeds, at the price of the momentum those nodes carry",
     0, "-"},
    {"fluid.light_node_mass", MPM_KEY_REAL, "0", 0, 0.5, 0, 0, NULL,
     "a gas node holding less than this fraction of the mean gas nodal mass (over the nodes "
     "holding gas) is empty too, as for empty_node_mass (0: off). Relative to the mean, so a "
     "spuriously compressed node elsewhere does not empty ordinary ones; on a refinement "
     "hierarchy each level's nodes against the mean at that level's spacing",
     0, "-"},
    {"fluid.regularise_min", MPM_KEY_INT, NULL, 1, HUGE_VAL, 0, 0, NULL,
     "split particles in a non-empty cell holding fewer than this (default ceil(ppc^dim / 2): "
     "refill where the gas has expanded to twice its seeding volume; 1 never splits)",
     1, "-"},
    {"fluid.stable_step", MPM_KEY_ENUM, "particle", 0, 0, 0, 0, "particle|neighbourhood",
     "how the gas's stable step is estimated: particle (the fastest single particle) or "
     "neighbourhood (mass-weighted over the 3^dim cells around each cell, so that light "
     "refill particles in a wake do not set the step; see fluid/fluid_stable.c; the main job "
     "uses it)",
     0, NULL},
    {"fluid.viscous_step", MPM_KEY_ENUM, "additive", 0, 0, 0, 0, "additive|damped",
     "how the viscous terms (artificial and physical) limit the gas's stable step: additive "
     "(dx / (c + |v| + 2 nu / dx), the acoustic and diffusion limits added) or damped (the "
     "damped critical step of the explicit update, dx / (|v| + nu / dx + sqrt(c^2 + (nu / "
     "dx)^2)), never smaller; with vnr's linear term 1.62 c where additive has 2 c; see "
     "docs/time.md)",
     0, NULL},
    {"fluid.regularise_max", MPM_KEY_INT, NULL, 2, HUGE_VAL, 0, 0, NULL,
     "merge particles in a cell holding more than this (default 4 ppc^dim: only where the "
     "gas is compressed fourfold, beyond the 2-3x of the usual shocks); > regularise_min",
     1, "-"},
    {"gas.*.geometry", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "name of the [geometry.NAME] region the gas fills (where regions overlap, the first "
     "[gas] section in the file wins)",
     0, NULL},
    {"gas.*.density", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "initial density, kg/m^3 (or density_field)", 1, "kg/m^3"},
    {"gas.*.pressure", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "initial pressure, Pa (or pressure_field)", 1, "Pa"},
    {"gas.*.velocity", MPM_KEY_REALS, "0 0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "initial velocity, m/s (dim values; extra values are ignored)", 0, "m/s"},
    {"gas.*.density_field", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "initial density as an expression in x, y, z (e.g. 1 + 0.1*exp(-x^2/0.01)), instead of "
     "density",
     1, "kg/m^3"},
    {"gas.*.pressure_field", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "initial pressure as an expression in x, y, z, instead of pressure", 1, "Pa"},
    {"gas.*.velocity_field", MPM_KEY_STRING, NULL, 0, 0, 0, 0, NULL,
     "initial velocity as expressions in x, y, z, one per component separated by ';', "
     "instead of velocity",
     1, "m/s"},
};

int fluid_add_schema(mpm_config *cfg) {
  MPM_CALL(mpm_config_add_schema(cfg, fluid_boundary_keys, fluid_boundary_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, fluid_obstacle_keys, fluid_obstacle_nkeys));
  MPM_CALL(mpm_config_add_schema(cfg, fluid_wall_keys, fluid_wall_nkeys));
  return mpm_config_add_schema(cfg, fluid_keys, (int)(sizeof fluid_keys / sizeof fluid_keys[0]));
}

/* ---- helpers ----------------------------------------------------------------------------- */

static const double *state(const mpm_particles *p, const double *y, int f) {
  return y + (size_t)p->offset[f] * p->n;
}

/* Field f from the state y if it is a state field, else from the particle data. */
static double *field(const mpm_particles *p, const double *y, int f) {
  return (f < p->nstate_fields ? (double *)y : p->data) + (size_t)p->offset[f] * p->n;
}

/* Grow the particle scratch arrays to the current count. tscratch holds the classic
 * transfer's a_p (dim), three interpolated scalars, and with APIC C(a) (dim^2) and two
 * discarded G2P outputs (2 dim). */
static int ensure_scratch(mpm_module *m) {
  fluid_content *fc = m->content;
  const mpm_lidx n = m->particles->n;
  const int dim = m->grid->dim;
  if (n <= fc->cap && fc->vsig && (!fc->refined || fc->av_l)) return 0;
  free(fc->vsig), free(fc->scratch), free(fc->vnew), free(fc->Cnew), free(fc->power);
  free(fc->tscratch), free(fc->sub), free(fc->work), free(fc->av_l), free(fc->lev);
  free(fc->sub_lev);
  fc->vnew = fc->Cnew = fc->tscratch = fc->sub = fc->work = fc->av_l = NULL;
  fc->lev = fc->sub_lev = NULL;
  fc->cap = n + n / 4 + 16;
  MPM_ALLOC(fc->vsig, (size_t)dim * dim * fc->cap);
  MPM_ALLOC(fc->scratch, (size_t)(2 * dim + dim * dim) * fc->cap);
  if (fc->mol_damping > 0) MPM_ALLOC(fc->work, (size_t)4 * dim * fc->cap);
  MPM_ALLOC(fc->power, fc->cap);
  if (fc->refined) MPM_ALLOC(fc->av_l, fc->cap);
  if (fc->refined) MPM_ALLOC(fc->lev, fc->cap);
  if (fc->tr.classic)
    MPM_ALLOC(fc->tscratch, (size_t)(dim + 3 + (fc->tr.apic ? dim * dim + 2 * dim : 0)) * fc->cap);
  if (fc->tr.musl) MPM_ALLOC(fc->vnew, (size_t)dim * fc->cap);
  if (fc->tr.musl && fc->tr.apic) MPM_ALLOC(fc->Cnew, (size_t)dim * dim * fc->cap);
  return 0;
}

/* ---- the RHS phases ------------------------------------------------------------------------ */

/* Deposit the particles (and the open faces' and virtual particles) into the phase: m, m v and,
 * with vsig, the forces; with b, the obstacles' ghost fields too. */
static int deposit(mpm_module *m, const double *y, const double *vsig, const fluid_batch *b) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  mpm_p2g_args a = {.n = n,
                    .m = mpm_particles_comp(p, fc->lay.f_m, 0),
                    .vsig = vsig,
                    .C = fc->tr.apic ? state(p, y, fc->lay.f_C) : NULL,
                    .lp = fc->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = state(p, y, FLUID_X) + (size_t)d * n;
    a.v[d] = state(p, y, FLUID_V) + (size_t)d * n;
    a.gravity[d] = vsig ? fc->gravity[d] : 0.0;
  }
  int rc = 0;
  fluid_p2g_any(m, m->phase, &a, &rc);
  MPM_CALL(rc);
  if (fc->filter_phase >= 0 && !m->hier) { /* the particles' own m and m v, for mol_damping */
    const mpm_grid_phase *ph = &m->grid->phase[m->phase];
    mpm_grid_phase *fp = &m->grid->phase[fc->filter_phase];
    const size_t bytes = sizeof(double) * (size_t)m->grid->nnodes;
    memcpy(fp->m_i, ph->m_i, bytes);
    for (int d = 0; d < dim; ++d) memcpy(fp->mv_i[d], ph->mv_i[d], bytes);
  }
  fluid_virtual_clear(&fc->virt);
  MPM_CALL(fluid_open_p2g(fc->open, m, y, &fc->virt));
  MPM_CALL(fluid_virtual_deposit(&fc->virt, m->grid, fc->lp));
  if (b)
    fluid_obstacles_deposit(&fc->obs, m->grid, n, a.x, b->m, b->V0, b->J, vsig, b->e,
                            fc->gas.gamma);
  return 0;
}

/* fluid.strain_rate = current (the method of lines): the strain rate of the state y itself, for
 * the artificial and physical viscosity, so that the RHS is a function of y alone, as an ERK
 * pair's order and error estimate assume. The lagged rate (the previous step's) holds every
 * ERK pair to first order in time wherever the artificial viscosity acts.
 *
 * The particles deposit m, m v and the pressure's force (p2g). The coupler then previews the
 * solve (mpm_module.h, p2g_rate): from copies of the deposits, summed over the ranks, with the
 * walls, open faces and obstacles, the coupling scheme and the other modules' constraints
 * acting as in the solve, it leaves in the phase's v the nodal velocity m v / m that the RHS's
 * own G2P will read. Its gradient L, interpolated back, is this RHS's rate: tr L and sym L
 * (p2g_rate). Only the particles with a viscous stress (in compression, or all with viscosity)
 * then deposit it, as massless particles. The rate is thus the one the energy equation's work
 * (V sigma : L) / m reads, so the artificial viscosity only ever heats. (A preview of the gas
 * alone, before the coupling, put compression where the shared velocity of the `velocity`
 * scheme expands the gas behind the main job's bar: there the artificial pressure did negative
 * work, up to -1.3e10 J/kg/s, and emptied particles of their internal energy under bs32.) The
 * phase's v and a are scratch until the solve. Cost: about 1.6x the lagged RHS's gas work
 * (test_gas_time_order), and the coupler's preview pass. */

/* tr L into divv and sym L into D (dim*dim, may be L itself; NULL: not wanted). */
static void rate_parts(int dim, mpm_lidx n, const double *L, double *divv, double *D) {
  for (mpm_lidx i = 0; i < n; ++i) divv[i] = L[i];
  for (int d = 1; d < dim; ++d)
    for (mpm_lidx i = 0; i < n; ++i) divv[i] += L[(size_t)(d * dim + d) * n + i];
  for (int r = 0; D && r < dim; ++r)
    for (int c = r; c < dim; ++c)
      for (mpm_lidx i = 0; i < n; ++i) {
        const double s =
            0.5 * (L[(size_t)(r * dim + c) * n + i] + L[(size_t)(c * dim + r) * n + i]);
        D[(size_t)(r * dim + c) * n + i] = D[(size_t)(c * dim + r) * n + i] = s;
      }
}

/* Deposit the viscous part of V sigma (fluid_stress_viscous) of the particles that have one, as
 * massless particles (forces only), and add it to b->vsig, which held the pressure's part. On a
 * hierarchy they deposit on the levels of this RHS (fc->lev, fluid_av_lengths), handed to it
 * for their positions and then again for the whole set's. */
static int deposit_viscous(mpm_module *m, const double *y, const fluid_batch *b) {
  fluid_content *fc = m->content;
  const int dim = b->dim, nk = dim * dim;
  const mpm_lidx n = b->n;
  const size_t cap = (size_t)fc->cap;
  if (!fc->sub) MPM_ALLOC(fc->sub, (size_t)(dim + nk) * cap);
  const int leveled = m->hier && fc->refined; /* fc->lev holds this RHS's levels */
  if (leveled && !fc->sub_lev) MPM_ALLOC(fc->sub_lev, cap);
  double *xs = fc->sub, *sig = xs + (size_t)dim * cap;
  const double *x = state(m->particles, y, FLUID_X);
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; ++i) k += fluid_stress_viscous(&fc->gas, b, i, NULL);
  if (k == 0) { /* a share of zero: the next restriction still sums the ranks (mpm_hier.h) */
    if (m->hier) mpm_hier_own_share(m->hier, m->phase);
    return 0;
  }
  double one[MPM_MAX_DIM * MPM_MAX_DIM];
  mpm_lidx j = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    if (!fluid_stress_viscous(&fc->gas, b, i, one)) continue;
    for (int d = 0; d < dim; ++d) xs[(size_t)d * cap + j] = x[(size_t)d * n + i];
    if (leveled) fc->sub_lev[j] = fc->lev[i];
    for (int q = 0; q < nk; ++q) {
      sig[(size_t)q * k + j] = one[q]; /* stride k: the kernel's n */
      b->vsig[(size_t)q * n + i] += one[q];
    }
    ++j;
  }
  mpm_p2g_args a = {.n = k, .vsig = sig, .lp = fc->lp}; /* the lean deposit (v NULL) */
  for (int d = 0; d < dim; ++d) a.x[d] = xs + (size_t)d * cap;
  int rc = 0;
  if (leveled) mpm_hier_levels_known(m->hier, xs, k, fc->sub_lev);
  fluid_p2g_any(m, m->phase, &a, &rc);
  if (leveled) mpm_hier_levels_known(m->hier, x, n, fc->lev);
  return rc;
}

/* Add the viscous part of V sigma (fluid_stress_viscous) of the lagged rate to b->vsig, which
 * holds the pressure's part: the classic update's whole stress, for one deposit. */
static void add_viscous(const fluid_content *fc, fluid_batch *b) {
  const int nk = b->dim * b->dim;
  double one[MPM_MAX_DIM * MPM_MAX_DIM];
  for (mpm_lidx i = 0; i < b->n; ++i)
    if (fluid_stress_viscous(&fc->gas, b, i, one))
      for (int q = 0; q < nk; ++q) b->vsig[(size_t)q * b->n + i] += one[q];
}

/* The stress batch of the state y: its fields and the lagged rate (divv, D). */
static fluid_batch batch_of(const mpm_module *m, const double *y) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  return (fluid_batch){.dim = p->dim,
                       .n = p->n,
                       .m = mpm_particles_comp(p, fc->lay.f_m, 0),
                       .V0 = mpm_particles_comp(p, fc->lay.f_V0, 0),
                       .J = state(p, y, FLUID_J),
                       .e = state(p, y, FLUID_E),
                       .divv = field(p, y, fc->lay.f_divv),
                       .D = fc->lay.f_D >= 0 ? field(p, y, fc->lay.f_D) : NULL,
                       .psi = fc->lay.f_psi >= 0 ? field(p, y, fc->lay.f_psi) : NULL,
                       .l = fc->refined ? fc->av_l : NULL,
                       .vsig = fc->vsig};
}

static int fluid_p2g(mpm_module *m, double t, const double *y) {
  (void)t;
  fluid_content *fc = m->content;
  MPM_CALL(ensure_scratch(m));
  fluid_av_lengths(m, y);
  fluid_batch b = batch_of(m, y);
  if (!fc->current_rate && !fc->gridp) {
    mpm_timer_start(MPM_T_STRESS);
    fluid_stress(&fc->gas, &b);
    mpm_timer_stop(MPM_T_STRESS);
    mpm_timer_start(MPM_T_P2G);
    MPM_CALL(deposit(m, y, fc->vsig, &b));
    mpm_timer_stop(MPM_T_P2G);
    return 0;
  }
  /* The current rate (above): the pressure's deposit; p2g_rate adds the viscous one. The grid
   * pressure (fluid_gridp.c) in the classic update: its deposit reads the particles' pressure
   * (and, but for the hybrid, takes it out of vsig), then the viscous stress of the lagged rate
   * joins vsig for one deposit. */
  mpm_timer_start(MPM_T_STRESS);
  fluid_stress_pressure(&fc->gas, &b);
  mpm_timer_stop(MPM_T_STRESS);
  mpm_timer_start(MPM_T_P2G);
  if (fc->gridp) MPM_CALL(fluid_gridp_deposit(m, y, &b));
  if (!fc->current_rate) add_viscous(fc, &b);
  MPM_CALL(deposit(m, y, fluid_gridp_stress(m, fc->vsig), NULL));
  mpm_timer_stop(MPM_T_P2G);
  return 0;
}

/* The pending copy of the lagged field f (divv, D or psi): the copies precede those fields in
 * the same order (fluid_particles_new). */
static double *pending_of(const fluid_content *fc, const mpm_particles *p, int f) {
  return mpm_particles_comp(p, fc->lay.f_pending + (f - fc->lay.f_divv), 0);
}

/* The current rate from the previewed nodal velocity (above), and the viscous deposit. */
static int fluid_p2g_rate(mpm_module *m, double t, const double *y) {
  (void)t;
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  fluid_batch b = batch_of(m, y); /* its divv and D are replaced below */
  mpm_timer_start(MPM_T_G2P);
  double *vout[MPM_MAX_DIM], *aout[MPM_MAX_DIM], *L = fc->scratch + (size_t)2 * dim * n;
  for (int d = 0; d < dim; ++d)
    vout[d] = fc->scratch + (size_t)d * n, aout[d] = fc->scratch + (size_t)(dim + d) * n;
  const int rc = fluid_g2p_phase(m, y, vout, aout, L, NULL, NULL, 0);
  mpm_timer_stop(MPM_T_G2P);
  MPM_CALL(rc);
  if (fc->lay.f_psi >= 0) { /* this RHS's limiter, into pending (g2p keeps it) */
    const double *v_i[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) v_i[d] = m->grid->phase[m->phase].v_i[d];
    double *psi = pending_of(fc, p, fc->lay.f_psi);
    MPM_CALL(fluid_limiter(m, y, v_i, L, psi));
    b.psi = psi;
  }
  double *D = b.D ? L : NULL; /* sym L in place */
  rate_parts(dim, n, L, fc->power, D);
  b.divv = fc->power, b.D = D;
  mpm_timer_start(MPM_T_P2G);
  MPM_CALL(deposit_viscous(m, y, &b)); /* vsig is now the whole stress (energy rate, obstacles) */
  const double *x[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) x[d] = state(p, y, FLUID_X) + (size_t)d * n;
  fluid_obstacles_deposit(&fc->obs, m->grid, n, x, b.m, b.V0, b.J, fc->vsig, b.e, fc->gas.gamma);
  mpm_timer_stop(MPM_T_P2G);
  return 0;
}

/* Before the nodal solve: the ghost pressure of the obstacles and the virtual particles' forces
 * (first pass only: in MUSL's remap no force acts, and only the first pass's obstacle force is
 * recorded), the mirrored pad nodes folded into the walls (on every level of a hierarchy), and
 * the open faces' forces. */
static int fluid_forces(mpm_module *m, double t, double h, mpm_pass pass) {
  fluid_content *fc = m->content;
  const int first = pass == MPM_PASS_FIRST;
  if (first) MPM_CALL(fluid_obstacles_begin(&fc->obs, m->grid, m->phase, t, h, 1));
  if (first && fc->gridp) MPM_CALL(fluid_gridp_forces(m)); /* after begin: the span ghost */
  if (first) {
    MPM_CALL(fluid_virtual_forces(&fc->virt, m->grid, m->phase, NULL, 0));
    MPM_CALL(fluid_open_gauge_forces(fc->open, m));
  }
  mpm_constraints_fold(&fc->cons, m->grid, m->phase);
  if (m->hier) mpm_hier_walls_fold(m->hier, m->phase);
  if (first) MPM_CALL(fluid_open_forces(fc->open, m, t));
  return 0;
}

/* After the nodal solve: walls and open faces, then obstacles (their force excludes what a wall
 * holds), then the walls again, so that mirrored pad nodes copy the obstacle-constrained nodes. */
static int fluid_constrain(mpm_module *m, double t, double h, mpm_pass pass) {
  (void)t;
  fluid_content *fc = m->content;
  const int first = pass == MPM_PASS_FIRST;
  mpm_constraints_apply(&fc->cons, m->grid, m->phase);
  if (m->hier) mpm_hier_walls_apply(m->hier, m->phase);
  fluid_open_hold(fc->open, m);
  if (fc->obs.count) {
    MPM_CALL(fluid_obstacles_apply(&fc->obs, m->grid, m->phase, first ? h : 0.0, first));
    mpm_constraints_apply(&fc->cons, m->grid, m->phase);
    if (m->hier) mpm_hier_walls_apply(m->hier, m->phase);
    if (first) MPM_CALL(fluid_obstacles_work(&fc->obs, m->grid, m->phase, h));
  }
  return 0;
}

/* de/dt = (V sigma : L) / m + heat / h: the work of the stress on the grid per unit mass, and
 * in the classic step the particle's share of the transfer's energy defect (fluid_transfer.c).
 * vsig holds the forces' stress, the gauge taken out (fluid_gauge.c): its work -p_g V tr L is
 * put back, so that e takes the whole pressure's. */
static void energy_rate(mpm_module *m, const double *y, const double *L, const double *heat,
                        double h) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const int dim = p->dim, nk = dim * dim;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0), *J = state(p, y, FLUID_J);
  const double pg = fc->gas.gauge;
  double *pw = fc->power; /* heat may be this array: read each entry before writing it */
  for (mpm_lidx i = 0; i < n; ++i) {
    double work = 0.0;
    for (int k = 0; k < nk; ++k) work += fc->vsig[(size_t)k * n + i] * L[(size_t)k * n + i];
    if (pg != 0.0) {
      double trL = 0.0;
      for (int d = 0; d < dim; ++d) trL += L[(size_t)(d * dim + d) * n + i];
      work -= pg * V0[i] * J[i] * trL;
    }
    pw[i] = work / mass[i] + (heat ? heat[i] / h : 0.0);
  }
}

/* The classic step's transfer into the arrays o points to, and the energy rate. */
static int classic_transfer(mpm_module *m, const double *y, double h, fluid_step_out *o) {
  fluid_content *fc = m->content;
  o->L = fc->scratch + (size_t)2 * m->grid->dim * m->particles->n;
  o->heat = fc->power;
  MPM_CALL(fluid_classic_transfer(m, y, h, o));
  energy_rate(m, y, o->L, o->heat, h);
  if (fc->gridp) fluid_gridp_work(m, y, o->L, fc->power); /* the pressure's work, at vbar */
  return 0;
}

/* MUSL's second transfer (Sulsky, Zhou and Schreyer 1995): the particles take their new
 * velocities (and APIC affine velocities) from the first grid update and deposit mass and
 * momentum again; positions and J then move with the nodal velocities of that deposit. The
 * energy rate is set here, from the first pass, whose nodal velocities the deposit replaces. */
static int fluid_remap(mpm_module *m, double t, const double *y, double h) {
  (void)t;
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  fluid_step_out o = {.C = fc->Cnew};
  for (int d = 0; d < dim; ++d)
    o.vhat[d] = fc->scratch + (size_t)d * n, o.vnew[d] = fc->vnew + (size_t)d * n;
  MPM_CALL(classic_transfer(m, y, h, &o));
  if (m->hier)
    mpm_hier_phase_zero(m->hier, m->phase);
  else
    mpm_grid_phase_zero(m->grid, m->phase);
  mpm_p2g_args a = {
      .n = n, .m = mpm_particles_comp(p, fc->lay.f_m, 0), .C = fc->Cnew, .lp = fc->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = state(p, y, FLUID_X) + (size_t)d * n;
    a.v[d] = o.vnew[d];
  }
  int rc = 0;
  fluid_p2g_any(m, m->phase, &a, &rc); /* the coupler restricts it on a hierarchy */
  return rc;
}

/* A replaced state field as a rate over the step: out = (out - y) / h, or (src - y) / h. */
static void as_rate(double *out, const double *src, const double *y, size_t count, double h) {
  for (size_t k = 0; k < count; ++k) out[k] = ((src ? src[k] : out[k]) - y[k]) / h;
}

/* dJ/dt = J tr L. The strain rate is kept for the next stress evaluation and stable step:
 * in the classic update as the state's rate (new - old) / h; in the method-of-lines RHS in the
 * fields pending_divv, pending_D, pending_psi, which fluid_post_step commits after an accepted step
 * (the RHS must not change what it reads: ARKODE also probes it at trial states). */
static int volume_rate(mpm_module *m, const double *y, double *ydot, const double *L,
                       const double *const *v_i, double h) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const int in_state = fc->lay.f_pending < 0;
  const double *J = state(p, y, FLUID_J);
  double *Jdot = ydot + (size_t)p->offset[FLUID_J] * n;
  double *tr = in_state ? fc->scratch : pending_of(fc, p, fc->lay.f_divv);
  double *D = fc->lay.f_D < 0 ? NULL
              : in_state      ? ydot + (size_t)p->offset[fc->lay.f_D] * n
                              : pending_of(fc, p, fc->lay.f_D);
  rate_parts(dim, n, L, tr, D);
  const double *Jrate = tr; /* fluid.volume_rate: point, or over the particle's domain */
  if (fc->volume_domain) MPM_CALL(fluid_volume_rate(m, y, v_i, L, &Jrate));
  if (fc->gridp) Jrate = fluid_gridp_rate_out(fc, NULL)[0]; /* fluid_gridp_work: dJ/dt / J */
  for (mpm_lidx i = 0; i < n; ++i) Jdot[i] = J[i] * Jrate[i];
  /* The limiter (riemann viscosity): with the current rate p2g_rate has set this RHS's. */
  double *psi = fc->lay.f_psi < 0 ? NULL
                : in_state        ? fc->scratch + n
                                  : pending_of(fc, p, fc->lay.f_psi);
  if (psi && !fc->current_rate) MPM_CALL(fluid_limiter(m, y, v_i, L, psi));
  if (!in_state) return 0;
  as_rate(ydot + (size_t)p->offset[fc->lay.f_divv] * n, tr, field(p, y, fc->lay.f_divv), n, h);
  if (D) as_rate(D, NULL, field(p, y, fc->lay.f_D), (size_t)dim * dim * n, h);
  if (psi)
    as_rate(ydot + (size_t)p->offset[fc->lay.f_psi] * n, psi, field(p, y, fc->lay.f_psi), n, h);
  return 0;
}

/* Three forms of G2P: the method-of-lines RHS (h = 0): dx/dt = sum S v_i, dv/dt = sum S a_i;
 * the classic USL step: the transfer of fluid_transfer.c as rates over h; MUSL after its
 * second deposit: positions and J move with the new nodal velocities, v, C and e take what
 * fluid_remap computed. */
/* The rates of the RHS (fluid_g2p, its last phase). */
static int g2p_rates(mpm_module *m, const double *y, double *ydot, double h) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  double *L = fc->scratch + (size_t)2 * dim * n;
  double *xdot[MPM_MAX_DIM] = {NULL}, *vdot[MPM_MAX_DIM] = {NULL}, *a_p[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d) {
    xdot[d] = ydot + (size_t)(p->offset[FLUID_X] + d) * n;
    vdot[d] = ydot + (size_t)(p->offset[FLUID_V] + d) * n;
    a_p[d] = fc->scratch + (size_t)(dim + d) * n;
  }
  const size_t nv = (size_t)dim * n, nC = (size_t)dim * dim * n;
  double *Cdot = fc->tr.apic ? ydot + (size_t)p->offset[fc->lay.f_C] * n : NULL;
  const double *v = state(p, y, FLUID_V), *C = fc->tr.apic ? state(p, y, fc->lay.f_C) : NULL;
  if (!(h > 0)) {
    mpm_hier_scalars rate;
    double *const *rate_out = NULL;
    int nrate = 0;
    if (fc->gridp) {
      MPM_CALL(fluid_gridp_nodal_rate(m, NULL, &rate));
      rate_out = fluid_gridp_rate_out(fc, &nrate);
    }
    MPM_CALL(fluid_g2p_phase(m, y, xdot, vdot, L, &rate, rate_out, nrate));
    energy_rate(m, y, L, NULL, h);
    if (fc->gridp) fluid_gridp_work(m, y, L, fc->power);
    if (!fc->tr.apic) fluid_wall_rate_mol(m, y, vdot, fc->power);
    MPM_CALL(fluid_mol_damping(m, y, vdot, fc->power, fc->work));
  } else if (!fc->tr.musl) {
    fluid_step_out o = {.C = Cdot};
    for (int d = 0; d < dim; ++d) o.vhat[d] = xdot[d], o.vnew[d] = vdot[d];
    MPM_CALL(classic_transfer(m, y, h, &o));
    as_rate(vdot[0], NULL, v, nv, h);
    if (Cdot) as_rate(Cdot, NULL, C, nC, h);
  } else {
    MPM_CALL(fluid_g2p_phase(m, y, xdot, a_p, L, NULL, NULL, 0)); /* the remapped velocities */
    as_rate(vdot[0], fc->vnew, v, nv, h);
    if (Cdot) as_rate(Cdot, fc->Cnew, C, nC, h);
  }
  /* The nodal velocity L is the gradient of: usl's time-centred one (fluid_transfer.c). */
  const double *v_i[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d)
    v_i[d] = h > 0 && !fc->tr.musl ? fc->node + (size_t)d * m->grid->nnodes
                                   : m->grid->phase[m->phase].v_i[d];
  MPM_CALL(volume_rate(m, y, ydot, L, v_i, h));
  const double *pos[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < dim; ++d) pos[d] = state(p, y, FLUID_X) + (size_t)d * n;
  fluid_obstacles_heat(&fc->obs, m->grid, n, pos, state(p, y, FLUID_E), h, fc->power);
  memcpy(ydot + (size_t)p->offset[FLUID_E] * n, fc->power, sizeof(double) * (size_t)n);
  if (h > 0) MPM_CALL(fluid_wall_ls_apply(m, y, ydot, h));
  fluid_open_sponge(fc->open, m, y, ydot);
  fluid_obstacles_list_done(&fc->obs);
  return 0;
}

static int fluid_g2p(mpm_module *m, double t, const double *y, double *ydot, double h) {
  (void)t;
  const int rc = g2p_rates(m, y, ydot, h);
  if (m->hier) mpm_hier_levels_known(m->hier, NULL, 0, NULL); /* the RHS's levels end here */
  return rc;
}

/* After an accepted step: commit the ERK pairs' pending strain rate, then shift and
 * regularise. */
static int fluid_post_step(mpm_module *m, double t, double h, int *changed) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  if (fc->lay.f_pending >= 0) { /* divv, D, psi follow their pending copies in the data */
    const size_t count =
        (size_t)p->n * (size_t)(p->offset[fc->lay.f_divv] - p->offset[fc->lay.f_pending]);
    memcpy(mpm_particles_comp(p, fc->lay.f_divv, 0), mpm_particles_comp(p, fc->lay.f_pending, 0),
           sizeof(double) * count);
  }
  MPM_CALL(fluid_obstacles_report(&fc->obs, m->grid, t, h));
  fc->s_local = -1.0; /* a new step begins: its first stable-step estimate recomputes it */
  /* Shift first, then refill from the counts after the shift: a refill child keeps its cell,
   * and no shift empties a cell the refill just filled. */
  int shifted = 0;
  MPM_CALL(fluid_shift(m, m->step, h, &shifted));
  if (shifted && fluid_refill_due(fc, m->step))
    MPM_CALL(mpm_cells_count(m->grid, m->phase, m->particles));
  *changed |= shifted;
  MPM_CALL(fluid_relevel(m, 0, changed));
  return fluid_regularise(m, m->step, changed);
}

static int fluid_boundary(mpm_module *m, double t, double h, int *changed) {
  fluid_content *fc = m->content;
  fluid_walls_return(m);
  /* A returned particle moved after the step's last RHS: the integrator restarts its first
   * stage (a reused one would be stale where the set did not also migrate: 2 ranks would
   * differ from 1). */
  if (fluid_obstacles_return(&fc->obs, m->grid, m->particles, FLUID_X) > 0) *changed = 1;
  return fluid_open_exchange(fc->open, m, t, h, changed);
}

static const char *fluid_reserved(const mpm_module *m, const double *x) {
  const fluid_content *fc = m->content;
  const int k = fluid_obstacles_which(&fc->obs, x);
  return k >= 0 ? fc->obs.ob[k].shape_key : NULL;
}

static int fluid_output(mpm_module *m) {
  MPM_CALL(fluid_output_fields(m));
  return 0;
}

/* |v|^2 of particle i at state y. */
static double speed_squared(const mpm_particles *p, const double *y, mpm_lidx i) {
  double v2 = 0.0;
  for (int d = 0; d < p->dim; ++d) {
    const double v = state(p, y, FLUID_V)[(size_t)d * p->n + i];
    v2 += v * v;
  }
  return v2;
}

/* The stable step of a refined gas: the smallest over the particles of their level's spacing h
 * (their position's level, fluid_position_level) over their signal speed, each computed as on a
 * uniform grid of spacing h (the artificial viscosity's length h too), returned as dx_finest /
 * smax. */
static double refined_stable_dt(const mpm_module *m, const double *y, double dx) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const double gamma = fc->gas.gamma;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const double *divv = field(p, y, fc->lay.f_divv);
  const double *psi = fc->lay.f_psi >= 0 ? field(p, y, fc->lay.f_psi) : NULL;
  const double *J = state(p, y, FLUID_J), *e = state(p, y, FLUID_E);
  const unsigned char *lev = fluid_position_levels(m, y);
  /* Per level: its spacing, the gas there and the ratio to the finest spacing. */
  const int nlev = m->hier ? m->hier->nlevels : 1;
  double hl[MPM_HIER_MAX_LEVELS], ratio[MPM_HIER_MAX_LEVELS];
  fluid_gas gl[MPM_HIER_MAX_LEVELS];
  for (int l = 0; l < nlev; ++l) {
    hl[l] = m->hier ? m->hier->level[l].grid->dx : m->grid->dx;
    gl[l] = fluid_gas_at(&fc->gas, &hl[l], 0), ratio[l] = dx / hl[l];
  }
  double smax = 0.0;
  for (mpm_lidx i = 0; i < n; ++i) {
    const double v2 = speed_squared(p, y, i);
    const int l = !m->hier ? 0 : lev ? lev[i] : fluid_position_level(m, NULL, y, i);
    const double h = hl[l];
    const fluid_gas *g = &gl[l];
    const double rho = mass[i] / (V0[i] * J[i]);
    const double c = sqrt(gamma * (gamma - 1.0) * fabs(e[i]));
    const double q = psi ? psi[i] : 0.0;
    const double s = g->damped_step ? sqrt(v2) + fluid_signal_speed(g, rho, c, divv[i], q, h)
                                    : c + sqrt(v2) + fluid_viscous_speed(g, rho, c, divv[i], q, h);
    const double sl = s * ratio[l];
    if (sl > smax) smax = sl; /* (fmax's answer, NaN passed over alike, without its call) */
  }
  return smax > 0.0 ? dx / smax : HUGE_VAL;
}

static double fluid_fastest_signal(const mpm_module *m, const double *y) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const double gamma = fc->gas.gamma, *e = state(p, y, FLUID_E);
  double smax = 0.0;
  for (mpm_lidx i = 0; i < n; ++i) {
    const double v2 = speed_squared(p, y, i);
    smax = fmax(smax, sqrt(gamma * (gamma - 1.0) * fabs(e[i])) + sqrt(v2));
  }
  return smax;
}

static double fluid_stable_dt(const mpm_module *m, const double *y) {
  fluid_content *fc = m->content;
  if (fc->stable_local && fc->s_local < 0.0 && fluid_neighbourhood_signal(m, &fc->s_local) != 0)
    fc->s_local = -1.0; /* an MPI failure: fall back on the particle estimate below */
  if (fc->stable_local && fc->s_local >= 0.0)
    return fc->s_local > 0.0 ? fluid_finest_dx(m) / fc->s_local : HUGE_VAL;
  const mpm_particles *p = m->particles;
  const mpm_lidx n = p->n;
  const double dx = fluid_finest_dx(m), gamma = fc->gas.gamma; /* one step for every level */
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const double *divv = field(p, y, fc->lay.f_divv);
  const double *psi = fc->lay.f_psi >= 0 ? field(p, y, fc->lay.f_psi) : NULL;
  const double *J = state(p, y, FLUID_J), *e = state(p, y, FLUID_E);
  const int viscous = fc->gas.mu > 0.0;
  if (fc->refined) return refined_stable_dt(m, y, dx);
  double smax = 0.0; /* the fastest signal: dt = dx / smax */
  for (mpm_lidx i = 0; i < n; ++i) {
    const double v2 = speed_squared(p, y, i);
    const double rho = viscous ? mass[i] / (V0[i] * J[i]) : 1.0; /* only viscosity needs it */
    const double c = sqrt(gamma * (gamma - 1.0) * fabs(e[i]));   /* sqrt(gamma p / rho) */
    const double s =
        fc->gas.damped_step
            ? sqrt(v2) + fluid_signal_speed(&fc->gas, rho, c, divv[i], psi ? psi[i] : 0.0, dx)
            : /* (additive: in its own order of operations, bit for bit) */
            c + sqrt(v2) + fluid_viscous_speed(&fc->gas, rho, c, divv[i], psi ? psi[i] : 0.0, dx);
    if (s > smax) smax = s; /* (fmax is a call: its NaN rules block inlining) */
  }
  return smax > 0.0 ? dx / smax : HUGE_VAL;
}

static int fluid_check(const mpm_module *m, const double *y, mpm_fault *fault) {
  if (mpm_module_check_positions(m, y, fault)) return 1;
  const mpm_particles *p = m->particles;
  const double *J = state(p, y, FLUID_J), *e = state(p, y, FLUID_E);
  int bad = 0; /* one pass without jumps first (the values are finite: checked above) */
  for (mpm_lidx i = 0; i < p->n; ++i) bad |= (J[i] <= 0.0) | (e[i] <= 0.0);
  for (mpm_lidx i = 0; bad && i < p->n; ++i) {
    if (J[i] <= 0.0)
      return mpm_fault_at(fault, p, y, i, "the gas volume collapsed (J = %.3g <= 0)", J[i]);
    if (e[i] <= 0.0)
      return mpm_fault_at(fault, p, y, i,
                          "the gas internal energy is not positive (e = %.3g J/kg, so p <= 0)",
                          e[i]);
  }
  return 0;
}

static void fluid_sums(const mpm_module *m, mpm_module_sums *s) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *e = mpm_particles_comp(p, FLUID_E, 0);
  memset(s, 0, sizeof *s);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    s->mass += mass[i];
    s->internal += mass[i] * e[i];
  }
  for (int d = 0; d < p->dim; ++d) {
    const double *v = mpm_particles_comp(p, FLUID_V, d);
    for (mpm_lidx i = 0; i < p->n; ++i) {
      s->momentum[d] += mass[i] * v[i];
      s->kinetic += 0.5 * mass[i] * v[i] * v[i];
    }
  }
}

static void fluid_destroy(mpm_module *m) {
  fluid_content *fc = m->content;
  if (fc) {
    mpm_constraints_free(&fc->cons);
    fluid_open_destroy(&fc->open);
    fluid_obstacles_free(&fc->obs);
    fluid_wall_ls_free(&fc->wall);
    fluid_gridp_destroy(fc);
    fluid_virtual_free(&fc->virt);
    free(fc->vsig), free(fc->scratch), free(fc->vnew), free(fc->Cnew), free(fc->power);
    free(fc->av_l), free(fc->lev);
    free(fc->sub), free(fc->work), free(fc->sub_lev);
    free(fc->tscratch), free(fc->node), free(fc->cellsum), free(fc->lim), free(fc->vol);
    fluid_lnode_free(fc);
    free(fc);
  }
  mpm_particles_destroy(&m->particles);
}

static const mpm_module_ops fluid_ops = {
    .p2g = fluid_p2g,
    .forces = fluid_forces,
    .constrain = fluid_constrain,
    .g2p = fluid_g2p,
    .stable_dt = fluid_stable_dt,
    .signal_speed = fluid_fastest_signal,
    .check = fluid_check,
    .sums = fluid_sums,
    .boundary = fluid_boundary,
    .post_step = fluid_post_step,
    .destroy = fluid_destroy,
    .remap = fluid_remap,
    .output = fluid_output,
    .reserved = fluid_reserved,
    .attach_wall = fluid_wall_ls_attach,
};

/* ---- construction -------------------------------------------------------------------------- */

/* The light merges' share after a refill of holes when fluid.merge_light is unset: the holes'
 * children are halves, and chains of them at a near vacuum's centre halve again and again; the
 * lightest then set the step (the double rarefaction at 800 cells: 2,224 steps without light
 * merges, 1,151 with 0.125, the same L1; fluid_regularise.c). */
#define FLUID_MERGE_LIGHT_HOLES 0.125

/* The regularisation thresholds; the defaults follow the seeding count ppc^dim. */
static int read_regularise(fluid_content *fc, const mpm_config *cfg, int dim) {
  const char *kmin = "fluid.regularise_min", *kmax = "fluid.regularise_max";
  int seeded = 1;
  for (int d = 0; d < dim; ++d) seeded *= fc->ppc;
  fc->reg_min = (seeded + 1) / 2, fc->reg_max = 4 * seeded;
  MPM_CALL(mpm_config_get_int(cfg, "fluid.regularise_every", &fc->reg_every));
  MPM_CALL(mpm_config_get_bool(cfg, "fluid.refill", &fc->refill));
  int every = 0;
  MPM_CALL(mpm_config_get_int(cfg, "fluid.refill_every", &every));
  if (every > 0 && !fc->refill)
    return mpm_config_fail(cfg, "fluid.refill_every",
                           "refill_every = %d asks for refills and fluid.refill = false turns "
                           "them off; remove one of the two keys",
                           every);
  fc->refill_every = fc->refill ? (every > 0 ? every : fc->reg_every) : 0;
  const char *holes;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.refill_holes", &holes));
  fc->refill_holes = !fc->refill ? 0 : strcmp(holes, "auto") == 0 ? -1 : strcmp(holes, "true") == 0;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.merge_light", &fc->merge_light));
  fc->merge_light_holes =
      mpm_config_has(cfg, "fluid.merge_light") ? fc->merge_light : FLUID_MERGE_LIGHT_HOLES;
  if (mpm_config_has(cfg, kmin)) MPM_CALL(mpm_config_get_int(cfg, kmin, &fc->reg_min));
  if (mpm_config_has(cfg, kmax)) MPM_CALL(mpm_config_get_int(cfg, kmax, &fc->reg_max));
  if (fc->reg_min < fc->reg_max) return 0;
  return mpm_config_fail(cfg, mpm_config_has(cfg, kmax) ? kmax : kmin,
                         "regularise_min = %d must be below regularise_max = %d (a cell would "
                         "be split and merged at once); lower regularise_min or raise "
                         "regularise_max",
                         fc->reg_min, fc->reg_max);
}

/* fluid.av_form and its coefficients, whose defaults depend on the form. */
static int read_av(fluid_gas *gas, const mpm_config *cfg) {
  const char *form;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.av_form", &form));
  gas->av_riemann = strcmp(form, "riemann") == 0;
  gas->av_lin = gas->av_riemann ? FLUID_RIEMANN_LIN : 0.5;
  gas->av_quad = gas->av_riemann ? FLUID_RIEMANN_QUAD : 2.0;
  if (mpm_config_has(cfg, "fluid.av_linear"))
    MPM_CALL(mpm_config_get_real(cfg, "fluid.av_linear", &gas->av_lin));
  if (mpm_config_has(cfg, "fluid.av_quadratic"))
    MPM_CALL(mpm_config_get_real(cfg, "fluid.av_quadratic", &gas->av_quad));
  return 0;
}

static int read_settings(fluid_content *fc, const mpm_config *cfg, const mpm_grid *g) {
  int nv;
  double grav[3] = {0, 0, 0};
  MPM_CALL(mpm_config_get_real(cfg, "fluid.gamma", &fc->gas.gamma));
  MPM_CALL(mpm_config_get_real(cfg, "physics.gauge_pressure", &fc->gas.gauge));
  MPM_CALL(mpm_config_get_real(cfg, "fluid.viscosity", &fc->gas.mu));
  MPM_CALL(read_av(&fc->gas, cfg));
  const char *vstep;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.viscous_step", &vstep));
  fc->gas.damped_step = strcmp(vstep, "damped") == 0;
  const char *stable;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.stable_step", &stable));
  fc->stable_local = strcmp(stable, "neighbourhood") == 0, fc->s_local = -1.0;
  if (fc->stable_local) MPM_ALLOC(fc->cellsum, 6 * (size_t)g->nnodes);
  MPM_CALL(mpm_config_get_real(cfg, "fluid.R", &fc->R));
  MPM_CALL(mpm_config_get_int(cfg, "fluid.ppc", &fc->ppc));
  MPM_CALL(read_regularise(fc, cfg, g->dim));
  MPM_CALL(mpm_config_get_real(cfg, "fluid.shift", &fc->shift));
  MPM_CALL(mpm_config_get_int(cfg, "fluid.shift_every", &fc->shift_every));
  MPM_CALL(mpm_config_get_real(cfg, "fluid.shift_expansion", &fc->shift_J));
  MPM_CALL(mpm_config_get_reals(cfg, "physics.gravity", grav, 3, &nv));
  memcpy(fc->gravity, grav, sizeof grav);
  MPM_CALL(mpm_transfer_from_config(&fc->tr, cfg, "fluid.pic_fraction"));
  const char *rate;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.strain_rate", &rate));
  if (fc->tr.classic && mpm_config_has(cfg, "fluid.strain_rate"))
    return mpm_config_fail(cfg, "fluid.strain_rate",
                           "is read with the ERK pairs only: the classic update (usl, musl) "
                           "updates the stress last, with the rate of the step before; remove "
                           "the key or choose time.method = bs32");
  fc->current_rate = !fc->tr.classic && strcmp(rate, "current") == 0;
  const char *vrate;
  MPM_CALL(mpm_config_get_string(cfg, "fluid.volume_rate", &vrate));
  fc->volume_domain = strcmp(vrate, "domain") == 0;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.mol_damping", &fc->mol_damping));
  if (fc->tr.classic && mpm_config_has(cfg, "fluid.mol_damping"))
    return mpm_config_fail(cfg, "fluid.mol_damping",
                           "is read with the ERK pairs only: the classic update (usl, musl) "
                           "damps through fluid.pic_fraction; remove the key");
  if (fc->tr.classic || fc->tr.apic) fc->mol_damping = 0.0;
  const char *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (!fc->current_rate && strcmp(method, "ssprk2") == 0)
    return mpm_config_fail(cfg, "fluid.strain_rate",
                           "lagged makes every stage of ssprk2 read the rate of the step before "
                           "(first order in time); remove the key, current is the default");
  fc->gas.l = g->dx;
  fc->lp = 0.5 / fc->ppc;
  return 0;
}

/* The lagged strain rate (divv, D) is part of the state in the classic update: the step's
 * rate is (new - old) / h, so the stress and the stable step of the next step read it from
 * y_{n+1}. The step size the driver sets and the one the RHS computed for the same state are
 * then the same, which the exact energy balance needs; a restart also gets it bit for bit. In
 * the method-of-lines RHS it is an ordinary field the RHS overwrites (the previous stage's).
 * Appends divv, [D], [psi] (pending: their pending_ copies) to f; returns the first's index. */
static int lag_fields(mpm_field_desc *f, int *nf, int dim, int viscous, int limiter, int pending) {
  static const char *const names[2][3] = {{"divv", "D", "psi"},
                                          {"pending_divv", "pending_D", "pending_psi"}};
  const int first = *nf;
  f[(*nf)++] = (mpm_field_desc){names[pending][0], 1};
  if (viscous) f[(*nf)++] = (mpm_field_desc){names[pending][1], dim * dim};
  if (limiter) f[(*nf)++] = (mpm_field_desc){names[pending][2], 1};
  return first;
}

/* The fields at most: x, v, J, e, C; m, V0; the six output fields; divv, D, psi and their
 * pending copies. */
enum { FLUID_MAX_FIELDS = 4 + 1 + 2 + 6 + 2 * 3 };
_Static_assert(FLUID_MAX_FIELDS <= MPM_PARTICLES_MAX_FIELDS, "the gas's fields fit a set");

int fluid_particles_new(mpm_particles **p, int dim, fluid_layout *lay, int apic, int viscous,
                        int limiter, int lag_in_state) {
  mpm_field_desc f[FLUID_MAX_FIELDS] = {{"x", dim}, {"v", dim}, {"J", 1}, {"e", 1}};
  int nf = 4;
  lay->f_C = apic ? nf : -1;
  if (apic) f[nf++] = (mpm_field_desc){"C", dim * dim};
  if (lag_in_state) lay->f_divv = lag_fields(f, &nf, dim, viscous, limiter, 0);
  const int nstate = nf;
  lay->f_m = nf, f[nf++] = (mpm_field_desc){"m", 1};
  lay->f_V0 = nf, f[nf++] = (mpm_field_desc){"V0", 1};
  lay->f_pending = -1;
  if (!lag_in_state) { /* the pending copies directly before divv, D, psi: one block to copy */
    lay->f_pending = lag_fields(f, &nf, dim, viscous, limiter, 1);
    lay->f_divv = lag_fields(f, &nf, dim, viscous, limiter, 0);
  }
  lay->f_D = viscous ? lay->f_divv + 1 : -1;
  lay->f_psi = limiter ? lay->f_divv + 1 + (viscous ? 1 : 0) : -1;
  lay->f_rho = nf, f[nf++] = (mpm_field_desc){"rho", 1};
  lay->f_p = nf, f[nf++] = (mpm_field_desc){"p", 1};
  lay->f_mach = nf, f[nf++] = (mpm_field_desc){"mach", 1};
  lay->f_T = nf, f[nf++] = (mpm_field_desc){"T", 1};
  lay->f_s = nf, f[nf++] = (mpm_field_desc){"s", 1};
  lay->f_rho_grid = nf, f[nf++] = (mpm_field_desc){"rho_grid", 1};
  MPM_CALL(mpm_particles_new(p, dim, f, nf, nstate));
  /* The output fields are filled just before a snapshot (fluid_output.c): edits, sorts and
   * migrations need not move them. */
  for (int k = lay->f_rho; k <= lay->f_rho_grid; ++k) mpm_particles_set_derived(*p, k);
  /* Every RHS writes the pending strain rate before the step commits it: a restart from a
   * checkpoint of usl or musl, which have none, needs none. */
  for (int k = lay->f_pending; k >= 0 && k < lay->f_divv; ++k) mpm_particles_set_scratch(*p, k);
  return 0;
}

/* The PIC share a gas beside a solid takes when no key names one (fluid.pic_fraction and
 * transfer.pic_fraction unset): under the classic update, with the particles' pressure (what
 * fluid.pressure = auto gives beside a solid), on a uniform grid. That gas grows a grid-scale
 * mode out of roundoff once its particles leave their seeding lattice (docs/gas.md, "Particle
 * noise"): on the gas-column/slab resonator (cases/fsi_resonator.ini, usl) the blow-up guard
 * stopped it at t = 1.86 at 800 cells per metre. With 0.02 (the main job's and RAE 2822's
 * share) it stays 1-D over 20 periods at 400 and 800 cells per metre, and its coupled
 * frequencies move by under 0.005 % of the exact ones; 0.005 let the mode grow (2.3e-7 c by
 * t = 3 at 800). The ERK pairs take no PIC share (mpm_transfer.c): there the cure is named
 * (fluid.pressure = hybrid). Beside coupling.scheme = sharp with the gauge (fluid_gauge.c) the
 * uniform part's quadrature is gone and so is the share: on the resonator at 50 to 400 cells per
 * metre f_1 converged at order 1.39 without it and at 1.07 with it; without it the gas stayed
 * 1-D to 2.5e-15 of c over 20 periods at 800 cells per metre. */
#define FLUID_PIC_BESIDE_SOLID 0.02

static int pic_auto(mpm_module *m, const mpm_config *cfg) {
  fluid_content *fc = m->content;
  if (!fc->tr.classic || fc->tr.apic || fc->gridp || mpm_config_has(cfg, "fluid.pic_fraction") ||
      mpm_config_has(cfg, "transfer.pic_fraction") || mpm_config_has(cfg, "refine.levels"))
    return 0;
  const char *const *names;
  int nsolid;
  MPM_CALL(mpm_config_instances(cfg, "solid", &names, &nsolid));
  if (nsolid == 0) return 0;
  const char *scheme;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.scheme", &scheme));
  if (fc->gas.gauge != 0.0 && strcmp(scheme, "sharp") == 0) {
    mpm_log(MPM_LOG_INFO, "pic_fraction: 0 (fluid.pic_fraction unset: beside sharp with the "
                          "gauge, physics.gauge_pressure)");
    return 0;
  }
  fc->tr.pic = FLUID_PIC_BESIDE_SOLID;
  mpm_log(MPM_LOG_INFO,
          "pic_fraction: %g (fluid.pic_fraction unset: a gas beside a solid under its particles' "
          "pressure and the classic update)",
          fc->tr.pic);
  return 0;
}

static int build(mpm_module *m, const mpm_config *cfg, int seed) {
  fluid_content *fc = m->content;
  mpm_grid *g = m->grid;
  mpm_walls walls;
  MPM_CALL(mpm_grid_add_phase(g, "fluid", &m->phase));
  MPM_CALL(mpm_config_get_real(cfg, "fluid.empty_node_mass", &g->phase[m->phase].empty_fraction));
  fc->filter_phase = -1;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.light_node_mass", &g->phase[m->phase].light_fraction));
  MPM_CALL(read_settings(fc, cfg, g));
  if (fc->mol_damping > 0.0) MPM_CALL(mpm_grid_add_phase(g, "fluid_filter", &fc->filter_phase));
  MPM_CALL(mpm_walls_from_config(&walls, cfg, g->dim));
  MPM_CALL(mpm_constraints_add_walls(&fc->cons, &walls, g));
  fc->walls = walls;
  MPM_CALL(fluid_gridp_init(m, cfg));
  MPM_CALL(pic_auto(m, cfg));
  if (fc->refill_holes < 0) fc->refill_holes = fluid_gridp_weighted(fc); /* auto */
  if (fc->merge_light > 0.0 && fc->reg_every == 0 && fc->refill_every == 0 && !fc->refill_holes)
    return mpm_config_fail(cfg, "fluid.merge_light",
                           "merge_light = %g merges light particles at each regularisation or "
                           "refill, and none happens (no fluid.regularise_every, no "
                           "fluid.refill_every, and this gas refills no holes: "
                           "fluid.refill_holes); set one of them, or remove merge_light",
                           fc->merge_light);
  MPM_CALL(fluid_open_new(&fc->open, m, cfg, &walls, fc->gas.gamma, fc->ppc));
  MPM_CALL(fluid_obstacles_build(&fc->obs, cfg, g, fc->ppc, (const unsigned char(*)[2])m->open));
  fc->obs.coast = fc->tr.classic; /* (fluid_obstacle.h, Nodes) */
  MPM_CALL(fluid_wall_ls_init(m, cfg, fc->tr.classic));
  MPM_CALL(fluid_gauge_check(m, cfg));
  fc->virt.phase = -1;
  if (!fc->gridp && fluid_open_uses_virtual(fc->open)) MPM_CALL(fluid_virtual_init(&fc->virt, g));
  MPM_ALLOC(fc->node, (size_t)(g->dim + 3) * g->nnodes);
  MPM_CALL(fluid_particles_new(&m->particles, g->dim, &fc->lay, fc->tr.apic, fc->gas.mu > 0,
                               fc->gas.av_riemann, fc->tr.classic));
  /* What a checkpoint may hold: positive mass, volume, volume ratio and internal energy (the
   * module's check faults on any other). */
  mpm_particles_set_range(m->particles, fc->lay.f_m, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  mpm_particles_set_range(m->particles, fc->lay.f_V0, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  mpm_particles_set_range(m->particles, FLUID_J, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  mpm_particles_set_range(m->particles, FLUID_E, 0.0, HUGE_VAL, MPM_FIELD_LO_OPEN);
  if (seed) MPM_CALL(fluid_seed(m, cfg));
  return 0;
}

int fluid_module_create(mpm_module **mp, const mpm_config *cfg, mpm_grid *grid, int seed) {
  const char *const *names;
  int count;
  *mp = NULL;
  MPM_CALL(mpm_config_instances(cfg, "gas", &names, &count));
  if (count == 0) {
    const char *const *obstacles;
    int nobs;
    MPM_CALL(mpm_config_instances(cfg, "obstacle", &obstacles, &nobs));
    if (nobs == 0) return 0;
    char key[160];
    snprintf(key, sizeof key, "obstacle.%s.shape", obstacles[0]);
    return mpm_config_fail(cfg, key,
                           "an obstacle is a boundary condition for the gas, and the scene has no "
                           "[gas.NAME] section: add the gas, or make the body a [solid.NAME] with "
                           "material = rigid");
  }
  mpm_module *m;
  MPM_ALLOC(m, 1);
  *mp = m;
  snprintf(m->name, sizeof m->name, "fluid");
  m->ops = &fluid_ops;
  m->role = MPM_ROLE_FLUID;
  m->grid = grid;
  fluid_content *fc;
  MPM_ALLOC(fc, 1);
  m->content = fc;
  const int rc = build(m, cfg, seed);
  if (rc) {
    mpm_module_destroy(mp);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  fc->ops = fluid_ops;
  if (fc->current_rate) fc->ops.p2g_rate = fluid_p2g_rate;
  m->ops = &fc->ops;
  m->cells_every = fc->refill_holes ? 1 : fc->refill_every;
  m->wall_slack = 0.5;
  m->commits_history = !fc->tr.classic && !fc->current_rate; /* the pending strain rate */
  return 0;
}
