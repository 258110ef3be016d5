/* The grid pressure beside a solid (fluid.pressure = grid, fluid_gridp.c; docs/refinement.md, "A
 * gas beside a solid"): the solid's region taken out of the gas's span integrals by the solid's
 * own quadrature, its particles (m->beside, mpm_points: positions, volumes V_s, mean pressures
 * p_s = -tr(sigma_s) / dim) handed over by the sim.
 *
 * The method. The span integrals run over the whole domain; beside a solid the gas's share is
 *   f_i = integral of p_h grad N_i - sum_s V_s p_h(x_s) grad N_i(x_s),
 *   D_i = integral of N_i div v_h - sum_s V_s N_i(x_s) div v_h(x_s),
 * where p_h = sum_j N_j p_j and v_h the gas's nodal velocity field. The nodal pressure p_j is the
 * gas's where the gas has mass, and is continued into the solid (active nodes without gas mass
 * where the solid deposits) by the solid's volume-weighted mean pressure there. Why: with the
 * gas at p0 and the solid at -p0 I, p_h = p0 everywhere, the span integral vanishes and the
 * correction is -sum_s V_s p0 grad N_i(x_s), the negative of the solid's stress force node by
 * node: a body at rest in gas at rest stays at rest to roundoff whatever the geometry and
 * whatever the levels' faces (the particles' quadrature needs a uniform lattice). The two
 * corrections are adjoint, as the span integrals are (sum_i f_i . v_i = sum_j p_j D_j): the
 * force's work is the gas's p dV up to the continued nodes' share sum_c p_c D_c, which no gas
 * particle reads; D_c is the solid quadrature's error on a node whose support the solid covers
 * (measured small against the time integrator's drift, docs/refinement.md).
 *
 * On a hierarchy each transfer is composite (mpm_hier_p2g, mpm_hier_g2p; the solid lies on the
 * finest level), the deposits are restricted onto the active nodes as the gas's are, and the
 * continued pressure is prolonged with the gas's (fluid_gridp.c).
 *
 * Invariant: without a solid (m->beside NULL) nothing here runs. */
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"

#include <stdlib.h>
#include <string.h>

int fluid_gridp_solid_init(fluid_gridp_solid *s, mpm_grid *g) {
  memset(s, 0, sizeof *s);
  return mpm_grid_add_phase(g, "fluid_solid_region", &s->phase);
}

void fluid_gridp_solid_free(fluid_gridp_solid *s) {
  free(s->buf);
  s->buf = NULL, s->cap = 0;
}

/* Scratch per solid particle: q (1), v and a (2 dim), L (dim^2), zeros (1 + dim). */
static int ensure(fluid_gridp_solid *s, mpm_lidx n, int dim) {
  if (s->cap >= n && s->buf) return 0;
  free(s->buf);
  s->cap = n + n / 4 + 16;
  s->buf = calloc((size_t)(2 + 3 * dim + dim * dim) * s->cap, sizeof(double));
  if (!s->buf) MPM_FAIL_OOM((size_t)s->cap);
  return 0;
}

static double *slot(const fluid_gridp_solid *s, int k) {
  return s->buf + (size_t)k * s->cap;
}

/* Zero the region phase, deposit (m, v[0], vsig) of the solid's points through the hierarchy,
 * restrict it and sum level 0's ghosts. */
