/* The optional APIC and external-force paths of the P2G and G2P kernels (mpm_kernels.h),
 * for every shape in 2-D and 3-D, on a one-rank grid.
 *
 *  (i)   P2G of particles carrying an affine velocity field v = v0 + A x with C_p = A gives
 *        nodal velocities mv_i / m_i = v0 + A x_i: each particle's contribution to node i is
 *        S m (v0 + A x_p + A (x_i - x_p)) = S m (v0 + A x_i). Checked at every node whose
 *        stencil lies inside the seeded block (full support), and the total momentum
 *        sum_i mv_i = sum_p m_p v_p (sum_i S (x_i - x_p) = 0). P2G with C = 0 deposits the
 *        same momenta as P2G without C, bit for bit.
 *  (ii)  G2P of an affine nodal velocity v_i = v0 + A x_i returns v_p = v0 + A x_p and
 *        C_p = A (for B-splines through the moment sum_i S (x_i - x_p)(x_i - x_p)^T = D I,
 *        for linear and GIMP through sum_i x_i (x) grad S = I), with L_out = A as well, and
 *        the fused product LF_out = L F = A F for a particle tensor F.
 *  (iii) P2G with only fext deposits a total nodal force sum_i f_i = sum_p fext_p
 *        (partition of unity); with gravity too, sum_p (m_p g + fext_p).
 *
 * Tolerance: 1e-12 relative to the scale of each quantity (|v0| + |A| |x|max for velocities,
 * |A| for C, sum |fext| for forces). Every identity above is exact in real arithmetic, so
 * only rounding in sums of a few hundred terms of size O(scale) remains (about 1e-15
 * relative); 1e-12 leaves a wide margin for that and still catches any wrong term, which
 * is O(dx) = O(0.1) relative. */
#include "mpm_random.h"
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>
#include <mpi.h>

#include "mpm_grid.h"
#include "mpm_kernels.h"

#define TOL 1e-12
#define NP  3000

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.2, 2.0, 2.6}, g_dx = 0.1;
/* Particles fill this block; nodes at least one support width inside it have full
 * support. */
static const double g_blo[3] = {-0.6, 0.4, 0.9}, g_bhi[3] = {0.8, 1.6, 2.2};
static const double g_v0[3] = {0.7, -1.3, 0.4};
static const double g_A[3][3] = {{0.3, -1.1, 0.6}, {0.9, 0.2, -0.4}, {-0.5, 0.8, 1.2}};

typedef struct {
  int dim;
  mpm_lidx n;
  double *x[3], *v[3], *m, *C, *fext[3];
} pset;

static double uniform(uint64_t *state) {
  return mpm_test_uniform(state);
}

static void affine(int dim, const double *x, double *v) {
  for (int r = 0; r < dim; ++r) {
    v[r] = g_v0[r];
    for (int c = 0; c < dim; ++c) v[r] += g_A[r][c] * x[c];
  }
}

/* Velocity scale |v0| + |A| max |x| over the domain. */
static double velocity_scale(int dim) {
  double v = 0, a = 0, x = 0;
  for (int r = 0; r < dim; ++r) {
    v = fmax(v, fabs(g_v0[r]));
    x = fmax(x, fmax(fabs(g_lo[r]), fabs(g_hi[r])));
    for (int c = 0; c < dim; ++c) a = fmax(a, fabs(g_A[r][c]));
  }
  return v + dim * a * x;
}

static void pset_make(pset *p, int dim, uint64_t seed) {
  memset(p, 0, sizeof *p);
  p->dim = dim;
  p->n = NP;
  for (int d = 0; d < dim; ++d) {
    p->x[d] = malloc(sizeof(double) * NP);
    p->v[d] = malloc(sizeof(double) * NP);
    p->fext[d] = malloc(sizeof(double) * NP);
  }
  p->m = malloc(sizeof(double) * NP);
  p->C = malloc(sizeof(double) * (size_t)(dim * dim) * NP);
  for (mpm_lidx i = 0; i < NP; ++i) {
    double x[3], v[3];
    for (int d = 0; d < dim; ++d)
      x[d] = p->x[d][i] = g_blo[d] + (g_bhi[d] - g_blo[d]) * uniform(&seed);
    affine(dim, x, v);
    for (int d = 0; d < dim; ++d) {
      p->v[d][i] = v[d];
      p->fext[d][i] = 2.0 * uniform(&seed) - 1.0;
    }
    p->m[i] = 0.5 + uniform(&seed);
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) p->C[(size_t)(r * dim + c) * NP + i] = g_A[r][c];
  }
}

static void pset_free(pset *p) {
  for (int d = 0; d < p->dim; ++d) free(p->x[d]), free(p->v[d]), free(p->fext[d]);
  free(p->m);
  free(p->C);
}

