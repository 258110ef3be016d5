/* The gas output fields, derived from the state just before a snapshot or checkpoint is
 * written (the module's output op), so that steps between outputs do not pay for them:
 * density, pressure, Mach number |v| / c, temperature p / (rho R) and specific entropy
 * c_v ln(p / rho^gamma), all from the particle's own density m / (V0 J); and rho_grid, the
 * grid's density mapped back to the particles.
 *
 * rho_grid. A particle's own density carries the particle noise of the method (a checkerboard
 * next to a body, ripples behind a shock) cell by cell. The grid sees the gas through the shape
 * functions: its nodal density rho_i = sum_p S_ip m_p / sum_p S_ip J_p V0_p (the volume-weighted
 * mean of the particles around node i: a node half covered by gas, at a wall, an obstacle or
 * a solid, reads the gas's density, not half of it), and each particle gets
 * sum_i S_ip rho_i. Uniform gas gives its density exactly; it smooths over about two cells,
 * so a shock looks a cell wider. Output only: the dynamics never read it. */
#include "fluid_eos.h"
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_shape.h"

#include <stdlib.h>
#include <string.h>

/* The stencil of the particle at x: its first node's local index and the weights along each
 * axis (a dummy third axis of weight 1 in 2-D). */
typedef struct out_stencil {
  int sup, nz;
  mpm_lidx first, sy, sz;
  double w[3][MPM_SHAPE_MAX_SUPPORT];
} out_stencil;

static void out_stencil_at(const mpm_grid *g, double lp, const mpm_particles *p, mpm_lidx i,
                           out_stencil *s) {
  double xi[3] = {0, 0, 0}, dw[3][MPM_SHAPE_MAX_SUPPORT];
  int base[3] = {0, 0, 0};
  for (int d = 0; d < g->dim; ++d)
    xi[d] = (mpm_particles_comp(p, FLUID_X, d)[i] - g->lo[d]) / g->dx;
  s->sup = mpm_shape_support(g->shape), s->nz = g->dim == 3 ? s->sup : 1;
  mpm_shape_eval(g->shape, g->dim, xi, lp, base, s->w, dw);
  if (g->dim == 2) s->w[2][0] = 1.0;
  s->sy = g->box_n[0], s->sz = (mpm_lidx)g->box_n[0] * g->box_n[1];
  s->first = mpm_grid_local_index(g, base);
}

static int grid_density(mpm_module *m, double *rho_grid) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  mpm_grid *g = m->grid;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0), *J = mpm_particles_comp(p, FLUID_J, 0);
  double *mi = NULL, *vi = NULL;
  MPM_ALLOC(mi, g->nnodes);
  vi = calloc((size_t)g->nnodes ? (size_t)g->nnodes : 1, sizeof *vi);
  if (!vi) {
    free(mi);
    MPM_FAIL_OOM(sizeof *vi * (size_t)g->nnodes);
  }
  out_stencil s;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    out_stencil_at(g, fc->lp, p, i, &s);
    for (int c = 0; c < s.nz; ++c)
      for (int b = 0; b < s.sup; ++b) {
        const mpm_lidx row = s.first + b * s.sy + c * s.sz;
        const double wbc = s.w[1][b] * s.w[2][c];
        for (int a = 0; a < s.sup; ++a) {
          mi[row + a] += s.w[0][a] * wbc * mass[i];
          vi[row + a] += s.w[0][a] * wbc * J[i] * V0[i];
        }
      }
  }
  double *fields[2] = {mi, vi};
  int rc = mpm_grid_halo_reverse(g, fields, 2);
  if (rc == 0) rc = mpm_grid_halo_forward(g, fields, 2);
  if (rc != 0) {
    free(mi), free(vi);
    MPM_CALL(rc);
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) mi[l] = vi[l] > 0.0 ? mi[l] / vi[l] : 0.0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    out_stencil_at(g, fc->lp, p, i, &s);
    double r = 0.0;
    for (int c = 0; c < s.nz; ++c)
      for (int b = 0; b < s.sup; ++b) {
        const mpm_lidx row = s.first + b * s.sy + c * s.sz;
        const double wbc = s.w[1][b] * s.w[2][c];
        for (int a = 0; a < s.sup; ++a) r += s.w[0][a] * wbc * mi[row + a];
      }
    rho_grid[i] = r;
  }
  free(mi), free(vi);
  return 0;
}

int fluid_output_fields(mpm_module *m) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const fluid_layout *lay = &fc->lay;
  const double gamma = fc->gas.gamma;
  const double *mass = mpm_particles_comp(p, lay->f_m, 0),
               *V0 = mpm_particles_comp(p, lay->f_V0, 0);
  const double *J = mpm_particles_comp(p, FLUID_J, 0), *e = mpm_particles_comp(p, FLUID_E, 0);
  double *rho = mpm_particles_comp(p, lay->f_rho, 0), *pr = mpm_particles_comp(p, lay->f_p, 0);
  double *mach = mpm_particles_comp(p, lay->f_mach, 0), *T = mpm_particles_comp(p, lay->f_T, 0);
  double *s = mpm_particles_comp(p, lay->f_s, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    rho[i] = mass[i] / (V0[i] * J[i]);
    pr[i] = fluid_pressure(gamma, rho[i], e[i]);
    T[i] = fluid_temperature(fc->R, rho[i], pr[i]);
    s[i] = fluid_entropy(gamma, fc->R, rho[i], pr[i]);
    mach[i] = 0.0;
  }
  for (int d = 0; d < p->dim; ++d) {
    const double *v = mpm_particles_comp(p, FLUID_V, d);
    for (mpm_lidx i = 0; i < p->n; ++i) mach[i] += v[i] * v[i];
  }
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const double c = fluid_sound_speed(gamma, rho[i], pr[i]);
    mach[i] = c > 0.0 ? sqrt(mach[i]) / c : 0.0;
  }
  MPM_CALL(grid_density(m, mpm_particles_comp(p, lay->f_rho_grid, 0)));
  return 0;
}
