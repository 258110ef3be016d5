/* The grid pressure beside a solid (fluid.pressure = grid, fluid_gridp.c; docs/refinement.md, "A
 * gas beside a solid"): the solid's region taken out of the gas's span integrals by the solid's
 * own quadrature, its particles (m->beside, mpm_points: positions and volumes V_s) handed over
 * by the sim.
 *
 * The method. The span integrals run over the whole domain; beside a solid the gas's share is
 *   f_i = integral of p_h grad N_i - sum_s V_s p_h(x_s) grad N_i(x_s),
 *   D_i = integral of N_i div v_h - sum_s V_s N_i(x_s) div v_h(x_s),
 * where p_h = sum_j N_j p_j and v_h the gas's nodal velocity field. The nodal pressure p_j is the
 * gas's where the gas has mass (the gas nodes, G_j = 1), and is continued into the solid (the
 * active nodes c without gas mass) by the gas's own pressure through the solid's points: each
 * point s takes the mean of the gas nodes it reads, q_s = sum_j N_j(x_s) G_j p_j / W_s with
 * W_s = sum_j N_j(x_s) G_j, and each continued node the volume-weighted mean of the points with
 * W_s > 0 in its support, p_c = sum_s V_s N_c(x_s) q_s / S_c. Those reach every node within two
 * of a gas node, all the nodes whose supports meet a gas node's. Why:
 *  - rest: with the gas at p0 every p_j is p0, the span integral vanishes and the correction is
 *    -sum_s V_s p0 grad N_i(x_s), the negative of the solid's stress force at -p0 I node by node:
 *    a body at rest in gas at rest stays at rest to roundoff whatever its shape and whatever the
 *    levels' faces (the particles' quadrature needs a uniform lattice);
 *  - energy: the continuation is linear in the gas's pressures, p_c = sum_j E_cj p_j, so the
 *    rate takes its transpose, the gas nodes' D_j += sum_c E_cj D_c: the forces' power
 *    sum_i f_i . v_i = sum_j p_j D_j over every node (the corrections are adjoint, as the span
 *    integrals are) is then exactly the gas particles' p dV, and total energy stays exact.
 * (The solid's mean stress as the continuation, measured first, keeps the rest too, but the
 * continued nodes' share sum_c p_c D_c of the work is no gas particle's: a pulse striking a
 * neo-Hookean disk lost 1 % of its energy, 4 % in a refined box.)
 *
 * On a hierarchy each transfer is composite (mpm_hier_p2g, mpm_hier_g2p on prolonged fields; the
 * solid lies on the finest level) and the deposits are restricted onto the active nodes as the
 * gas's are.
 *
 * The same two corrections serve fluid.pressure = hybrid (fluid_gridp.c) with the gas's own
 * particles as the points (fluid_gridp_points_force, fluid_gridp_points_rate): s->pts names the
 * points each instance reads.
 *
 * Invariant: without a solid (m->beside NULL) the solid's instance does nothing. */
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
  free(s->buf), free(s->lev), free(s->W);
  s->buf = NULL, s->lev = NULL, s->W = NULL, s->cap = 0;
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l)
    free(s->A[l]), free(s->B[l]), s->A[l] = s->B[l] = NULL;
}

static const mpm_grid *level_grid(const mpm_module *m, int l) {
  return m->hier ? m->hier->level[l].grid : m->grid;
}