static int deposit(mpm_module *m, const fluid_gridp_solid *s, const double *mass, const double *v0,
                   const double *vsig) {
  const mpm_points *pts = m->beside;
  const int dim = m->grid->dim, zero = 2 + 2 * dim + dim * dim;
  mpm_p2g_args a = {.n = pts->n, .m = mass, .vsig = vsig, .lp = ((fluid_content *)m->content)->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = pts->x[d], a.v[d] = d == 0 && v0 ? v0 : slot(s, zero);
  int rc = 0;
  if (m->hier) {
    mpm_hier_phase_zero(m->hier, s->phase);
    fluid_p2g_any(m, s->phase, &a, &rc);
    MPM_CALL(rc);
    mpm_hier_restrict(m->hier, s->phase);
  } else {
    mpm_grid_phase_zero(m->grid, s->phase);
    fluid_p2g_any(m, s->phase, &a, &rc);
  }
  mpm_grid_phase *ph = &m->grid->phase[s->phase];
  double *f[2 + MPM_MAX_DIM] = {ph->m_i, ph->mv_i[0]};
  for (int d = 0; d < dim; ++d) f[2 + d] = ph->f_i[d];
  return mpm_grid_halo_reverse(m->grid, f, 2 + dim);
}

static const mpm_grid *level_grid(const mpm_module *m, int l) {
  return m->hier ? m->hier->level[l].grid : m->grid;
}

static int nlevels(const mpm_module *m) {
  return m->hier ? m->hier->nlevels : 1;
}

int fluid_gridp_solid_pressure(mpm_module *m, fluid_gridp_solid *s, double *const *P,
                               const double *const *M) {
  const mpm_points *pts = m->beside;
  if (!pts) return 0;
  MPM_CALL(ensure(s, pts->n, m->grid->dim));
  MPM_CALL(deposit(m, s, pts->V, pts->p, NULL)); /* m_i: sum N V, mv_i[0]: sum N V p */
  for (int l = 0; l < nlevels(m); ++l) {
    const mpm_grid *g = level_grid(m, l);
    const mpm_grid_phase *ph = &g->phase[s->phase];
    const unsigned char *act = m->hier ? m->hier->level[l].active : NULL;
    for (mpm_lidx k = 0; k < g->nnodes; ++k)
      if ((!act || act[k]) && !(M[l][k] > 0.0) && ph->m_i[k] > 0.0)
        P[l][k] = ph->mv_i[0][k] / ph->m_i[k];
  }
  return 0;
}

/* Gather at the solid's points: v_h and L of velocity vel (NULL: the region phase's, zero) into
 * the scratch, and the scalar sc (per level, or NULL) into slot 0. */
static int gather(mpm_module *m, const fluid_gridp_solid *s, int phase, const mpm_hier_nodal *vel,
                  double *const *sc, int want_L) {
  const mpm_points *pts = m->beside;
  const int dim = m->grid->dim;
  const mpm_grid_phase *ph = &m->grid->phase[phase];
  mpm_g2p_args a = {.n = pts->n, .lp = ((fluid_content *)m->content)->lp};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = pts->x[d];
    a.v_i[d] = vel ? vel->v_i[0][d] : ph->v_i[d], a.a_i[d] = ph->a_i[d];
    a.v_out[d] = slot(s, 1 + d), a.a_out[d] = slot(s, 1 + dim + d);
  }
  a.L_out = want_L ? slot(s, 1 + 2 * dim) : NULL;
  mpm_hier_scalars hs;
  if (sc) {
    a.nscalar = 1, a.s_i[0] = sc[0], a.s_out[0] = slot(s, 0);
    for (int l = 0; l < nlevels(m); ++l) hs.s_i[l][0] = sc[l];
  }
  if (!m->hier) {
    mpm_kernels_get(dim)->g2p(m->grid, &a);
    return 0;
  }
  return mpm_hier_g2p_from(m->hier, phase, &a, vel, sc ? &hs : NULL);
}

int fluid_gridp_solid_force(mpm_module *m, fluid_gridp_solid *s, double *const *P) {
  const mpm_points *pts = m->beside;
  if (!pts) return 0;
  const int dim = m->grid->dim;
  const mpm_lidx n = pts->n;
  MPM_CALL(gather(m, s, s->phase, NULL, P, 0));
  /* vsig = +V_s p_h(x_s) I: the kernel's f_i -= vsig grad N_i is the correction. */
  double *vsig = slot(s, 1), *q = slot(s, 0);
  memset(vsig, 0, sizeof(double) * (size_t)dim * dim * n);
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx i = 0; i < n; ++i) vsig[(size_t)(d * dim + d) * n + i] = pts->V[i] * q[i];
  MPM_CALL(deposit(m, s, slot(s, 2 + 2 * dim + dim * dim), NULL, vsig));
  for (int l = 0; l < nlevels(m); ++l) {
    const mpm_grid *g = level_grid(m, l);
    const mpm_grid_phase *src = &g->phase[s->phase], *dst = &g->phase[m->phase];
    for (int d = 0; d < dim; ++d)
      for (mpm_lidx k = 0; k < g->nnodes; ++k) dst->f_i[d][k] += src->f_i[d][k];
  }
  return 0;
}

int fluid_gridp_solid_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                           double *const *D) {
  const mpm_points *pts = m->beside;
  if (!pts) return 0;
  const int dim = m->grid->dim;
  const mpm_lidx n = pts->n;
  MPM_CALL(gather(m, s, m->phase, vel, NULL, 1));
  const double *L = slot(s, 1 + 2 * dim);
  double *q = slot(s, 0);
  for (mpm_lidx i = 0; i < n; ++i) {
    double div = 0.0;
    for (int d = 0; d < dim; ++d) div += L[(size_t)(d * dim + d) * n + i];
    q[i] = pts->V[i] * div;
  }
  MPM_CALL(deposit(m, s, q, NULL, NULL)); /* m_i: sum N V div v_h */
  for (int l = 0; l < nlevels(m); ++l) {
    const mpm_grid *g = level_grid(m, l);
    const double *r = g->phase[s->phase].m_i;
    for (mpm_lidx k = 0; k < g->nnodes; ++k) D[l][k] -= r[k];
  }
  return 0;
}
