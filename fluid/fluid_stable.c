/* The neighbourhood estimate of the gas's fastest signal (fluid.stable_step = neighbourhood).
 *
 * The explicit update is stable when the step resolves the fastest signal the grid's nodes
 * carry. A node's mass, stiffness and momentum are sums over the particles its shape function
 * reaches, so a particle counts in proportion to its mass: a light particle that is hot, fast
 * or strongly compressed among heavier ones cannot set a node's frequency alone, and positions
 * move with the nodal velocity, a mass-weighted mean of the particles' velocities. The default
 * estimate (fluid.stable_step = particle) instead takes the largest c + |v| + 2 nu / dx of any
 * single particle, which in a wake refilled with light particles can be several times what any
 * node carries (measured on the main job: the limiting particles hold 1/16 to 1/1000 of a
 * seeded particle's mass).
 *
 * Here, for every cell c the grid owns, over the 3 x 3 (x 3) cells around it (the reach of the
 * quadratic B-spline):
 *   s_c = sqrt(sum m s_p^2 / sum m) + sum m |v_p| / sum m,
 * with s_p = c_p + 2 nu_p / dx the particle's acoustic and viscous (artificial and physical)
 * speed (fluid.viscous_step = damped: fluid_signal_speed's damped form), and the step is dx over
 * the largest s_c. The sums are taken per cell after migration, when every particle sits on the
 * rank owning its cell, and the forward halo gives each rank its neighbours' cells: the result does
 * not depend on the decomposition (up to the order of the sums). It is computed once per step, at
 * the first estimate after the step began (every rank asks at the same points: the estimate is
 * collective), from the state the step starts from; the adaptive pairs' stage and end-of-step
 * estimates reuse it. */
#include "fluid_internal.h"

#include "fluid_stress.h"
#include "mpm_cells.h"
#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Deposit m, m s^2 and m |v| of every particle into its cell (at the cell's lower corner
 * node, as mpm_cells.h stores cells). */
static void deposit(const mpm_module *m, double *const *sum) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const double dx = g->dx, gamma = fc->gas.gamma;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const double *divv = mpm_particles_comp(p, fc->lay.f_divv, 0);
  const double *psi = fc->lay.f_psi >= 0 ? mpm_particles_comp(p, fc->lay.f_psi, 0) : NULL;
  const double *J = mpm_particles_comp(p, FLUID_J, 0), *e = mpm_particles_comp(p, FLUID_E, 0);
  const double *x[MPM_MAX_DIM], *vel[MPM_MAX_DIM]; /* (read once: sum may alias the block) */
  for (int d = 0; d < g->dim; ++d)
    x[d] = mpm_particles_comp(p, FLUID_X, d), vel[d] = mpm_particles_comp(p, FLUID_V, d);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    int c[MPM_MAX_DIM] = {0};
    double v2 = 0.0;
    for (int d = 0; d < g->dim; ++d) {
      v2 += vel[d][i] * vel[d][i];
      c[d] = mpm_cells_coord(g, d, x[d][i]);
    }
    const double rho = fc->gas.mu > 0.0 ? mass[i] / (V0[i] * J[i]) : 1.0; /* only mu needs it */
    const double cs = sqrt(gamma * (gamma - 1.0) * fabs(e[i]));
    const double s =
        fc->gas.damped_step
            ? fluid_signal_speed(&fc->gas, rho, cs, divv[i], psi ? psi[i] : 0.0, dx)
            : cs + fluid_viscous_speed(&fc->gas, rho, cs, divv[i], psi ? psi[i] : 0.0, dx);
    const mpm_lidx l = mpm_grid_local_index(g, c);
    sum[0][l] += mass[i], sum[1][l] += mass[i] * s * s, sum[2][l] += mass[i] * sqrt(v2);
  }
}

/* out = the sum of in over the three nodes l - 1, l, l + 1 along axis d of the box (0 on the
 * box's first and last layer along d, which have no neighbour there). */
static void box_sum_axis(const mpm_grid *g, int d, const double *in, double *out) {
  mpm_lidx stride = 1;
  for (int k = 0; k < d; ++k) stride *= g->box_n[k];
  const int n = g->box_n[d];
  const mpm_lidx outer = g->nnodes / (stride * n);
  for (mpm_lidx o = 0; o < outer; ++o) {
    double *r = out + o * stride * n;
    const double *a = in + o * stride * n;
    for (mpm_lidx j = 0; j < stride; ++j) r[j] = r[(n - 1) * stride + j] = 0.0;
    for (int i = 1; i < n - 1; ++i)
      for (mpm_lidx j = 0; j < stride; ++j) {
        const mpm_lidx l = i * stride + j;
        r[l] = a[l - stride] + a[l] + a[l + stride];
      }
  }
}

int fluid_neighbourhood_signal(const mpm_module *m, double *smax) {
  fluid_content *fc = m->content;
  mpm_grid *g = m->grid;
  const size_t nn = (size_t)g->nnodes;
  double *sum[3] = {fc->cellsum, fc->cellsum + nn, fc->cellsum + 2 * nn};
  double *tmp[3] = {fc->cellsum + 3 * nn, fc->cellsum + 4 * nn, fc->cellsum + 5 * nn};
  memset(fc->cellsum, 0, sizeof *fc->cellsum * 3 * nn);
  deposit(m, sum);
  MPM_CALL(mpm_grid_halo_forward(g, sum, 3));
  /* The 3^dim block sums, one axis at a time (the halo holds the cells around the box). */
  for (int d = 0; d < g->dim; ++d)
    for (int j = 0; j < 3; ++j) {
      box_sum_axis(g, d, sum[j], tmp[j]);
      double *t = sum[j];
      sum[j] = tmp[j], tmp[j] = t;
    }
  int lo[MPM_MAX_DIM] = {0}, n[MPM_MAX_DIM] = {1, 1, 1};
  mpm_lidx total = 1;
  for (int d = 0; d < g->dim; ++d) {
    lo[d] = g->cell_split[d][g->coord[d]];
    n[d] = g->cell_split[d][g->coord[d] + 1] - lo[d];
    total *= n[d];
  }
  double best = 0.0;
  for (mpm_lidx k = 0; k < total; ++k) {
    int c[MPM_MAX_DIM] = {0};
    mpm_lidx r = k;
    for (int d = 0; d < g->dim; ++d) c[d] = lo[d] + (int)(r % n[d]), r /= n[d];
    const mpm_lidx l = mpm_grid_local_index(g, c);
    if (!(sum[0][l] > 0.0)) continue;
    const double s = sqrt(sum[1][l] / sum[0][l]) + sum[2][l] / sum[0][l];
    if (s > best) best = s; /* fmax's result, NaN included, without its call */
  }
  *smax = best;
  return 0;
}