/* Scratch per solid point: q, W, u. */
enum { S_Q, S_W, S_U, S_COUNT };
static int ensure(mpm_module *m, fluid_gridp_solid *s, mpm_lidx n) {
  const int fresh = !s->A[0];
  for (int l = 0; fresh && l < (m->hier ? m->hier->nlevels : 1); ++l) {
    const mpm_lidx nn = m->hier ? m->hier->level[l].grid->nnodes : m->grid->nnodes;
    MPM_ALLOC(s->A[l], (size_t)nn);
    MPM_ALLOC(s->B[l], (size_t)nn);
  }
  if (s->cap >= n && s->buf) return 0;
  free(s->buf), free(s->lev);
  s->lev = NULL;
  s->cap = n + n / 4 + 16;
  const size_t count = (size_t)S_COUNT * (size_t)s->cap;
  s->buf = calloc(count, sizeof(double));
  if (!s->buf) MPM_FAIL_OOM(count * sizeof(double));
  if (m->hier) MPM_ALLOC(s->lev, s->cap);
  return 0;
}

/* On a hierarchy: find the solid's points' levels once and vouch for them (mpm_hier_levels_known)
 * for the transfers of one entry below (the continuation's weights, deposits and gathers: about
 * eight per right-hand side, each of which would find them again), keeping the gas's to
 * restore (unvouch). */
static void vouch(mpm_module *m, fluid_gridp_solid *s) {
  const mpm_points *pts = s->pts;
  if (!m->hier || !s->lev) return;
  mpm_hier_levels_vouched(m->hier, &s->saved_x, &s->saved_n, &s->saved_lev);
  for (mpm_lidx i = 0; i < pts->n; ++i) {
    double x[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < m->grid->dim; ++d) x[d] = pts->x[d][i];
    s->lev[i] = (unsigned char)mpm_hier_level_of(m->hier, x);
  }
  mpm_hier_levels_known(m->hier, pts->x[0], pts->n, s->lev);
}

static void unvouch(mpm_module *m, const fluid_gridp_solid *s) {
  if (m->hier && s->lev) mpm_hier_levels_known(m->hier, s->saved_x, s->saved_n, s->saved_lev);
}

static double *slot(const fluid_gridp_solid *s, int k) {
  return s->buf + (size_t)k * s->cap;
}

/* Zero the region phase, make the lean deposit (mpm_kernels.h) of the points, m with v0 (the
 * two-scalar deposit: m v0 into mv_i[0]) or (m, viso), through the hierarchy, restrict it and
 * sum level 0's ghosts. */
static int deposit(mpm_module *m, const fluid_gridp_solid *s, const double *mass, const double *v0,
                   const double *viso) {
  const mpm_points *pts = s->pts;
  const int dim = m->grid->dim;
  mpm_p2g_args a = {
      .n = pts->n, .m = mass, .s = v0, .viso = viso, .lp = ((fluid_content *)m->content)->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = pts->x[d];
  /* The arrays this deposit fills, the only ones its readers read: m_i, mv_i[0] or f_i. */
  mpm_grid_phase *ph = &m->grid->phase[s->phase];
  double *f[2 + MPM_MAX_DIM];
  int nf = 0;
  if (mass) f[nf++] = ph->m_i;
  if (v0) f[nf++] = ph->mv_i[0];
  for (int d = 0; viso && d < dim; ++d) f[nf++] = ph->f_i[d];
  int rc = 0;
  if (m->hier) {
    mpm_hier_phase_zero(m->hier, s->phase);
    fluid_p2g_any(m, s->phase, &a, &rc);
    MPM_CALL(rc);
    mpm_hier_restrict(m->hier, s->phase);
  } else {
    for (int k = 0; k < nf; ++k) memset(f[k], 0, sizeof(double) * (size_t)m->grid->nnodes);
    fluid_p2g_any(m, s->phase, &a, &rc);
  }
  return mpm_grid_halo_reverse(m->grid, f, nf);
}

static int nlevels(const mpm_module *m) {
  return m->hier ? m->hier->nlevels : 1;
}

static int active(const mpm_module *m, int l, mpm_lidx k) {
  return !m->hier || m->hier->level[l].active[k];
}

/* The scalar gather (mpm_kernels.h) at the points: the ns (<= 2) prolonged level scalars sc[j]
 * into slots out[j], or with div, div v_h of velocity vel (NULL: the phase's) into div. */
static int gather(mpm_module *m, const fluid_gridp_solid *s, int phase, const mpm_hier_nodal *vel,
                  int ns, double *const *const *sc, const int *out, double *div) {
  const mpm_points *pts = s->pts;
  const int dim = m->grid->dim;
  const mpm_grid_phase *ph = &m->grid->phase[phase];
  mpm_g2p_args a = {
      .n = pts->n, .lp = ((fluid_content *)m->content)->lp, .nscalar = ns, .div_out = div};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = pts->x[d];
    a.v_i[d] = vel ? vel->v_i[0][d] : ph->v_i[d], a.a_i[d] = ph->a_i[d];
  }
  mpm_hier_scalars hs;
  for (int j = 0; j < ns; ++j) {
    a.s_i[j] = sc[j][0], a.s_out[j] = slot(s, out[j]);
    for (int l = 0; l < nlevels(m); ++l) hs.s_i[l][j] = sc[j][l];
  }
  if (!m->hier) {
    mpm_kernels_get(dim)->g2p(m->grid, &a);
    return 0;
  }
  return mpm_hier_g2p_from(m->hier, phase, &a, vel, ns ? &hs : NULL);
}

