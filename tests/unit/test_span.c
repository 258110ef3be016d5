/* The exact span integrals of quadratic B-spline fields (common/mpm_span.h), on box grids in 2-D
 * and 3-D (spacing 0.1, spans 0 .. 9 per axis, 0 .. 7 along the others in 2-D).
 *
 *  (1) Adjointness: sum_i f_i . v_i = sum_j p_j D_j for random p and v, to 1e-13 of the sum of
 *      |terms| (the same products in another order).
 *  (2) A constant pressure gives no force at any node whose support lies inside the span set
 *      (to 1e-15 of p h^(dim-1)); a linear p = a + b x gives f_x = -b h^dim there (the integral of
 *      -N_i dp/dx, and a quadratic B-spline integrates to h^dim), to 1e-13 relative. A
 *      one-point rule at a lattice that is not symmetric about the node misses both.
 *  (3) A constant velocity gives D = 0 at every node; v = (c x, 0, ...) gives D_i = c h^dim at
 *      the interior nodes, to 1e-13 relative.
 *  (4) Half spans: with the spans at x = 0 and x = 10 h halved (a wall through their nodes),
 *      sum_i D_i is the integral of div v over the clipped box, c (10 h) (8 h)[(8 h)], to 1e-13
 *      relative; the full spans give c (11 h) ... instead.
 *  (5) Half spans on every axis (spans 0 .. 10 along x, 0 .. 7 along the others, all ends
 *      halved) and two interior spans skipped, each axis d in turn: v = c x_d e_d gives sum_i D_i
 *      = c |V| (V the spans integrated), and a constant p = a gives sum_i f_d,i x_d,i = a |V|
 *      (the B-splines reproduce x_d, so that sum is the integral of p d x_d/dx_d), to 1e-13
 *      relative; and sum f.v = sum p D for random fields, as in (1). A wrong half, or a skipped
 *      span still integrated, along any axis misses these by a span's share of |V|.
 *  (6) Node planes (mpm_span_plane, an open face's boundary term): on the set of (5) without
 *      the skipped spans, for each axis d, the span force of a constant p less the planes
 *      through the end nodes along d (the face integrals of p N_i n_d) is 0 at every node, to
 *      1e-14 of p h^(dim-1) (the divergence theorem: what an open face at p cancels); and a
 *      plane integrates q = c x_t (t another axis, which the B-splines reproduce) to c times
 *      the face's first moment, to 1e-13 relative. A wrong normal matrix or tangential half
 *      leaves a node's force off by a share of p h^(dim-1). */
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

#include "mpm_span.h"

#define H 0.1

typedef struct fixture {
  mpm_grid *g;
  mpm_span_set set;
  double *p, *D, *f[3], *v[3];
} fixture;

/* Box nodes -1 .. 11 along x (spans 0 .. 9, or 0 .. 10) and -1 .. 8 along the others (spans
 * 0 .. 7). */
static void make(fixture *x, int dim) {
  const double origin[3] = {0, 0, 0};
  const int lo[3] = {-1, -1, -1}, n[3] = {13, 10, 10};
  assert_int_equal(mpm_grid_box_new(&x->g, dim, origin, H, MPM_SHAPE_QUADRATIC, lo, n), 0);
  const size_t nn = (size_t)x->g->nnodes;
  x->p = calloc(nn, sizeof(double)), x->D = calloc(nn, sizeof(double));
  for (int d = 0; d < 3; ++d)
    x->f[d] = calloc(nn, sizeof(double)), x->v[d] = calloc(nn, sizeof(double));
  x->set = (mpm_span_set){.lo = {0, 0, 0}, .hi = {9, 7, 7}};
}

static void done(fixture *x) {
  free(x->p), free(x->D);
  for (int d = 0; d < 3; ++d) free(x->f[d]), free(x->v[d]);
  mpm_grid_destroy(&x->g);
}

static void node_of(const mpm_grid *g, mpm_lidx k, int *gi) {
  for (int d = 0; d < g->dim; ++d) {
    gi[d] = g->box_lo[d] + (int)(k % g->box_n[d]);
    k /= g->box_n[d];
  }
}

/* Is node k's support (spans gi - 1 .. gi + 1) inside the set? */
static int interior(const fixture *x, mpm_lidx k) {
  int gi[3];
  node_of(x->g, k, gi);
  for (int d = 0; d < x->g->dim; ++d)
    if (gi[d] - 1 < x->set.lo[d] || gi[d] + 1 > x->set.hi[d]) return 0;
  return 1;
}

static double uniform(uint64_t *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(*s >> 11) / 9007199254740992.0 - 0.5;
}

