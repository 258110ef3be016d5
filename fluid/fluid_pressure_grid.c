/* fluid.pressure_smoothing = w > 0: the pressure each gas particle puts into its stress is
 * p_p + w (A(p)_p - p_p), with the grid-smoothed value
 *
 *   A(p)_p = sum_i S_ip p_i,   p_i = sum_q S_iq V_q p_q / sum_q S_iq V_q,
 *
 * the volume-weighted nodal average of the particles' ideal-gas pressures interpolated back.
 * The force is still sum_p V_p sigma_p grad S_ip, so momentum stays exact. A uniform pressure
 * is kept exactly (sum_i S_ip = 1), whatever the particles' positions; what the smoothing
 * removes is the particle-to-particle scatter of p, which the particle quadrature of the force
 * turns into grid-scale forces. The artificial viscosity q stays the particle's own: it acts in
 * the narrow compressions of shocks, where a smoothed q would spread them by a cell.
 *
 * Energy. The stress does the work sum_p V_p pbar_p tr L_p on the grid (pbar the blended
 * pressure). Booked as each particle's own (de/dt = -pbar V tr L / m), it drains particles
 * whose own pressure is below pbar while they expand (de/dt = -pbar dv/dt < -p dv/dt: their
 * entropy falls). So each particle takes the work of its own pressure, -p_p V_p tr L_p / m_p,
 * and the difference, r_q = V_q (p_q - pbar_q) tr L_q summed over the particles, is given back
 * through the same average: particle p takes V_p A(r / V)_p / m_p. Since sum_p V_p A(s)_p =
 * sum_i V_i s_i = sum_q V_q s_q for any s, the shares sum to sum_q r_q exactly, and total
 * energy stays at roundoff. Where tr L is smooth the shares nearly cancel the differences
 * (sum_q V_q A(p)_q = sum_q V_q p_q), so the correction is small and local.
 *
 * What it does (measured 2026-12-02, docs/gas.md): at w = 1 nothing resists particles clumping
 * within a cell (their pressure no longer pushes them apart, only the average's does): Sod at
 * 200 cells stopped at t = 0.17 with particles piled at the contact and one at e = 0, under
 * bs32 and usl alike, with either energy booking. Blended, it runs, but Sod's L1 grows with w
 * and with refinement, and the ERK grid-scale mode grows faster. Kept as an experiment.
 *
 * The sums use the gas's own particles only (not the open faces' or obstacles' virtual
 * particles, not a solid sharing the nodes): near a face, an obstacle or a solid the average
 * is one-sided. They are the filter grid phase's m_i and (m v)_i (fluid_transfer.c), summed
 * over the ranks' halos as the mass is; a node no particle reaches keeps 0 and weighs nothing.
 * Cost: two scalar deposits, four halo exchanges and two gathers per right-hand side. */
#include "fluid_internal.h"

#include "fluid_eos.h"

#include "mpm_error.h"
#include "mpm_kernels.h"

/* Scratch layout (stride n): V, p, s, out, then 2 dim - 1 discarded gather outputs. */
enum { W_V, W_P, W_S, W_OUT, W_DUMMY };

/* out = A(s) with weights V (see the file comment). */
static int average(mpm_module *m, const double *y, const double *V, const double *s, double *out,
                   double *dummy) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  mpm_grid *g = m->grid;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  mpm_grid_phase *ph = &g->phase[fc->filter_phase];
  mpm_grid_phase_zero(g, fc->filter_phase);
  mpm_p2g_args a = {.n = n, .m = V, .lp = fc->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n, a.v[d] = s;
  mpm_kernels_get(dim)->p2g(g, fc->filter_phase, &a);
  double *f[2] = {ph->m_i, ph->mv_i[0]};
  MPM_CALL(mpm_grid_halo_reverse(g, f, 2));
  double *s_i = ph->v_i[0];
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    s_i[l] = ph->m_i[l] > 0.0 ? ph->mv_i[0][l] / ph->m_i[l] : 0.0;
  MPM_CALL(mpm_grid_halo_forward(g, &s_i, 1));
  mpm_g2p_args r = {.n = n, .lp = fc->lp};
  for (int d = 0; d < dim; ++d) {
    r.x[d] = a.x[d];
    r.v_i[d] = r.a_i[d] = s_i;
    r.v_out[d] = d == 0 ? out : dummy + (size_t)(d - 1) * n;
    r.a_out[d] = dummy + (size_t)(dim - 1 + d) * n;
  }
  mpm_kernels_get(dim)->g2p(g, &r);
  return 0;
}

int fluid_pressure_grid(mpm_module *m, const double *y, const fluid_batch *b, double *work,
                        double *pbar) {
  const fluid_content *fc = m->content;
  const mpm_lidx n = m->particles->n;
  double *V = work + (size_t)W_V * n, *pp = work + (size_t)W_P * n;
  for (mpm_lidx i = 0; i < n; ++i) {
    V[i] = b->V0[i] * b->J[i];
    pp[i] = fluid_pressure(fc->gas.gamma, b->m[i] / V[i], b->e[i]);
  }
  MPM_CALL(average(m, y, V, pp, pbar, work + (size_t)W_DUMMY * n));
  const double w = fc->pressure_share;
  if (w < 1.0)
    for (mpm_lidx i = 0; i < n; ++i) pbar[i] = pp[i] + w * (pbar[i] - pp[i]);
  return 0;
}

int fluid_pressure_grid_heat(mpm_module *m, const double *y, const double *L, const double *pbar,
                             double *work, double *power) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *V = work + (size_t)W_V * n, *pp = work + (size_t)W_P * n;
  double *s = work + (size_t)W_S * n, *out = work + (size_t)W_OUT * n;
  for (mpm_lidx i = 0; i < n; ++i) {
    double tr = 0.0;
    for (int d = 0; d < dim; ++d) tr += L[(size_t)(d * dim + d) * n + i];
    s[i] = (pp[i] - pbar[i]) * tr; /* r / V */
  }
  MPM_CALL(average(m, y, V, s, out, work + (size_t)W_DUMMY * n));
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  for (mpm_lidx i = 0; i < n; ++i) power[i] += V[i] * (out[i] - s[i]) / mass[i];
  return 0;
}