/* The continuation's weights: A = the gas nodes' indicator G (prolonged), W_s into slot S_W and
 * the weight V_s [W_s > 0] into slot S_U; with P, B = G p (prolonged) and q_s into slot S_Q. The
 * region phase's m_i then holds S_c, and with P its mv_i[0] sum_s V_s N_c q_s. */
static int weights(mpm_module *m, fluid_gridp_solid *s, const double *const *M,
                   const double *const *P) {
  const mpm_points *pts = s->pts;
  for (int l = 0; l < nlevels(m); ++l)
    for (mpm_lidx k = 0; k < level_grid(m, l)->nnodes; ++k) {
      const int gas = active(m, l, k) && M[l][k] > 0.0;
      s->A[l][k] = gas;
      s->B[l][k] = gas && P ? P[l][k] : 0.0;
    }
  MPM_CALL(fluid_gridp_prolong(m, s->A));
  if (P) MPM_CALL(fluid_gridp_prolong(m, s->B));
  double *const *sc[2] = {s->A, s->B};
  const int out[2] = {S_W, S_Q};
  MPM_CALL(gather(m, s, s->phase, NULL, P ? 2 : 1, sc, out, NULL));
  double *W = slot(s, S_W), *q = slot(s, S_Q), *w = slot(s, S_U);
  for (mpm_lidx i = 0; i < pts->n; ++i) {
    w[i] = W[i] > 0.0 ? pts->V[i] : 0.0;
    if (P) q[i] = W[i] > 0.0 ? q[i] / W[i] : 0.0;
  }
  return deposit(m, s, w, P ? q : NULL, NULL);
}

/* An active node without gas mass where the continuation reaches (S_c > 0). */
static int continued(const mpm_module *m, const fluid_gridp_solid *s, int l, mpm_lidx k,
                     const double *const *M) {
  return active(m, l, k) && !(M[l][k] > 0.0) && level_grid(m, l)->phase[s->phase].m_i[k] > 0.0;
}

/* The share of a node's geometric volume the solid's points must fill for the node to be deep:
 * the whole of it, less roundoff. A node the solid fills in part lies at a face of the solid; a
 * face touching gas has its ring, and a free face (touching no gas) keeps no pressure: carried
 * there, its span force, handed to the solid, loaded the faces of the slab of
 * cases/fsi_transmission.ini that touch no gas (2,484 steps and 3 retries where the particles'
 * pressure took 2,061; with this cut 2,073 and none). */
#define DEEP_COVER 0.99