static mpm_grid *grid_make(int dim, mpm_shape_kind shape) {
  mpm_grid *g = NULL;
  const int nproc[3] = {1, 1, 1};
  int phase;
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_SELF, dim, g_lo, g_hi, g_dx, shape, nproc), 0);
  assert_int_equal(mpm_grid_add_phase(g, "p", &phase), 0);
  return g;
}

/* Position of box node l, and whether its support lies inside the seeded block. */
static int node_position(const mpm_grid *g, mpm_lidx l, double *x) {
  int inside = 1;
  for (int d = 0; d < g->dim; ++d) {
    const int gi = g->box_lo[d] + (int)(l % g->box_n[d]);
    l /= g->box_n[d];
    x[d] = g->lo[d] + gi * g->dx;
    inside &= x[d] - 2 * g->dx >= g_blo[d] && x[d] + 2 * g->dx <= g_bhi[d];
  }
  return inside;
}

static void p2g(mpm_grid *g, const pset *p, const double *C, int fext, double gravity) {
  mpm_p2g_args a = {.n = p->n, .m = p->m, .C = C, .lp = 0.25};
  for (int d = 0; d < p->dim; ++d) {
    a.x[d] = p->x[d], a.v[d] = p->v[d], a.gravity[d] = gravity * (d + 1);
    a.fext[d] = fext ? p->fext[d] : NULL;
  }
  mpm_grid_phase_zero(g, 0);
  mpm_kernels_get(p->dim)->p2g(g, 0, &a);
}

/* (i) */
static void check_p2g_affine(int dim, mpm_shape_kind shape) {
  mpm_grid *g = grid_make(dim, shape);
  pset p;
  pset_make(&p, dim, 17u + (uint64_t)(10 * dim + shape));
  p2g(g, &p, p.C, 0, 0.0);
  const mpm_grid_phase *ph = &g->phase[0];
  const double V = velocity_scale(dim);
  double err = 0, mom[3] = {0}, pmom[3] = {0}, mass = 0;
  int checked = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    double x[3], v[3];
    for (int d = 0; d < dim; ++d) mom[d] += ph->mv_i[d][l];
    if (!node_position(g, l, x)) continue;
    assert_true(ph->m_i[l] > 0);
    affine(dim, x, v);
    for (int d = 0; d < dim; ++d) err = fmax(err, fabs(ph->mv_i[d][l] / ph->m_i[l] - v[d]) / V);
    checked++;
  }
  for (mpm_lidx i = 0; i < p.n; ++i) {
    mass += p.m[i];
    for (int d = 0; d < dim; ++d) pmom[d] += p.m[i] * p.v[d][i];
  }
  double merr = 0;
  for (int d = 0; d < dim; ++d) merr = fmax(merr, fabs(mom[d] - pmom[d]) / (mass * V));
  printf("  %d-D %-9s P2G, C = A: %5d full-support nodes, max |v_i - (v0 + A x_i)| / V = %.2e; "
         "momentum %.2e\n",
         dim, mpm_shape_name(shape), checked, err, merr);
  assert_true(checked > 50);
  assert_true(err <= TOL);
  assert_true(merr <= TOL);

  /* C = 0 deposits exactly what no C deposits. */
  double *mv0[3];
  for (int d = 0; d < dim; ++d) mv0[d] = malloc(sizeof(double) * (size_t)g->nnodes);
  double *zero = calloc((size_t)(dim * dim) * NP, sizeof(double));
  p2g(g, &p, NULL, 0, 0.0);
  for (int d = 0; d < dim; ++d) memcpy(mv0[d], ph->mv_i[d], sizeof(double) * (size_t)g->nnodes);
  p2g(g, &p, zero, 0, 0.0);
  for (int d = 0; d < dim; ++d)
    assert_memory_equal(mv0[d], ph->mv_i[d], sizeof(double) * (size_t)g->nnodes);
  free(zero);
  for (int d = 0; d < dim; ++d) free(mv0[d]);
  pset_free(&p);
  mpm_grid_destroy(&g);
}

