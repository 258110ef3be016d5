/* `contact`: separate nodal fields, and a normal-only interaction where the phases approach
 * each other (Bardenhagen, Brackbill and Sulsky 2000, with the solid's mass-gradient normal):
 * free slip, no interpenetration, separation allowed, optional Coulomb friction.
 *
 * At a shared node with the solid's outward normal n, the centre-of-mass velocity v_cm =
 * (m_s v_s + m_g v_g) / (m_s + m_g) is what a single field would move with. The phases approach
 * when (v_s - v_cm) . n > 0; then each loses its normal velocity relative to v_cm (the normal
 * impulse J = m_s (v_s - v_cm) . n passes from the solid to the gas), and with friction mu the
 * tangential relative velocity is reduced by at most mu J, never reversed. Both changes are
 * equal and opposite: momentum balances to roundoff, and the exchange only removes kinetic
 * energy (an inelastic normal impact, plus the friction work).
 *
 * The classic update tests and corrects the velocities after the solve (the step's new
 * velocities), as an impulse over the step. The adaptive ERK pairs are refused (see
 * contact_create). */
#include "mpm_coupling.h"
#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const mpm_key_spec contact_keys[] = {
    {"coupling.friction", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "contact: Coulomb friction coefficient between the solid and the gas, >= 0 (0: free slip)", 0,
     "-"},
};

typedef struct {
  double mu;
} contact;

/* The switch between touching and not makes a method-of-lines RHS non-smooth: under bs32 the
 * adaptive step fell a thousandfold below the uncoupled one (1e-7 s against 1e-4 s on
 * cases/fsi_pulse.ini), so contact runs with the classic update only. */
static int contact_create(mpm_coupling *c, const mpm_config *cfg) {
  const char *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "usl") != 0 && strcmp(method, "musl") != 0)
    return mpm_config_fail(cfg, "coupling.scheme",
                           "contact needs the classic update (time.method = usl or musl): its "
                           "on/off switch makes the %s right-hand side non-smooth and the "
                           "adaptive step collapses; use velocity or traction with %s",
                           method, method);
  contact *ct;
  MPM_ALLOC(ct, 1);
  c->content = ct;
  return mpm_config_get_real(cfg, "coupling.friction", &ct->mu);
}

static void contact_destroy(mpm_coupling *c) {
  free(c->content);
  c->content = NULL;
}

/* Remove the normal part of w relative to w_cm (and with friction some of the tangential part)
 * from the solid's w_s and the gas's w_g, given the normal impulse per unit solid mass jn
 * ((w_s - w_cm) . n). */
static void correct(int dim, const double *n, double ms, double mg, double mu, double jn,
                    const double *wcm, double *ws, double *wg) {
  double rel[MPM_MAX_DIM], tan = 0.0; /* solid's tangential velocity relative to v_cm */
  for (int d = 0; d < dim; ++d) {
    rel[d] = ws[d] - wcm[d] - jn * n[d];
    tan += rel[d] * rel[d];
  }
  tan = sqrt(tan);
  /* Coulomb: the tangential change is at most mu times the normal one, and stops the slip. */
  const double ft = tan > 0 && mu > 0 ? fmin(mu * jn, tan) / tan : 0.0;
  for (int d = 0; d < dim; ++d) {
    const double dws = -jn * n[d] - ft * rel[d]; /* the solid's change */
    ws[d] += dws;
    wg[d] -= dws * ms / mg;
  }
}

static int contact_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  const contact *ct = c->content;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    double n[MPM_MAX_DIM];
    if (!mpm_coupling_shared(c, l) || !mpm_coupling_solid_normal(c, l, n)) continue;
    const double ms = s->m_i[l], mg = g->m_i[l], inv = 1.0 / (ms + mg);
    double vs[MPM_MAX_DIM], vg[MPM_MAX_DIM], vcm[MPM_MAX_DIM], vn = 0.0;
    for (int d = 0; d < dim; ++d) {
      vs[d] = s->v_i[d][l], vg[d] = g->v_i[d][l];
      vcm[d] = (ms * vs[d] + mg * vg[d]) * inv;
      vn += (vs[d] - vcm[d]) * n[d];
    }
    /* The first pass corrects the step's new velocities (an impulse over h); MUSL's remap
     * pass the velocities of the remapped momenta (h = 0: positions move with them). */
    if (!(vn > 0)) continue;
    correct(dim, n, ms, mg, ct->mu, vn, vcm, vs, vg);
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, vs, NULL, h);
    mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, vg, NULL, h);
  }
  return 0;
}

static const mpm_coupling_ops contact_ops = {
    .create = contact_create,
    .after_solve = contact_after_solve,
    .destroy = contact_destroy,
};

const mpm_coupling_type coupling_contact = {
    .name = "contact",
    .help = "separate fields, a normal-only interaction where the phases approach: free slip, "
            "no interpenetration, separation allowed; coupling.friction for Coulomb friction",
    .needs = MPM_COUPLING_NORMALS,
    .keys = contact_keys,
    .nkeys = (int)(sizeof contact_keys / sizeof contact_keys[0]),
    .ops = &contact_ops,
};