/* The hybrid (s->deep; uniform grid): the nodes beyond the continued ring that the solid fills
 * whole take the ring's mean pressure (weighted by the ring nodes' solid-region mass, summed
 * over the ranks' owned nodes), so that p_h has no edge inside the solid. An edge is where the span
 * integral and the solid's quadrature differ: at rest the force there would be the quadrature's
 * error on the edge's profile, which the coupler now hands to the solid (mpm_coupling.c,
 * hand_over), and a solid at rest would move. Beyond the edge the span force at rest is -p0 sum_s
 * V_s grad N_i(x_s), the negative of the prestressed solid's own force: it stays at rest node by
 * node. A deep node lies three nodes or more from every gas node (the ring holds the nodes within
 * two), so its rate integral, read from the gas's velocity, vanishes and the transpose has nothing
 * to carry. */
static int deep(mpm_module *m, fluid_gridp_solid *s, double *const *P, const double *const *M) {
  const mpm_grid *g = m->grid;
  const mpm_grid_phase *ph = &g->phase[s->phase];
  double sum[2] = {0.0, 0.0}, all[2];
  for (mpm_lidx k = 0; k < g->nnodes; ++k) {
    s->A[0][k] = continued(m, s, 0, k, M);
    if (s->A[0][k] > 0.0 && mpm_grid_node_is_owned(g, k))
      sum[0] += ph->m_i[k] * P[0][k], sum[1] += ph->m_i[k];
  }
  MPM_CALL_MPI(MPI_Allreduce(sum, all, 2, MPI_DOUBLE, MPI_SUM, g->comm));
  const double pbar = all[1] > 0.0 ? all[0] / all[1] : 0.0;
  if (!s->W) MPM_CALL(fluid_gridp_geometric_volume(g, &s->W));
  MPM_CALL(deposit(m, s, s->pts->V, NULL, NULL)); /* m_i: the solid's volume at each node */
  for (mpm_lidx k = 0; k < g->nnodes; ++k)
    if (s->A[0][k] == 0.0 && !(M[0][k] > 0.0) && ph->m_i[k] >= DEEP_COVER * s->W[k]) P[0][k] = pbar;
  return 0;
}

int fluid_gridp_solid_pressure(mpm_module *m, fluid_gridp_solid *s, double *const *P,
                               const double *const *M) {
  if (!m->beside) return 0;
  s->pts = m->beside;
  MPM_CALL(ensure(m, s, m->beside->n));
  vouch(m, s);
  const int rc = weights(m, s, M, (const double *const *)P);
  unvouch(m, s);
  MPM_CALL(rc);
  for (int l = 0; l < nlevels(m); ++l) {
    const mpm_grid_phase *ph = &level_grid(m, l)->phase[s->phase];
    for (mpm_lidx k = 0; k < level_grid(m, l)->nnodes; ++k)
      if (continued(m, s, l, k, M)) P[l][k] = ph->mv_i[0][k] / ph->m_i[k];
  }
  return s->deep ? deep(m, s, P, M) : 0;
}

int fluid_gridp_points_load(mpm_module *m, fluid_gridp_solid *s, double *const *P, double **load) {
  const mpm_points *pts = s->pts;
  MPM_CALL(ensure(m, s, pts->n));
  double *const *sc[1] = {P};
  const int out[1] = {S_Q};
  MPM_CALL(gather(m, s, s->phase, NULL, 1, sc, out, NULL));
  double *q = *load = slot(s, S_Q);
  for (mpm_lidx i = 0; i < pts->n; ++i) q[i] *= pts->V[i];
  return 0;
}

int fluid_gridp_points_force(mpm_module *m, fluid_gridp_solid *s, double *const *P) {
  const int dim = m->grid->dim;
  /* viso = +V_s p_h(x_s): the kernel's f_i -= viso grad N_i is the correction. */
  double *q;
  MPM_CALL(fluid_gridp_points_load(m, s, P, &q));
  MPM_CALL(deposit(m, s, NULL, NULL, q));
  for (int l = 0; l < nlevels(m); ++l) {
    const mpm_grid *g = level_grid(m, l);
    const mpm_grid_phase *src = &g->phase[s->phase], *dst = &g->phase[m->phase];
    for (int d = 0; d < dim; ++d)
      for (mpm_lidx k = 0; k < g->nnodes; ++k) dst->f_i[d][k] += src->f_i[d][k];
  }
  return 0;
}

