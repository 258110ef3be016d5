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
 * estimates reuse it.
 *
 * On a hierarchy (mpm_hier.h) each particle counts in the cells of its position's level, and the
 * neighbourhoods are taken on each level: level 0's cells as above, a finer level's spans (its
 * cells, mpm_cells.h) over its box, summed over the ranks, so every rank holds them whole. As the
 * particle estimate does there, a particle's speed takes its level's spacing and viscous lengths,
 * and the one step of every level is the smallest of h_l / s_c over the levels' cells. */
#include "fluid_internal.h"

#include "fluid_stress.h"
#include "mpm_cells.h"
#include "mpm_error.h"
#include "mpm_hier.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Deposit m, m s^2 and m |v| of every particle into its cell (at the cell's lower corner
 * node, as mpm_cells.h stores cells); on a hierarchy (lev: the particles' levels), a particle on
 * level l >= 1 into fine[l]'s three fields at its span (mpm_cells_level_index). */
static void deposit(const mpm_module *m, double *const *sum, const unsigned char *lev,
                    double *const *fine) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const double gamma = fc->gas.gamma;
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
    /* The spacing and viscous lengths of the particle's level (fluid_module.c's particle
     * estimate on a hierarchy). */
    const double dx = lev ? m->hier->level[lev[i]].grid->dx : g->dx;
    fluid_gas at_level;
    const fluid_gas *gas = &fc->gas;
    if (lev) at_level = fluid_gas_at(&fc->gas, &dx, 0), gas = &at_level;
    const double s = gas->damped_step
                         ? fluid_signal_speed(gas, rho, cs, divv[i], psi ? psi[i] : 0.0, dx)
                         : cs + fluid_viscous_speed(gas, rho, cs, divv[i], psi ? psi[i] : 0.0, dx);
    double *to[3] = {sum[0], sum[1], sum[2]};
    mpm_lidx l;
    if (lev && lev[i] > 0) { /* its span on level lev[i] */
      const int L = lev[i];
      const double xi[MPM_MAX_DIM] = {x[0][i], g->dim > 1 ? x[1][i] : 0.0,
                                      g->dim > 2 ? x[2][i] : 0.0};
      if ((l = mpm_cells_level_index_at(m->hier, L, xi)) < 0) continue; /* (cannot happen) */
      const size_t nl = (size_t)m->hier->level[L].grid->nnodes;
      to[0] = fine[L], to[1] = fine[L] + nl, to[2] = fine[L] + 2 * nl;
    } else {
      l = mpm_grid_local_index(g, c);
    }
    to[0][l] += mass[i], to[1][l] += mass[i] * s * s, to[2][l] += mass[i] * sqrt(v2);
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

/* The 3^dim block sums of the three fields sum[] over g's box, one axis at a time, into sum[]
 * (tmp: room for three more; the pointers are swapped as the passes go). */
static void block_sums(const mpm_grid *g, double **sum, double **tmp) {
  for (int d = 0; d < g->dim; ++d)
    for (int j = 0; j < 3; ++j) {
      box_sum_axis(g, d, sum[j], tmp[j]);
      double *t = sum[j];
      sum[j] = tmp[j], tmp[j] = t;
    }
}

/* s_c of cell (box index) k from its block sums, times scale; 0 for a cell without gas. */
static double cell_signal(double *const *sum, size_t k, double scale) {
  if (!(sum[0][k] > 0.0)) return 0.0;
  return (sqrt(sum[1][k] / sum[0][k]) + sum[2][k] / sum[0][k]) * scale;
}

/* The largest s_c over a finer level's box, times h_finest / h_l (so that the finest spacing
 * over it is the level's step): its sums (three fields in buf, room for six), summed over the
 * ranks, then block-summed like level 0's. */
static int level_signal(const mpm_module *m, int l, double *buf, double *smax) {
  const mpm_grid *g = m->hier->level[l].grid;
  const size_t nn = (size_t)g->nnodes;
  const double scale = fluid_finest_dx(m) / g->dx;
  if (3 * nn > INT_MAX) MPM_FAIL(MPM_ERR_INTERNAL, "the neighbourhood step: level %d too large", l);
  if (m->hier->nranks > 1)
    MPM_CALL_MPI(
        MPI_Allreduce(MPI_IN_PLACE, buf, (int)(3 * nn), MPI_DOUBLE, MPI_SUM, m->grid->comm));
  double *sum[3] = {buf, buf + nn, buf + 2 * nn},
         *tmp[3] = {buf + 3 * nn, buf + 4 * nn, buf + 5 * nn};
  block_sums(g, sum, tmp);
  for (size_t k = 0; k < nn; ++k) {
    const double s = cell_signal(sum, k, scale);
    if (s > *smax) *smax = s;
  }
  return 0;
}

int fluid_neighbourhood_signal(const mpm_module *m, double *smax) {
  fluid_content *fc = m->content;
  mpm_grid *g = m->grid;
  const size_t nn = (size_t)g->nnodes;
  double *sum[3] = {fc->cellsum, fc->cellsum + nn, fc->cellsum + 2 * nn};
  double *tmp[3] = {fc->cellsum + 3 * nn, fc->cellsum + 4 * nn, fc->cellsum + 5 * nn};
  memset(fc->cellsum, 0, sizeof *fc->cellsum * 3 * nn);
  double *fine[MPM_HIER_MAX_LEVELS] = {NULL};
  const unsigned char *lev = NULL;
  const int nlevels = m->hier ? m->hier->nlevels : 1;
  int rc = 0;
  if (nlevels > 1) {
    lev = fluid_position_levels(m, m->particles->data);
    rc = lev ? 0 : MPM_ERR_MEMORY;
  }
  for (int l = 1; !rc && l < nlevels; ++l) {
    const size_t nl = (size_t)m->hier->level[l].grid->nnodes;
    fine[l] = calloc(6 * nl, sizeof *fine[l]);
    if (!fine[l]) rc = MPM_ERR_MEMORY;
  }
  if (!rc) deposit(m, sum, lev, fine);
  double best = 0.0;
  for (int l = 1; !rc && l < nlevels; ++l) rc = level_signal(m, l, fine[l], &best);
  for (int l = 1; l < nlevels; ++l) free(fine[l]);
  if (rc) MPM_FAIL(rc, "the neighbourhood step: cannot sum the finer levels' cells");
  MPM_CALL(mpm_grid_halo_forward(g, sum, 3));
  block_sums(g, sum, tmp); /* (the halo holds the cells around the box) */
  int lo[MPM_MAX_DIM] = {0}, n[MPM_MAX_DIM] = {1, 1, 1};
  mpm_lidx total = 1;
  for (int d = 0; d < g->dim; ++d) {
    lo[d] = g->cell_split[d][g->coord[d]];
    n[d] = g->cell_split[d][g->coord[d] + 1] - lo[d];
    total *= n[d];
  }
  const double scale0 = fluid_finest_dx(m) / g->dx; /* 1 without a hierarchy */
  for (mpm_lidx k = 0; k < total; ++k) {
    int c[MPM_MAX_DIM] = {0};
    mpm_lidx r = k;
    for (int d = 0; d < g->dim; ++d) c[d] = lo[d] + (int)(r % n[d]), r /= n[d];
    const double s = cell_signal(sum, (size_t)mpm_grid_local_index(g, c), scale0);
    if (s > best) best = s; /* fmax's result, NaN included, without its call */
  }
  *smax = best;
  return 0;
}