static void adjoint(int dim) {
  fixture x;
  make(&x, dim);
  uint64_t s = 7;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    x.p[k] = uniform(&s);
    for (int d = 0; d < dim; ++d) x.v[d][k] = uniform(&s);
  }
  mpm_span_force(x.g, &x.set, x.p, x.f);
  mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
  double fv = 0, pd = 0, scale = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    for (int d = 0; d < dim; ++d) fv += x.f[d][k] * x.v[d][k], scale += fabs(x.f[d][k] * x.v[d][k]);
    pd += x.p[k] * x.D[k];
  }
  printf("%d-D: sum f.v = %.15e, sum p D = %.15e (of %.3e)\n", dim, fv, pd, scale);
  assert_true(fabs(fv - pd) <= 1e-13 * scale);
  done(&x);
}

static void test_adjoint(void **state) {
  (void)state;
  adjoint(2), adjoint(3);
}

static void pressure(int dim) {
  fixture x;
  make(&x, dim);
  const double a = 2.0, b = 3.0, hd = pow(H, dim);
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) x.p[k] = a;
  mpm_span_force(x.g, &x.set, x.p, x.f);
  double worst = 0;
  int count = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k)
    for (int d = 0; d < dim && interior(&x, k); ++d) worst = fmax(worst, fabs(x.f[d][k])), ++count;
  printf("%d-D constant p: largest interior |f| %.2e over %d components\n", dim, worst, count);
  assert_true(count > 0 && worst <= 1e-15 * a * pow(H, dim - 1));
  for (int d = 0; d < dim; ++d) memset(x.f[d], 0, sizeof(double) * (size_t)x.g->nnodes);
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    int gi[3];
    node_of(x.g, k, gi);
    x.p[k] = a + b * gi[0] * H;
  }
  mpm_span_force(x.g, &x.set, x.p, x.f);
  worst = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    if (!interior(&x, k)) continue;
    worst = fmax(worst, fabs(x.f[0][k] + b * hd) / (b * hd));
    for (int d = 1; d < dim; ++d) worst = fmax(worst, fabs(x.f[d][k]) / (b * hd));
  }
  printf("%d-D linear p: largest interior deviation from f_x = -b h^dim %.2e (relative)\n", dim,
         worst);
  assert_true(worst <= 1e-13);
  done(&x);
}

static void test_pressure(void **state) {
  (void)state;
  pressure(2), pressure(3);
}

static void divergence(int dim) {
  fixture x;
  make(&x, dim);
  const double c = 1.5, hd = pow(H, dim);
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k)
    for (int d = 0; d < dim; ++d) x.v[d][k] = 0.7 + d;
  mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
  double worst = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) worst = fmax(worst, fabs(x.D[k]));
  printf("%d-D constant v: largest |D| %.2e\n", dim, worst);
  assert_true(worst <= 1e-15 * hd / H);
  memset(x.D, 0, sizeof(double) * (size_t)x.g->nnodes);
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    int gi[3];
    node_of(x.g, k, gi);
    x.v[0][k] = c * gi[0] * H;
    for (int d = 1; d < dim; ++d) x.v[d][k] = 0.0;
  }
  mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
  worst = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k)
    if (interior(&x, k)) worst = fmax(worst, fabs(x.D[k] - c * hd) / (c * hd));
  printf("%d-D linear v: largest interior deviation from D = c h^dim %.2e (relative)\n", dim,
         worst);
  assert_true(worst <= 1e-13);
  /* (4) the same field over the spans 0 .. 10 along x, both ends halved */
  memset(x.D, 0, sizeof(double) * (size_t)x.g->nnodes);
  x.set.hi[0] = 10, x.set.half_lo[0] = x.set.half_hi[0] = 1;
  mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
  double sum = 0, want = c * 10 * H;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) sum += x.D[k];
  for (int d = 1; d < dim; ++d) want *= 8 * H;
  printf("%d-D halved ends: sum D %.15e, integral of div v %.15e\n", dim, sum, want);
  assert_true(fabs(sum - want) <= 1e-13 * want);
  done(&x);
}

static void test_divergence(void **state) {
  (void)state;
  divergence(2), divergence(3);
}

/* The set of (5): all ends halved, the spans of nodes (3, 3, 3) and (5, 2, 4) skipped. Returns
 * the measure of what it integrates. */
static double halved_set(fixture *x, int dim, unsigned char *skip) {
  const int gap[2][3] = {{3, 3, 3}, {5, 2, 4}};
  x->set = (mpm_span_set){.lo = {0, 0, 0}, .hi = {10, 7, 7}, .skip = skip};
  double vol = 10 * H;
  for (int d = 0; d < dim; ++d) x->set.half_lo[d] = x->set.half_hi[d] = 1;
  for (int d = 1; d < dim; ++d) vol *= 7 * H;
  for (int k = 0; k < 2; ++k) skip[mpm_grid_local_index(x->g, gap[k])] = 1;
  return vol - 2 * pow(H, dim);
}