int fluid_gridp_solid_force(mpm_module *m, fluid_gridp_solid *s, double *const *P) {
  if (!m->beside) return 0;
  s->pts = m->beside;
  MPM_CALL(ensure(m, s, m->beside->n));
  vouch(m, s);
  const int rc = fluid_gridp_points_force(m, s, P);
  unvouch(m, s);
  return rc;
}

/* D_j -= sum_s V_s N_j(x_s) div v_h(x_s) on every node. */
int fluid_gridp_points_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                            double *const *D) {
  const mpm_points *pts = s->pts;
  const mpm_lidx n = pts->n;
  MPM_CALL(ensure(m, s, n));
  double *q = slot(s, S_Q);
  MPM_CALL(gather(m, s, m->phase, vel, 0, NULL, NULL, q));
  for (mpm_lidx i = 0; i < n; ++i) q[i] *= pts->V[i];
  MPM_CALL(deposit(m, s, q, NULL, NULL)); /* m_i: sum N V div v_h */
  for (int l = 0; l < nlevels(m); ++l) {
    const double *r = level_grid(m, l)->phase[s->phase].m_i;
    for (mpm_lidx k = 0; k < level_grid(m, l)->nnodes; ++k) D[l][k] -= r[k];
  }
  return 0;
}

/* fluid_gridp_solid_rate with the points' levels vouched for. */
static int solid_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                      double *const *D, const double *const *M) {
  const mpm_points *pts = s->pts;
  MPM_CALL(fluid_gridp_points_rate(m, s, vel, D));
  /* The continuation's transpose: R_c = D_c / S_c, u_s = V_s / W_s sum_c N_c R_c, and the gas
   * nodes take D_j += sum_s N_j u_s. */
  MPM_CALL(weights(m, s, M, NULL));
  for (int l = 0; l < nlevels(m); ++l) {
    const double *S = level_grid(m, l)->phase[s->phase].m_i;
    for (mpm_lidx k = 0; k < level_grid(m, l)->nnodes; ++k)
      s->B[l][k] = continued(m, s, l, k, M) ? D[l][k] / S[k] : 0.0;
  }
  MPM_CALL(fluid_gridp_prolong(m, s->B));
  double *const *sc[1] = {s->B};
  const int out[1] = {S_Q};
  MPM_CALL(gather(m, s, s->phase, NULL, 1, sc, out, NULL));
  const double *W = slot(s, S_W), *R = slot(s, S_Q);
  double *u = slot(s, S_U);
  for (mpm_lidx i = 0; i < pts->n; ++i) u[i] = W[i] > 0.0 ? pts->V[i] * R[i] / W[i] : 0.0;
  MPM_CALL(deposit(m, s, u, NULL, NULL));
  for (int l = 0; l < nlevels(m); ++l) {
    const double *r = level_grid(m, l)->phase[s->phase].m_i;
    for (mpm_lidx k = 0; k < level_grid(m, l)->nnodes; ++k)
      if (active(m, l, k) && M[l][k] > 0.0) D[l][k] += r[k];
  }
  return 0;
}

int fluid_gridp_solid_rate(mpm_module *m, fluid_gridp_solid *s, const mpm_hier_nodal *vel,
                           double *const *D, const double *const *M) {
  if (!m->beside) return 0;
  s->pts = m->beside;
  MPM_CALL(ensure(m, s, m->beside->n));
  vouch(m, s);
  const int rc = solid_rate(m, s, vel, D, M);
  unvouch(m, s);
  return rc;
}