/* (ii) */
static void check_g2p_affine(int dim, mpm_shape_kind shape) {
  mpm_grid *g = grid_make(dim, shape);
  mpm_grid_phase *ph = &g->phase[0];
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    double x[3], v[3];
    node_position(g, l, x);
    affine(dim, x, v);
    for (int d = 0; d < dim; ++d) ph->v_i[d][l] = v[d], ph->a_i[d][l] = -v[d];
  }
  pset p;
  pset_make(&p, dim, 91u + (uint64_t)(10 * dim + shape));
  const size_t nt = (size_t)(dim * dim) * NP;
  double *vout[3], *aout[3], *C = malloc(sizeof(double) * nt), *L = malloc(sizeof(double) * nt),
                             *F = malloc(sizeof(double) * nt), *LF = malloc(sizeof(double) * nt);
  uint64_t seed = 7u;
  for (size_t k = 0; k < nt; ++k) F[k] = 2.0 * uniform(&seed) - 1.0;
  mpm_g2p_args a = {.n = p.n, .lp = 0.25, .L_out = L, .C_out = C, .F = F, .LF_out = LF};
  for (int d = 0; d < dim; ++d) {
    vout[d] = malloc(sizeof(double) * NP), aout[d] = malloc(sizeof(double) * NP);
    a.x[d] = p.x[d], a.v_i[d] = ph->v_i[d], a.a_i[d] = ph->a_i[d];
    a.v_out[d] = vout[d], a.a_out[d] = aout[d];
  }
  mpm_kernels_get(dim)->g2p(g, &a);
  const double V = velocity_scale(dim);
  double ev = 0, eC = 0, eL = 0, eF = 0, amax = 0;
  for (int r = 0; r < dim; ++r)
    for (int c = 0; c < dim; ++c) amax = fmax(amax, fabs(g_A[r][c]));
  for (mpm_lidx i = 0; i < p.n; ++i) {
    for (int d = 0; d < dim; ++d) {
      ev = fmax(ev, fabs(vout[d][i] - p.v[d][i]) / V);
      ev = fmax(ev, fabs(aout[d][i] + p.v[d][i]) / V);
    }
    for (int r = 0; r < dim; ++r)
      for (int c = 0; c < dim; ++c) {
        eC = fmax(eC, fabs(C[(size_t)(r * dim + c) * NP + i] - g_A[r][c]) / amax);
        eL = fmax(eL, fabs(L[(size_t)(r * dim + c) * NP + i] - g_A[r][c]) / amax);
        double af = 0; /* (A F)_rc; |F| <= 1, so amax * dim bounds it */
        for (int k = 0; k < dim; ++k) af += g_A[r][k] * F[(size_t)(k * dim + c) * NP + i];
        eF = fmax(eF, fabs(LF[(size_t)(r * dim + c) * NP + i] - af) / (amax * dim));
      }
  }
  printf("  %d-D %-9s G2P of v0 + A x: max |v_p - (v0 + A x_p)| / V = %.2e, |C_p - A| / |A| = "
         "%.2e, |L_p - A| / |A| = %.2e, |L F - A F| / (|A| dim) = %.2e\n",
         dim, mpm_shape_name(shape), ev, eC, eL, eF);
  assert_true(ev <= TOL);
  assert_true(eC <= TOL);
  assert_true(eL <= TOL);
  assert_true(eF <= TOL);
  for (int d = 0; d < dim; ++d) free(vout[d]), free(aout[d]);
  free(C), free(L), free(F), free(LF);
  pset_free(&p);
  mpm_grid_destroy(&g);
}

/* (iii) */
static void check_fext(int dim, mpm_shape_kind shape) {
  mpm_grid *g = grid_make(dim, shape);
  pset p;
  pset_make(&p, dim, 5u + (uint64_t)(10 * dim + shape));
  const mpm_grid_phase *ph = &g->phase[0];
  for (int with_gravity = 0; with_gravity <= 1; ++with_gravity) {
    const double gr = with_gravity ? 9.81 : 0.0;
    p2g(g, &p, NULL, 1, gr);
    double total[3] = {0}, expect[3] = {0}, scale = 0, err = 0;
    for (mpm_lidx l = 0; l < g->nnodes; ++l)
      for (int d = 0; d < dim; ++d) total[d] += ph->f_i[d][l];
    for (mpm_lidx i = 0; i < p.n; ++i)
      for (int d = 0; d < dim; ++d) {
        const double f = p.fext[d][i] + p.m[i] * gr * (d + 1);
        expect[d] += f;
        scale += fabs(f);
      }
    for (int d = 0; d < dim; ++d) err = fmax(err, fabs(total[d] - expect[d]) / scale);
    printf("  %d-D %-9s P2G fext%s: |sum f_i - sum f_p| / sum |f_p| = %.2e\n", dim,
           mpm_shape_name(shape), with_gravity ? " + m g" : "", err);
    assert_true(err <= TOL);
  }
  pset_free(&p);
  mpm_grid_destroy(&g);
}

static void test_p2g_affine(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) check_p2g_affine(dim, (mpm_shape_kind)s);
}

static void test_g2p_affine(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) check_g2p_affine(dim, (mpm_shape_kind)s);
}

static void test_fext(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) check_fext(dim, (mpm_shape_kind)s);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_p2g_affine),
      cmocka_unit_test(test_g2p_affine),
      cmocka_unit_test(test_fext),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
