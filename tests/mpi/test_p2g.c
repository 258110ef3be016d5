/* P2G over 1..N ranks against a serial P2G of the same particles.
 *
 * Every rank generates the same particle set (seeded), keeps the particles whose cell it
 * owns, runs P2G and the reverse halo exchange, and compares its owned nodes with a P2G of
 * all particles on a one-rank grid (MPI_COMM_SELF). Tolerance: 1e-13 relative to the
 * largest value of each field: the sums differ only in the order of additions. Also checks
 * that total nodal mass and momentum equal the particle totals (partition of unity) and
 * that the forward exchange gives every ghost its owner's value. */
#include "mpm_grid.h"
#include "mpm_kernels.h"
#include "mpm_module.h"

#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NP 4000

static double rnd(unsigned long long *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(*s >> 11) / 9007199254740992.0;
}

typedef struct {
  int dim;
  double x[3][NP], v[3][NP], m[NP], vsig[9 * NP];
} pset;

static void make_particles(pset *p, int dim, const double *lo, const double *hi) {
  unsigned long long s = 12345 + (unsigned long long)dim;
  p->dim = dim;
  for (int i = 0; i < NP; ++i) {
    for (int d = 0; d < dim; ++d) {
      p->x[d][i] = lo[d] + (hi[d] - lo[d]) * rnd(&s);
      p->v[d][i] = 2 * rnd(&s) - 1;
    }
    p->m[i] = 0.5 + rnd(&s);
    for (int c = 0; c < dim * dim; ++c) p->vsig[c * NP + i] = rnd(&s) - 0.5;
  }
}

/* P2G of the particles in `keep` into phase 0 of g, then the reverse halo. */
static void p2g(mpm_grid *g, const pset *all, const int *keep, int nkeep) {
  static double x[3][NP], v[3][NP], m[NP], vsig[9 * NP];
  const int dim = all->dim;
  for (int k = 0; k < nkeep; ++k) {
    const int i = keep[k];
    for (int d = 0; d < dim; ++d) x[d][k] = all->x[d][i], v[d][k] = all->v[d][i];
    m[k] = all->m[i];
    for (int c = 0; c < dim * dim; ++c) vsig[c * nkeep + k] = all->vsig[c * NP + i];
  }
  mpm_p2g_args a = {.n = nkeep, .m = m, .vsig = vsig, .lp = 0.25};
  for (int d = 0; d < dim; ++d) a.x[d] = x[d], a.v[d] = v[d], a.gravity[d] = 0.5 * (d + 1);
  mpm_grid_phase_zero(g, 0);
  mpm_kernels_get(dim)->p2g(g, 0, &a);
  mpm_grid_phase *ph = &g->phase[0];
  double *f[1 + 2 * 3];
  int nf = 0;
  f[nf++] = ph->m_i;
  for (int d = 0; d < dim; ++d) f[nf++] = ph->mv_i[d], f[nf++] = ph->f_i[d];
  if (mpm_grid_halo_reverse(g, f, nf) != 0) CHECK(0, "halo_reverse failed");
}

/* Global node index of box node l. */
static void global_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  for (int d = 0; d < g->dim; ++d) {
    gi[d] = g->box_lo[d] + (int)(l % g->box_n[d]);
    l /= g->box_n[d];
  }
}

static void compare(const mpm_grid *g, const mpm_grid *ref, double *maxrel) {
  const mpm_grid_phase *a = &g->phase[0], *b = &ref->phase[0];
  const int dim = g->dim;
  double scale[7] = {0}, err[7] = {0};
  const int nf = 1 + 2 * dim;
  for (mpm_lidx l = 0; l < ref->nnodes; ++l) {
    scale[0] = fmax(scale[0], fabs(b->m_i[l]));
    for (int d = 0; d < dim; ++d) {
      scale[1 + d] = fmax(scale[1 + d], fabs(b->mv_i[d][l]));
      scale[1 + dim + d] = fmax(scale[1 + dim + d], fabs(b->f_i[d][l]));
    }
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!mpm_grid_node_is_owned(g, l)) continue;
    int gi[3];
    global_of(g, l, gi);
    const mpm_lidx r = mpm_grid_local_index(ref, gi);
    err[0] = fmax(err[0], fabs(a->m_i[l] - b->m_i[r]));
    for (int d = 0; d < dim; ++d) {
      err[1 + d] = fmax(err[1 + d], fabs(a->mv_i[d][l] - b->mv_i[d][r]));
      err[1 + dim + d] = fmax(err[1 + dim + d], fabs(a->f_i[d][l] - b->f_i[d][r]));
    }
  }
  *maxrel = 0;
  for (int k = 0; k < nf; ++k) *maxrel = fmax(*maxrel, err[k] / scale[k]);
}

static void totals(const mpm_grid *g, int owned_only, double *t) {
  const mpm_grid_phase *ph = &g->phase[0];
  memset(t, 0, 4 * sizeof *t);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (owned_only && !mpm_grid_node_is_owned(g, l)) continue;
    t[0] += ph->m_i[l];
    for (int d = 0; d < g->dim; ++d) t[1 + d] += ph->mv_i[d][l];
  }
}

