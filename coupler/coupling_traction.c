/* `traction`: the seed paper's explicit procedure. The phases solve separately; the gas sees
 * the solid as a moving slip wall, and the force that wall exerts on the gas goes back to the
 * solid as an equal and opposite nodal force.
 *
 * At a shared node with the solid's outward normal n (from its mass gradient) the gas's normal
 * velocity is held to the solid's, as a static obstacle holds it to zero (fluid_obstacle.h):
 * v_g' = v_g - ((v_g - v_s) . n) n, and in the method-of-lines RHS likewise its normal
 * acceleration. The wall is bilateral: the gas can neither enter the solid nor leave it. The
 * momentum the wall takes from the gas, J = m_g (v_g - v_g'), is the gas's load on the solid;
 * the solid receives it at the same node (v_s' = v_s + J / m_s), so the exchange balances to
 * roundoff. The solid's velocity after that load is no longer exactly the wall velocity the gas
 * saw: the procedure is explicit, and the work the two sides do does not cancel; coupling.csv
 * reports the difference.
 *
 * The pressure of the gas reaches the solid through the held nodes: the gas nodes within a
 * stencil of the interface are shared nodes (the solid's stencil reaches as far out as the
 * gas's reaches in), so the push of the gas's incomplete stencil there is taken by the wall and
 * passed on. No ghost pressure is added. */
#include "mpm_coupling.h"

static int traction_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    double n[MPM_MAX_DIM];
    if (!mpm_coupling_shared(c, l) || !mpm_coupling_solid_normal(c, l, n)) continue;
    /* The wall is the solid where it outweighs the gas. On the fringe of its stencil the roles
     * swap: the light solid node follows the gas's normal velocity and the gas takes the
     * reaction; a reaction m_g / m_s >> 1 times the gas's change would throw it off. The
     * changes along n satisfy m_g fg + m_s fs = 0 either way. */
    const double ms = s->m_i[l], mg = g->m_i[l];
    const int wall_is_solid = ms >= mg;
    const double fg = wall_is_solid ? -1.0 : -ms / mg, fs = wall_is_solid ? mg / ms : 1.0;
    double vs[MPM_MAX_DIM], vg[MPM_MAX_DIM], as[MPM_MAX_DIM], ag[MPM_MAX_DIM];
    double vn = 0.0, an = 0.0;
    for (int d = 0; d < dim; ++d) {
      vs[d] = s->v_i[d][l], vg[d] = g->v_i[d][l], as[d] = s->a_i[d][l], ag[d] = g->a_i[d][l];
      vn += (vg[d] - vs[d]) * n[d], an += (ag[d] - as[d]) * n[d];
    }
    for (int d = 0; d < dim; ++d) {
      vg[d] += fg * vn * n[d], vs[d] += fs * vn * n[d];
      if (h > 0) continue;
      ag[d] += fg * an * n[d], as[d] += fs * an * n[d];
    }
    mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, vg, h > 0 ? NULL : ag, h);
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, vs, h > 0 ? NULL : as, h);
  }
  return 0;
}

static const mpm_coupling_ops traction_ops = {
    .after_solve = traction_after_solve,
};

const mpm_coupling_type coupling_traction = {
    .name = "traction",
    .help = "separate solves; the gas sees the solid as a moving slip wall and its load goes "
            "back to the solid as an equal and opposite nodal force: the seed paper's explicit "
            "procedure",
    .needs = MPM_COUPLING_NORMALS,
    .ops = &traction_ops,
};