static void halved(int dim) {
  fixture x;
  make(&x, dim);
  const size_t nn = (size_t)x.g->nnodes;
  unsigned char *skip = calloc(nn, 1);
  const double vol = halved_set(&x, dim, skip), a = 2.0, c = 1.5;
  for (int d = 0; d < dim; ++d) {
    memset(x.D, 0, sizeof(double) * nn), memset(x.f[d], 0, sizeof(double) * nn);
    for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
      int gi[3];
      node_of(x.g, k, gi);
      x.p[k] = a, x.v[d][k] = c * gi[d] * H;
    }
    mpm_span_force(x.g, &x.set, x.p, x.f);
    mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
    double fx = 0, sd = 0;
    for (mpm_lidx k = 0; k < x.g->nnodes; ++k) fx += x.f[d][k] * x.v[d][k] / c, sd += x.D[k];
    printf("%d-D halved, axis %d: sum D %.15e, sum f x %.15e, want %.15e, %.15e\n", dim, d, sd, fx,
           c * vol, a * vol);
    assert_true(fabs(sd - c * vol) <= 1e-13 * c * vol);
    assert_true(fabs(fx - a * vol) <= 1e-13 * a * vol);
    memset(x.v[d], 0, sizeof(double) * nn);
  }
  uint64_t s = 5;
  memset(x.D, 0, sizeof(double) * nn);
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    x.p[k] = uniform(&s);
    for (int d = 0; d < dim; ++d) x.v[d][k] = uniform(&s), x.f[d][k] = 0;
  }
  mpm_span_force(x.g, &x.set, x.p, x.f);
  mpm_span_divergence(x.g, &x.set, (const double *const *)x.v, x.D);
  double fv = 0, pd = 0, scale = 0;
  for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
    for (int d = 0; d < dim; ++d) fv += x.f[d][k] * x.v[d][k], scale += fabs(x.f[d][k] * x.v[d][k]);
    pd += x.p[k] * x.D[k];
  }
  printf("%d-D halved, skipped: sum f.v = %.15e, sum p D = %.15e\n", dim, fv, pd);
  assert_true(fabs(fv - pd) <= 1e-13 * scale);
  free(skip);
  done(&x);
}

static void test_halved(void **state) {
  (void)state;
  halved(2), halved(3);
}

/* (6): the planes through the end nodes along d of the set of (5), without its skipped spans. */
static void planes(int dim) {
  fixture x;
  make(&x, dim);
  const size_t nn = (size_t)x.g->nnodes;
  const double a = 2.0, c = 1.5;
  double len[3] = {10 * H, 7 * H, 7 * H};
  x.set = (mpm_span_set){.lo = {0, 0, 0}, .hi = {10, 7, 7}};
  for (int d = 0; d < dim; ++d) x.set.half_lo[d] = x.set.half_hi[d] = 1;
  double *plane = calloc(nn, sizeof(double));
  for (int d = 0; d < dim; ++d) {
    for (mpm_lidx k = 0; k < x.g->nnodes; ++k) x.p[k] = a, x.f[d][k] = 0;
    mpm_span_force(x.g, &x.set, x.p, x.f);
    for (int side = 0; side < 2; ++side) {
      mpm_span_set face = x.set;
      face.lo[d] = face.hi[d] = side ? x.set.hi[d] : 0, face.half_lo[d] = face.half_hi[d] = 0;
      memset(plane, 0, sizeof(double) * nn);
      mpm_span_plane(x.g, &face, d, x.p, plane);
      for (mpm_lidx k = 0; k < x.g->nnodes; ++k) x.f[d][k] += (side ? -1.0 : 1.0) * plane[k];
    }
    double worst = 0;
    for (mpm_lidx k = 0; k < x.g->nnodes; ++k) worst = fmax(worst, fabs(x.f[d][k]));
    printf("%d-D planes along %d: largest |f - planes| %.2e (of a h^(dim-1) %.1e)\n", dim, d, worst,
           a * pow(H, dim - 1));
    assert_true(worst <= 1e-14 * a * pow(H, dim - 1));
    for (int t = 0; t < dim; ++t) {
      if (t == d) continue;
      for (mpm_lidx k = 0; k < x.g->nnodes; ++k) {
        int gi[3];
        node_of(x.g, k, gi);
        x.p[k] = c * gi[t] * H;
      }
      mpm_span_set face = x.set;
      face.lo[d] = face.hi[d] = x.set.hi[d], face.half_lo[d] = face.half_hi[d] = 0;
      memset(plane, 0, sizeof(double) * nn);
      mpm_span_plane(x.g, &face, d, x.p, plane);
      double sum = 0, want = c * len[t] * len[t] / 2;
      for (mpm_lidx k = 0; k < x.g->nnodes; ++k) sum += plane[k];
      for (int e = 0; e < dim; ++e) want *= e == d || e == t ? 1.0 : len[e];
      printf("%d-D plane along %d of c x_%d: %.15e, want %.15e\n", dim, d, t, sum, want);
      assert_true(fabs(sum - want) <= 1e-13 * want);
    }
  }
  free(plane);
  done(&x);
}

static void test_planes(void **state) {
  (void)state;
  planes(2), planes(3);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_adjoint),    cmocka_unit_test(test_pressure),
      cmocka_unit_test(test_divergence), cmocka_unit_test(test_halved),
      cmocka_unit_test(test_planes),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
