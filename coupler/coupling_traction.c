/* `traction`: the seed paper's explicit procedure. The phases solve separately; the gas sees
 * the solid's surface as a moving slip wall, and the force that wall exerts on the gas goes
 * back to the solid as an equal and opposite nodal force. (Inside the solid, and where the
 * solid's clamp or rigid body holds a node, the gas is held in every direction: below.)
 *
 * At a shared node with the solid's outward normal n (from its mass gradient) the gas's normal
 * velocity is held to the wall's, as a static obstacle holds it to zero (fluid_obstacle.h), and
 * in the method-of-lines RHS likewise its normal acceleration. The wall is bilateral (the gas
 * can neither enter the solid nor leave it) and slip (tangential velocities stay each phase's
 * own). The momentum the wall takes from the gas, J = m_g (v_g - v_g') . n n, is the gas's load
 * on the solid and goes to the solid at the same node, so the exchange balances to roundoff.
 *
 * The wall moves with the solid's velocity after that load: both end with the normal velocity
 * of their centre of mass at the node, (m_s v_s + m_g v_g) . n / (m_s + m_g). A wall that kept
 * the solid's velocity from before the load (the gas held to v_s, the solid then pushed on by J)
 * leaves a normal velocity jump between the phases after every step, of the order of the load
 * itself: the next step removes it as a new impulse, whatever the step size, so the force grows
 * as 1/h on a short step and the interface creates energy at every step (measured: +0.5 % of
 * the total energy by t = 0.2 on cases/fsi_box.ini with usl, a reflected wave +0.26 of the
 * incident off, a transmitted one +7 %). Holding both to the common velocity does no net work.
 *
 * The pressure of the gas reaches the solid through the held nodes: the gas nodes within a
 * stencil of the interface are shared nodes (the solid's stencil reaches as far out as the
 * gas's reaches in), so the push of the gas's incomplete stencil there is taken by the wall and
 * passed on. No ghost pressure is added.
 *
 * Under fluid.wall_treatment = least_squares the gas particles next to the solid also take the
 * gas's least-squares wall fit, against the solid's surface as a moving wall
 * (mpm_solid_wall.h): their velocity, internal energy and density come from the gas particles
 * behind them instead of from the held nodes alone (their normal velocity stays the held
 * nodes'), and the fit's impulses go to the solid's nodes. On the 1-D piston
 * (cases/fsi_gas_piston.ini) that lifts the first gas layer from 36 % under the post-shock
 * pressure to within 1 % of it.
 *
 * Inside the solid the normal means nothing: where |grad m_s| dx < 0.5 m_s (a node a cell or
 * more inside; the nodes on a straight face give 1.5) the phases share the velocity of their
 * centre of mass, as under `velocity`. In a bar three cells thick the nodes in its middle see
 * gas from both faces and a normal of roundoff direction; holding the gas only along it let the
 * gas through. Where the solid's clamp or rigid body holds a shared node, the gas takes the
 * solid's velocity there (MPM_COUPLING_HOLDS), and on a domain wall the normal loses its
 * component across the wall (mpm_coupling_solid_surface). On the main job
 * (cases/supersonic_bar.ini, 4 mm) these cut the gas particles within a quarter cell of a bar
 * particle from 27-73 to 4-11 (0.5-1.5 ms): they had come in through the clamped root along the
 * floor. The run still blows up, at the outflow's floor corner. */
#include "mpm_coupling.h"
#include "mpm_error.h"
#include "mpm_solid_wall.h"

/* |grad m_s| dx / m_s below which a shared node counts as inside the solid. */
#define TRACTION_SURFACE 0.5

static int traction_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    double n[MPM_MAX_DIM];
    if (!mpm_coupling_shared(c, l)) continue;
    const double ms = s->m_i[l], mg = g->m_i[l];
    if (!mpm_coupling_solid_surface(c, l, TRACTION_SURFACE, n)) {
      /* Inside the solid: the phases share the velocity of their centre of mass. */
      double v[MPM_MAX_DIM], a[MPM_MAX_DIM];
      for (int d = 0; d < dim; ++d) {
        v[d] = (ms * s->v_i[d][l] + mg * g->v_i[d][l]) / (ms + mg);
        a[d] = (ms * s->a_i[d][l] + mg * g->a_i[d][l]) / (ms + mg);
      }
      mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, v, a, h);
      mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, v, a, h);
      continue;
    }
    /* Both end with the normal velocity of their centre of mass: the wall the gas sees moves
     * with the solid's velocity after the gas's load (m_g fg + m_s fs = 0). */
    const double fg = -ms / (ms + mg), fs = mg / (ms + mg);
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
    mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, vg, ag, h);
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, vs, as, h);
  }
  return 0;
}

/* Under the gas's least-squares wall treatment the gas particles next to the solid take the
 * fit against the solid's surface as a moving wall (mpm_solid_wall.h). */
static int traction_create(mpm_coupling *c, const mpm_config *cfg) {
  mpm_solid_wall *w = NULL;
  const int rc = mpm_solid_wall_offer(c, cfg, &w);
  c->content = w; /* traction_destroy frees it, after an input error too */
  return rc;
}

static void traction_destroy(mpm_coupling *c) {
  mpm_solid_wall *w = c->content;
  mpm_solid_wall_free(&w);
  c->content = NULL;
}

/* The relaxation of the phases' own velocities under the method of lines (mpm_coupling.h)
 * acts where this scheme ties them: along the normal on the solid's surface, every component
 * inside it. */
static int traction_relax_normal(const mpm_coupling *c, mpm_lidx l, double *n) {
  return mpm_coupling_solid_surface(c, l, TRACTION_SURFACE, n);
}

static const mpm_key_spec traction_keys[] = {
    MPM_COUPLING_MOL_RATE_KEY("velocity, traction and sharp")};

static const mpm_coupling_ops traction_ops = {
    .create = traction_create,
    .after_solve = traction_after_solve,
    .relax_normal = traction_relax_normal,
    .destroy = traction_destroy,
};

const mpm_coupling_type coupling_traction = {
    .name = "traction",
    .help = "separate solves; the gas sees the solid's surface as a moving slip wall and its "
            "load goes back to the solid as an equal and opposite nodal force: the seed paper's "
            "explicit procedure",
    .needs = MPM_COUPLING_NORMALS | MPM_COUPLING_HOLDS | MPM_COUPLING_RELAXES,
    .keys = traction_keys,
    .nkeys = sizeof traction_keys / sizeof traction_keys[0],
    .ops = &traction_ops,
};
