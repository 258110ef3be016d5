/* The projected dilatation (solid.NAME.dilatation = projected): the volume change a body's
 * deformation gradient takes is the grid's, not the particle's own.
 *
 * At two particles per cell a quadratic B-spline grid does not see a particle-scale alternation
 * of the volumetric strain: the nodal forces of such a pattern cancel, so nothing restores it,
 * and a rate that differs between the two particle columns of a cell (beside a coupling face,
 * where the node a cell outside carries the gas's velocity) builds one up. Projecting the rate
 * of volume change onto the nodes and back removes that pattern at its source: each particle's
 * tr L is replaced by
 *
 *   d_p = sum_i S_ip (sum_q S_iq V_q tr L_q) / (sum_q S_iq V_q),
 *
 * the volume-weighted nodal mean of tr L interpolated back, and L by L + (d_p - tr L_p) / dim I,
 * so that dF/dt = L F changes by (d_p - tr L_p) / dim F and the deviatoric part of the motion
 * is the particle's own. This is the F-bar / B-bar idea of the finite-element method carried to
 * MPM by a nodal projection (Coombs, Charlton, Cortis and Augarde 2018 average over cells;
 * Moutsanidis, Long and Bazilevs 2020 project onto the spline basis, as here). A uniform tr L
 * is projected onto itself (the ratio of the two sums), so a homogeneous motion is the
 * particle method's to roundoff.
 *
 * Invariants: runs inside the solid's G2P, after this RHS's p2g grouped the particles by body
 * (sc->idx), on one level (refinement refuses the key, solid_refine.c); the projecting bodies
 * deposit into the grid phase dil.phase and only they read it back, so a body's dilatation mixes
 * only with projecting bodies' at shared nodes. The bulk viscosity reads the particle's own rate
 * (lag_divv runs before, and the method of lines' rate is solid_bulkq_rate.c's). */
#include "solid_dilatation.h"

#include "mpm_error.h"
#include "mpm_kernels.h"
#include "solid_tensor.h"

#include <stdlib.h>
#include <string.h>

int solid_dilatation_read(mpm_module *m, const mpm_config *cfg) {
  solid_content *sc = m->content;
  solid_dilatation *dl = &sc->dil;
  MPM_ALLOC(dl->body, sc->nbodies);
  for (int b = 0; b < sc->nbodies; ++b) {
    char key[160];
    const char *kind;
    solid_key(key, sizeof key, sc->body[b].section, "dilatation");
    MPM_CALL(mpm_config_get_string(cfg, key, &kind));
    dl->body[b] = strcmp(kind, "projected") == 0;
    if (dl->body[b] && sc->body[b].mat->ops->rigid)
      return mpm_config_fail(cfg, key,
                             "a rigid body does not deform, so it has no dilatation to project; "
                             "remove the key");
    dl->on |= dl->body[b];
  }
  if (!dl->on) return 0;
  return mpm_grid_add_phase(m->grid, "solid_dilatation", &dl->phase);
}

void solid_dilatation_free(solid_dilatation *dl) {
  free(dl->body);
  free(dl->idx);
  free(dl->work);
  memset(dl, 0, sizeof *dl);
}

/* The projecting particles into dl->idx (*all: every particle, no list); their count. */
static mpm_lidx projecting(const solid_content *sc, int *all) {
  const solid_dilatation *dl = &sc->dil;
  mpm_lidx k = 0, at = 0;
  *all = 1;
  for (int b = 0; b < sc->nbodies; ++b) *all &= dl->body[b];
  for (int b = 0; b < sc->nbodies; ++b) {
    if (dl->body[b] && !*all)
      memcpy(dl->idx + k, sc->idx + at, sizeof(mpm_lidx) * (size_t)sc->count[b]), k += sc->count[b];
    at += sc->count[b];
  }
  return *all ? at : k;
}

static int ensure(solid_dilatation *dl, mpm_lidx n) {
  if (n <= dl->cap) return 0;
  free(dl->idx);
  free(dl->work);
  dl->idx = NULL, dl->work = NULL;
  dl->cap = n + n / 4 + 16;
  MPM_ALLOC(dl->idx, dl->cap);
  MPM_ALLOC(dl->work, (size_t)3 * dl->cap);
  return 0;
}

int solid_dilatation_apply(mpm_module *m, const double *y, double *L, double *Fdot) {
  solid_content *sc = m->content;
  solid_dilatation *dl = &sc->dil;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  mpm_grid *g = m->grid;
  mpm_grid_phase *ph = &g->phase[dl->phase];
  MPM_CALL(ensure(dl, n));
  int all;
  const mpm_lidx count = projecting(sc, &all);
  const mpm_lidx *idx = all ? NULL : dl->idx;
  double *V = dl->work, *tr = dl->work + dl->cap, *bar = dl->work + 2 * (size_t)dl->cap;
  const double *F = y + (size_t)p->offset[F_F] * n;
  const double *V0 = mpm_particles_comp(p, sc->lay.f_V0, 0);
  for (mpm_lidx k = 0; k < count; ++k) {
    const mpm_lidx i = idx ? idx[k] : k;
    V[i] = V0[i] * solid_det(dim, F, n, i);
    tr[i] = 0.0;
    for (int d = 0; d < dim; ++d) tr[i] += L[(size_t)(d * dim + d) * n + i];
  }
  /* The two-scalar deposit (mpm_kernels.h): S V into m_i, S V tr L into mv_i[0]. */
  const size_t bytes = sizeof(double) * (size_t)g->nnodes;
  memset(ph->m_i, 0, bytes);
  memset(ph->mv_i[0], 0, bytes);
  mpm_p2g_args a = {.n = n, .idx = idx, .nidx = count, .m = V, .s = tr, .lp = sc->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = y + (size_t)(p->offset[F_X] + d) * n;
  mpm_kernels_get(dim)->p2g(g, dl->phase, &a);
  double *sums[2] = {ph->m_i, ph->mv_i[0]};
  MPM_CALL(mpm_grid_halo_reverse(g, sums, 2));
  for (mpm_lidx k = 0; k < g->nnodes; ++k)
    ph->mv_i[0][k] = ph->m_i[k] > 0.0 ? ph->mv_i[0][k] / ph->m_i[k] : 0.0;
  MPM_CALL(mpm_grid_halo_forward(g, &sums[1], 1));
  mpm_g2p_args r = {.n = n, .idx = idx, .nidx = count, .lp = sc->lp, .nscalar = 1};
  for (int d = 0; d < dim; ++d) r.x[d] = a.x[d];
  r.s_i[0] = ph->mv_i[0];
  r.s_out[0] = bar;
  mpm_kernels_get(dim)->g2p(g, &r);
  const size_t nt = (size_t)dim * dim;
  for (mpm_lidx k = 0; k < count; ++k) {
    const mpm_lidx i = idx ? idx[k] : k;
    const double c = (bar[i] - tr[i]) / dim;
    for (size_t t = 0; t < nt; ++t) Fdot[t * n + i] += c * F[t * n + i];
    for (int d = 0; d < dim; ++d) L[(size_t)(d * dim + d) * n + i] += c;
  }
  return 0;
}
