/* The solids' bulk viscosity under the method of lines (the ERK pairs, ssprk2): the strain rate
 * of the state itself, so that the RHS is a function of y alone (solid_bulk_viscosity.h).
 *
 * The coupler previews the solve of this RHS's deposit (mpm_module.h, p2g_rate) and leaves in
 * the solid's phase the nodal velocity its G2P will read, the coupling and constraints acting.
 * tr L of that velocity at each particle goes to pending_divv; each compressed particle of a
 * body with a bulk viscosity then deposits -V q I as a massless particle (forces only), packed
 * so that the deposit costs only what is compressed. The rate is the one F moves with in this
 * RHS (dF/dt = L F), so q does work V q |tr D| >= 0 against the motion only: as under usl,
 * that work leaves the kinetic energy and is stored nowhere (a drop of the total energy).
 *
 * Invariants: runs after this RHS's p2g (ensure_scratch sized the arrays, the particles are
 * grouped by body, vsig is free again); writes only scratch arrays and pending_divv, which
 * nothing in the RHS reads; solid_bulkq_commit copies it to divv after an accepted step, and
 * the stable step reads divv, which a checkpoint holds (a restart is bitwise). */
#include "solid_internal.h"

#include "mpm_error.h"
#include "mpm_timer.h"

#include <string.h>

/* tr L of the phase's (previewed) nodal velocity at every particle, into tr. */
static int current_rate(mpm_module *m, const double *y, double *tr) {
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const mpm_grid_phase *ph = &m->grid->phase[m->phase];
  double *L = sc->scratch + (size_t)2 * dim * n;
  mpm_g2p_args a = {.n = n, .lp = sc->lp, .L_out = L};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
    a.v_i[d] = ph->v_i[d];
    a.a_i[d] = ph->a_i[d];
    a.v_out[d] = sc->scratch + (size_t)d * n;
    a.a_out[d] = sc->scratch + (size_t)(dim + d) * n;
  }
  MPM_CALL(solid_gather(m, &a));
  for (mpm_lidx i = 0; i < n; ++i) {
    double s = 0.0;
    for (int d = 0; d < dim; ++d) s += L[(size_t)(d * dim + d) * n + i];
    tr[i] = s;
  }
  return 0;
}

/* Pack the compressed particles of the bodies with a bulk viscosity: their positions into x
 * and -V q I into vsig (both with stride cap). Returns their count. */
static mpm_lidx pack(const solid_content *sc, const mpm_particles *p, const double *y,
                     const double *tr, double *x, double *vsig) {
  const int dim = p->dim;
  const mpm_lidx n = p->n, cap = sc->cap;
  const double *mass = mpm_particles_comp(p, sc->lay.f_m, 0);
  const mpm_lidx *idx = sc->idx;
  mpm_lidx k = 0;
  for (int b = 0; b < sc->nbodies; idx += sc->count[b++]) {
    const solid_bulkq *q = &sc->body[b].q;
    if (!solid_bulkq_on(q)) continue;
    for (mpm_lidx j = 0; j < sc->count[b]; ++j) {
      const mpm_lidx i = idx[j];
      if (!(tr[i] < 0.0)) continue;
      for (int d = 0; d < dim; ++d)
        x[(size_t)d * cap + k] = y[(size_t)(p->offset[F_X] + d) * n + i];
      const double vq = solid_bulkq_vq(q, mass[i], tr[i]);
      for (int c = 0; c < dim * dim; ++c) vsig[(size_t)c * cap + k] = c % (dim + 1) ? 0.0 : -vq;
      ++k;
    }
  }
  return k;
}

int solid_bulkq_p2g_rate(mpm_module *m, double t, const double *y) {
  (void)t;
  solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  double *tr = mpm_particles_comp(p, sc->lay.f_pending, 0);
  mpm_timer_start(MPM_T_G2P);
  const int rc = current_rate(m, y, tr);
  mpm_timer_stop(MPM_T_G2P);
  MPM_CALL(rc);
  double *x = sc->scratch, *vsig = sc->vsig;
  const mpm_lidx count = pack(sc, p, y, tr, x, vsig);
  if (count == 0) return 0;
  /* Packed with stride cap; the deposit reads vsig's components with stride count. */
  for (int c = 1; c < dim * dim; ++c)
    memmove(vsig + (size_t)c * count, vsig + (size_t)c * sc->cap, sizeof(double) * count);
  mpm_p2g_args a = {.n = count, .m = sc->zero, .vsig = vsig, .lp = sc->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = x + (size_t)d * sc->cap, a.v[d] = sc->zero;
  mpm_timer_start(MPM_T_P2G);
  const int rd = solid_deposit(m, &a);
  mpm_timer_stop(MPM_T_P2G);
  return rd;
}

void solid_bulkq_commit(const mpm_module *m) {
  const solid_content *sc = m->content;
  const mpm_particles *p = m->particles;
  memcpy(mpm_particles_comp(p, sc->lay.f_divv, 0), mpm_particles_comp(p, sc->lay.f_pending, 0),
         sizeof(double) * (size_t)p->n);
}