static void run_case(int dim, mpm_shape_kind shape) {
  const double lo[3] = {-1.0, 0.0, 0.5}, hi[3] = {2.0, 2.4, 2.3}, dx = 0.1;
  static pset all;
  static int keep[NP], every[NP];
  make_particles(&all, dim, lo, hi);
  mpm_grid *g = NULL, *ref = NULL;
  const int nproc[3] = {0, 0, 0};
  int ip;
  if (mpm_grid_new(&g, MPI_COMM_WORLD, dim, lo, hi, dx, shape, nproc) != 0 ||
      mpm_grid_new(&ref, MPI_COMM_SELF, dim, lo, hi, dx, shape, nproc) != 0 ||
      mpm_grid_add_phase(g, "p", &ip) != 0 || mpm_grid_add_phase(ref, "p", &ip) != 0) {
    CHECK(0, "grid creation failed");
    return;
  }
  int nkeep = 0;
  for (int i = 0; i < NP; ++i) {
    every[i] = i;
    double x[3] = {all.x[0][i], all.x[1][i], dim == 3 ? all.x[2][i] : 0};
    if (mpm_grid_owner_of(g, x) == g->rank) keep[nkeep++] = i;
  }
  p2g(g, &all, keep, nkeep);
  p2g(ref, &all, every, NP);

  double maxrel, gmax;
  compare(g, ref, &maxrel);
  MPI_Allreduce(&maxrel, &gmax, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  CHECK(gmax <= 1e-13, "%d-D %s: nodal fields differ from serial by %.3e relative", dim,
        mpm_shape_name(shape), gmax);

  /* Conservation: owned-node totals against particle totals. */
  double t[4], tg[4], pt[4] = {0};
  totals(g, 1, t);
  MPI_Allreduce(t, tg, 4, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  for (int i = 0; i < NP; ++i) {
    pt[0] += all.m[i];
    for (int d = 0; d < dim; ++d) pt[1 + d] += all.m[i] * all.v[d][i];
  }
  double cons = fabs(tg[0] - pt[0]) / pt[0];
  for (int d = 0; d < dim; ++d) cons = fmax(cons, fabs(tg[1 + d] - pt[1 + d]) / pt[0]);
  CHECK(cons <= 1e-13, "%d-D %s: mass/momentum not conserved: %.3e", dim, mpm_shape_name(shape),
        cons);

  /* Forward exchange: after it, every stored node equals the serial value. */
  mpm_grid_phase *ph = &g->phase[0];
  double *f[4] = {ph->m_i, ph->mv_i[0], ph->mv_i[1], dim == 3 ? ph->mv_i[2] : NULL};
  mpm_grid_halo_forward(g, f, dim + 1);
  double ferr = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3], inside = 1;
    global_of(g, l, gi);
    for (int d = 0; d < dim; ++d) inside &= gi[d] >= -g->pad && gi[d] <= g->ncells[d] + g->pad;
    if (inside)
      ferr = fmax(ferr, fabs(ph->m_i[l] - ref->phase[0].m_i[mpm_grid_local_index(ref, gi)]));
  }
  CHECK(ferr <= 1e-13 * pt[0], "%d-D %s: ghost masses after the forward exchange differ by %.3e",
        dim, mpm_shape_name(shape), ferr);
  /* The nodal solve: v = mv/m + h f/m, a = f/m on nodes above the phase's empty fraction of
   * the largest nodal mass (and, in the third pass, above its light fraction of the mean
   * nodal mass), zero on the others (1e-14 by default; the gas may raise both). The mean is
   * the serial grid's, over the nodes with mass, on any number of ranks. */
  double rsum = 0.0, rcount = 0.0, rmax = 0.0;
  for (mpm_lidx l = 0; l < ref->nnodes; ++l) rmax = fmax(rmax, ref->phase[0].m_i[l]);
  for (mpm_lidx l = 0; l < ref->nnodes; ++l)
    if (ref->phase[0].m_i[l] > 1e-14 * rmax) rsum += ref->phase[0].m_i[l], rcount += 1.0;
  const double h = 1e-3;
  for (int pass = 0; pass < 3; ++pass) {
    ph->empty_fraction = pass == 1 ? 0.05 : 1e-14;
    ph->light_fraction = pass == 2 ? 0.3 : 0.0;
    CHECK(mpm_grid_phase_update(g, 0, h) == 0, "nodal solve failed");
    if (pass == 2)
      CHECK(fabs(ph->m_mean - rsum / rcount) <= 1e-13 * ph->m_mean,
            "%d-D %s: mean nodal mass %.15g, serial %.15g", dim, mpm_shape_name(shape), ph->m_mean,
            rsum / rcount);
    const double mmin = fmax(ph->empty_fraction * ph->m_max, ph->light_fraction * ph->m_mean);
    long nempty = 0, nbad = 0;
    for (mpm_lidx l = 0; l < g->nnodes; ++l)
      for (int d = 0; d < dim; ++d) {
        const double m = ph->m_i[l], v = ph->v_i[d][l], a = ph->a_i[d][l];
        if (m <= mmin) {
          nempty += m > 0 && d == 0;
          nbad += v != 0 || a != 0;
        } else {
          const double ae = ph->f_i[d][l] / m, ve = ph->mv_i[d][l] / m + h * ae;
          nbad += fabs(a - ae) > 1e-14 * fabs(ae) || fabs(v - ve) > 1e-14 * fabs(ve);
        }
      }
    long sums[2] = {nempty, nbad};
    MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    CHECK(sums[1] == 0 && (pass == 0 || sums[0] > 0),
          "%d-D %s: nodal solve with empty fraction %g, light fraction %g: %ld wrong nodes, "
          "%ld nodes with mass treated as empty",
          dim, mpm_shape_name(shape), ph->empty_fraction, ph->light_fraction, sums[1], sums[0]);
  }
  if (g->rank == 0)
    printf("%d-D %-9s ranks %d: max relative nodal difference %.2e, conservation %.2e\n", dim,
           mpm_shape_name(shape), g->size, gmax, cons);
  mpm_grid_destroy(&g);
  mpm_grid_destroy(&ref);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) run_case(dim, (mpm_shape_kind)s);
  const int total = mpm_test_finish("test_p2g");
  MPI_Finalize();
  return total ? 1 : 0;
}
