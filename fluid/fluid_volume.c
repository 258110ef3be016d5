/* The particle's volume rate over its own domain (fluid.volume_rate = domain).
 *
 * The default rule moves a gas particle's J by the nodal velocity's divergence at its centre,
 * dJ/dt = J tr L(x_p). Where the interpolated velocity carries grid-scale ripple, that point
 * value is not the rate at which the particle's share of the space grows: on Toro's strong
 * shock moving across the grid, the hot gas that comes to rest behind the rarefaction sits at
 * 0.87 cells apart, the point rate there runs 7 % above the rate of the spacing of the
 * particles around it, and J ends 3.9 % above the spacing's J (docs/gas.md). The domain rule
 * takes instead the flux of the interpolated velocity through the faces of the particle's
 * domain, a box of side l = min((J V0)^(1/dim), dx) around x_p, by the midpoint rule on each
 * face:
 *
 *   tr L_dom = sum_d (v_d(x_p + l/2 e_d) - v_d(x_p - l/2 e_d)) / l,
 *
 * so that particles whose domains tile a region have volume rates that sum to the flux
 * through its boundary, as the divergence theorem has it. Only J reads it: the energy keeps
 * the point rate (the one the forces' work is made of), and the ideal gas's forces, p V =
 * (gamma - 1) m e, and its sound speed do not depend on J, so in an inviscid gas alone the
 * motion is unchanged and only the density and pressure the particles carry change; the
 * viscous stress, obstacles, open faces, shifting and regularisation, which read J, see the
 * new volume.
 *
 * Known defect (docs/gas.md): a face point's stencil reaches one node beyond the particle's,
 * and a node the gas does not fill holds v = 0, so at the edge of gas moving into vacuum the
 * rate is wrong; the option stays an experiment, off by default.
 *
 * A face point whose stencil would leave the rank's stored nodes is moved back to the last
 * point whose stencil is stored, as in fluid_limiter.c; a particle whose two face points
 * along an axis then coincide keeps the point rate along that axis. */
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_grid.h"

#include <math.h>
#include <stdlib.h>

/* Component v of the nodal velocity at the point whose stencil starts at node base with the
 * weights w along each axis. */
static double value_at(const mpm_grid *g, const double *v, const int *base,
                       const double (*w)[MPM_SHAPE_MAX_SUPPORT], int sup) {
  const mpm_lidx sy = g->box_n[0], sz = (mpm_lidx)g->box_n[0] * g->box_n[1];
  const mpm_lidx first = mpm_grid_local_index(g, base);
  const int nz = g->dim == 3 ? sup : 1;
  double s = 0.0;
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < sup; ++b) {
      const mpm_lidx row = first + b * sy + c * sz;
      double r = 0.0;
      for (int a = 0; a < sup; ++a) r += w[0][a] * v[row + a];
      s += w[1][b] * (g->dim == 3 ? w[2][c] : 1.0) * r;
    }
  return s;
}

int fluid_volume_rate(mpm_module *m, const double *y, const double *const *v_i, const double *L,
                      const double **rate) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = p->dim, sup = mpm_shape_support(g->shape);
  const mpm_lidx n = p->n;
  if (n > fc->vol_cap || !fc->vol) {
    free(fc->vol);
    fc->vol = NULL;
    fc->vol_cap = n + n / 4 + 16;
    MPM_ALLOC(fc->vol, fc->vol_cap);
  }
  const double *x = y + (size_t)p->offset[FLUID_X] * n, *J = y + (size_t)p->offset[FLUID_J] * n;
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM]; /* where a point's stencil is stored, in cells */
  for (int d = 0; d < dim; ++d) {
    lo[d] = g->box_lo[d] + 1.0;
    hi[d] = (g->box_lo[d] + g->box_n[d] - 2) * (1.0 - 1e-12);
  }
  for (mpm_lidx i = 0; i < n; ++i) {
    const double V = J[i] * V0[i], side_l = dim == 2 ? sqrt(V) : cbrt(V);
    const double half = 0.5 * fmin(side_l, g->dx) / g->dx;
    double xi[3] = {0, 0, 0}, w[3][MPM_SHAPE_MAX_SUPPORT], dw[3][MPM_SHAPE_MAX_SUPPORT];
    int base[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xi[d] = (x[(size_t)d * n + i] - g->lo[d]) / g->dx;
    mpm_shape_eval(g->shape, dim, xi, fc->lp, base, w, dw);
    double tr = 0.0;
    for (int d = 0; d < dim; ++d) {
      double face[2], at[2];
      const int b0 = base[d];
      double w0[MPM_SHAPE_MAX_SUPPORT];
      for (int a = 0; a < sup; ++a) w0[a] = w[d][a];
      for (int side = 0; side < 2; ++side) {
        double xs = xi[d] + (side ? half : -half);
        xs = xs < lo[d] ? lo[d] : xs > hi[d] ? hi[d] : xs;
        face[side] = xs;
        base[d] = mpm_shape_1d(g->shape, xs, fc->lp, w[d], dw[d]);
        at[side] = value_at(g, v_i[d], base, (const double(*)[MPM_SHAPE_MAX_SUPPORT])w, sup);
      }
      base[d] = b0;
      for (int a = 0; a < sup; ++a) w[d][a] = w0[a];
      const double l = (face[1] - face[0]) * g->dx;
      tr += l > 0.0 ? (at[1] - at[0]) / l : L[(size_t)(d * dim + d) * n + i];
    }
    fc->vol[i] = tr;
  }
  *rate = fc->vol;
  return 0;
}
