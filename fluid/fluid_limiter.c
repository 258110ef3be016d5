/* The limiter of the riemann artificial viscosity (fluid.av_form = riemann; fluid_stress.h).
 *
 * Christensen's limiter (Christensen 1990; Caramana, Shashkov and Whalen 1998, eq. 10) in the
 * particle form: along each axis d the particle's compression L_dd is compared with the same
 * component of the nodal velocity's gradient one cell either side, at x_p -+ dx e_d, with
 * r_-, r_+ the two ratios:
 *
 *   psi_d = max(0, min((r_- + r_+) / 2, 2 r_-, 2 r_+, 1)),
 *
 * 1 in smooth compression (the gradient is the same either side: q off) and 0 at a shock (it
 * is much weaker either side: all of q). The particle's psi is the mean of psi_d weighted by
 * the compression -L_dd of the axes that compress; a particle that does not compress has
 * psi = 0 (q is 0 there anyway). The limiter only scales q >= 0, so the energy balance and
 * conservation are those of the stress it limits.
 *
 * The gradients are read from the nodal velocity the particle's own L came from, by one G2P
 * of the 2 dim neighbour points of every compressing particle. A neighbour point whose stencil
 * would leave the rank's stored nodes (a particle that crossed into a neighbour rank's cells
 * within an ERK step) is moved back to the last point whose stencil is stored: only such
 * particles can see a limiter that depends on the decomposition. */
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_kernels.h"

#include <stdlib.h>

/* Christensen's psi from the ratios r_- and r_+. */
static double christensen(double rm, double rp) {
  double s = 0.5 * (rm + rp);
  if (2.0 * rm < s) s = 2.0 * rm;
  if (2.0 * rp < s) s = 2.0 * rp;
  if (s > 1.0) s = 1.0;
  return s > 0.0 ? s : 0.0;
}

/* Grow the neighbour-point scratch to npts points: x, v, a (dim each) and L (dim^2). */
static int ensure_points(fluid_content *fc, int dim, mpm_lidx npts) {
  if (npts <= fc->lim_cap && fc->lim) return 0;
  free(fc->lim);
  fc->lim = NULL;
  fc->lim_cap = npts + npts / 4 + 16;
  MPM_ALLOC(fc->lim, (size_t)(3 * dim + dim * dim) * fc->lim_cap);
  return 0;
}

int fluid_limiter(mpm_module *m, const double *y, const double *const *v_i, const double *L,
                  double *psi) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double *x = y + (size_t)p->offset[FLUID_X] * n;
  mpm_lidx k = 0; /* compressing particles */
  for (mpm_lidx i = 0; i < n; ++i) {
    double tr = 0.0;
    for (int d = 0; d < dim; ++d) tr += L[(size_t)(d * dim + d) * n + i];
    psi[i] = tr < 0.0 ? -1.0 : 0.0; /* -1: to be computed */
    k += tr < 0.0;
  }
  if (k == 0) return 0;
  const mpm_lidx np = 2 * (mpm_lidx)dim * k; /* point (j, d, side) at (2 d + side) k + j */
  MPM_CALL(ensure_points(fc, dim, np));
  const size_t cap = (size_t)fc->lim_cap;
  double *xs = fc->lim, *vs = xs + (size_t)dim * cap, *as = vs + (size_t)dim * cap;
  double *Ls = as + (size_t)dim * cap;     /* stride np: the kernel's n */
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM]; /* where a point's stencil is stored */
  for (int d = 0; d < dim; ++d) {
    lo[d] = g->lo[d] + (g->box_lo[d] + 1) * g->dx;
    hi[d] = g->lo[d] + (g->box_lo[d] + g->box_n[d] - 2) * g->dx * (1.0 - 1e-12);
  }
  mpm_lidx j = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    if (psi[i] == 0.0) continue;
    for (int d = 0; d < dim; ++d)
      for (int side = 0; side < 2; ++side) {
        const mpm_lidx q = (2 * d + side) * k + j;
        for (int c = 0; c < dim; ++c) {
          double xc = x[(size_t)c * n + i] + (c == d ? (side ? g->dx : -g->dx) : 0.0);
          xc = xc < lo[c] ? lo[c] : xc > hi[c] ? hi[c] : xc;
          xs[(size_t)c * cap + q] = xc;
        }
      }
    ++j;
  }
  mpm_g2p_args a = {.n = np, .lp = fc->lp, .L_out = Ls};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = xs + (size_t)d * cap;
    a.v_i[d] = a.a_i[d] = v_i[d];
    a.v_out[d] = vs + (size_t)d * cap, a.a_out[d] = as + (size_t)d * cap;
  }
  mpm_kernels_get(dim)->g2p(g, &a);
  j = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    if (psi[i] == 0.0) continue;
    double num = 0.0, den = 0.0;
    for (int d = 0; d < dim; ++d) {
      const size_t dd = (size_t)(d * dim + d);
      const double c = L[dd * n + i];
      if (!(c < 0.0)) continue;
      const double rm = Ls[dd * np + (2 * d) * k + j] / c;
      const double rp = Ls[dd * np + (2 * d + 1) * k + j] / c;
      num += -c * christensen(rm, rp), den += -c;
    }
    psi[i] = den > 0.0 ? num / den : 0.0;
    ++j;
  }
  return 0;
}
