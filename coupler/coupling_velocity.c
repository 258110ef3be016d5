/* `velocity`: the seed paper's implicit procedure. Where both phases have mass they share one
 * nodal velocity: the masses, momenta and forces are summed and solved together, so no-slip
 * holds at the interface without tracking it.
 *
 * After the separate solves, each shared node takes the mass-weighted mean of the phases'
 * velocities and accelerations, which is exactly the combined solve: sum m_k v_k = sum mv_k +
 * h sum f_k. The momentum each phase gains there comes from the other: the exchange balances to
 * roundoff. It is a perfectly inelastic exchange: the nodal kinetic energy it removes is what
 * the coupling power reports (<= 0).
 *
 * Constraints. A solid's clamp or rigid body holds its own nodes after the solve; on a shared
 * node the gas then takes the solid's constrained velocity (the shared field obeys both), as
 * an external constraint, not an interface exchange. */
#include "mpm_coupling.h"

#include <math.h>
#include <stdlib.h>

/* The method of lines' relaxation (mpm_coupling.h, MPM_COUPLING_RELAXES), in units of the
 * slowest module's stable rate: no step is longer than time.cfl times that module's stable step,
 * so h k stays below 2 time.cfl, inside bs32's real stability interval (-2.5, 0) for time.cfl <
 * 1.25, as the gas's wall rate argues (fluid/fluid_transfer.c). The default is as fast as that
 * allows, so that the phases' velocities meet within a few steps: at 1 the Mach 2 face of
 * test_multirate_face_mri read 1.9 % below u* under MRIStep at time.cfl = 0.4, at 2 0.3 % (58 %
 * above without it). */
static const mpm_key_spec velocity_keys[] = {
    {"coupling.mol_rate", MPM_KEY_REAL, "2", 0, 2, 0, 0, NULL,
     "velocity, ERK pairs: the rate at which the phases' own velocities relax towards each "
     "other at the shared nodes, in units of the slowest module's stable rate (1 / the largest "
     "of the modules' stable steps); the method of lines moves a particle with the shared "
     "nodal velocity but gives its own velocity only the nodal acceleration (0: off; the "
     "classic update's impulse does this once a step and ignores the key)",
     0, "-"},
};

static int velocity_create(mpm_coupling *c, const mpm_config *cfg) {
  return mpm_config_get_real(cfg, "coupling.mol_rate", &c->relax_share);
}

static int velocity_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    if (!mpm_coupling_shared(c, l)) continue;
    const double ms = s->m_i[l], mg = g->m_i[l], inv = 1.0 / (ms + mg);
    double v[MPM_MAX_DIM], a[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) {
      v[d] = (ms * s->v_i[d][l] + mg * g->v_i[d][l]) * inv;
      a[d] = (ms * s->a_i[d][l] + mg * g->a_i[d][l]) * inv;
    }
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, v, a, h);
    mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, v, a, h);
  }
  return 0;
}

/* The gas takes the solid's constrained velocity where a constraint changed it (in the classic
 * update as an impulse, like every nodal constraint); the solid's constraint takes the reaction,
 * which is recorded as the gas's force on the solid. */
static int velocity_after_constrain(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l)
    if (mpm_coupling_shared(c, l)) mpm_coupling_follow_solid(c, l, h, MPM_ALL_AXES);
  return 0;
}

static const mpm_coupling_ops velocity_ops = {
    .create = velocity_create,
    .after_solve = velocity_after_solve,
    .after_constrain = velocity_after_constrain,
};

const mpm_coupling_type coupling_velocity = {
    .name = "velocity",
    .help = "one shared nodal velocity where both phases have mass: no-slip, the seed paper's "
            "implicit procedure; the default",
    .needs = MPM_COUPLING_RELAXES,
    .keys = velocity_keys,
    .nkeys = sizeof velocity_keys / sizeof velocity_keys[0],
    .ops = &velocity_ops,
};
