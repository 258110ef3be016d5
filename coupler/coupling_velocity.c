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

static const mpm_key_spec velocity_keys[] = {
    MPM_COUPLING_MOL_RATE_KEY("velocity, traction and sharp")};

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
