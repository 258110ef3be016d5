/* Shape functions (mpm_shape.h): the reproducing properties every MPM transfer relies on,
 * checked on tensor-product stencils in 2-D and 3-D at random points, plus the 1-D pieces
 * against independent reference formulas, finite-difference derivatives, continuity at
 * the breakpoints, and the name table.
 *
 * Properties at a point x (grid units), over the stencil nodes i with S_i = prod_d w_d:
 *   partition of unity     sum S_i = 1
 *   linear completeness    sum S_i x_i = x
 *   gradient sums          sum grad S_i = 0,  sum x_i (x) grad S_i = I
 * all to 1e-13 absolute, with x = O(10) so that rounding is the only error source. */
#include "mpm_random.h"
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "mpm_shape.h"

#define NPOINTS 20000
#define TOL     1e-13
#define FD_STEP 1e-6
#define FD_TOL  1e-6

typedef struct shape_case {
  mpm_shape_kind kind;
  double lp; /* GIMP half-width; ignored by the others */
  const char *label;
} shape_case;

static const shape_case g_cases[] = {
    {MPM_SHAPE_LINEAR, 0.5, "linear"},    {MPM_SHAPE_GIMP, 0.25, "gimp lp=0.25"},
    {MPM_SHAPE_GIMP, 0.5, "gimp lp=0.5"}, {MPM_SHAPE_QUADRATIC, 0.5, "quadratic"},
    {MPM_SHAPE_CUBIC, 0.5, "cubic"},
};
#define NCASES ((int)(sizeof g_cases / sizeof g_cases[0]))

/* ------------------------------------------------------------------------ helpers --- */

static double next_uniform(uint64_t *state) {
  return mpm_test_uniform(state);
}

/* Uniform in [4, 12): the stencil stays well inside a lattice of nodes 0..16. */
static double random_xi(uint64_t *state) {
  return 4.0 + 8.0 * next_uniform(state);
}

/* Antiderivative of the hat max(0, 1 - |s|). */
static double hat_integral(double s) {
  if (s <= -1.0) return 0.0;
  if (s <= 0.0) return 0.5 * (s + 1.0) * (s + 1.0);
  if (s <= 1.0) return 1.0 - 0.5 * (1.0 - s) * (1.0 - s);
  return 1.0;
}

/* Cardinal B-spline of order n on [0, n] by the Cox-de Boor recursion. */
static double cardinal_bspline(int n, double t) {
  if (n == 1) return t >= 0.0 && t < 1.0 ? 1.0 : 0.0;
  return (t * cardinal_bspline(n - 1, t) + (n - t) * cardinal_bspline(n - 1, t - 1.0)) / (n - 1);
}

/* Reference weight of a node at distance r, derived independently of mpm_shape.h: GIMP as
 * the hat averaged over the particle [r - lp, r + lp], B-splines by recursion. */
static double reference_weight(mpm_shape_kind kind, double r, double lp) {
  switch (kind) {
  case MPM_SHAPE_LINEAR:
    return fabs(r) < 1.0 ? 1.0 - fabs(r) : 0.0;
  case MPM_SHAPE_GIMP:
    return (hat_integral(r + lp) - hat_integral(r - lp)) / (2.0 * lp);
  case MPM_SHAPE_QUADRATIC:
    return cardinal_bspline(3, r + 1.5);
  default:
    return cardinal_bspline(4, r + 2.0);
  }
}

/* Weight of global node j for a particle at xi (0 outside the stencil). */
static double node_weight(mpm_shape_kind kind, double xi, double lp, int j, double *dw_out) {
  double w[MPM_SHAPE_MAX_SUPPORT], dw[MPM_SHAPE_MAX_SUPPORT];
  int base = mpm_shape_1d(kind, xi, lp, w, dw);
  int k = j - base;
  int in = k >= 0 && k < mpm_shape_support(kind);
  if (dw_out) *dw_out = in ? dw[k] : 0.0;
  return in ? w[k] : 0.0;
}

/* ------------------------------------------------- tensor-product reproduction tests --- */

typedef struct max_errors {
  double unity, linear, grad_sum, grad_moment;
} max_errors;

/* Accumulate the four sums over one point's stencil and record the worst deviations. */
static void check_point(const shape_case *c, int dim, const double *xi, max_errors *e) {
  int base[3], n = mpm_shape_support(c->kind), nn = 1;
  double w[3][MPM_SHAPE_MAX_SUPPORT], dw[3][MPM_SHAPE_MAX_SUPPORT];
  double sum = 0.0, sx[3] = {0}, g[3] = {0}, m[3][3] = {{0}};
  mpm_shape_eval(c->kind, dim, xi, c->lp, base, w, dw);
  for (int d = 0; d < dim; ++d) nn *= n;
  for (int node = 0; node < nn; ++node) {
    int k[3] = {node % n, (node / n) % n, node / (n * n)};
    double s = 1.0, grad[3], xn[3];
    for (int d = 0; d < dim; ++d) s *= w[d][k[d]], xn[d] = base[d] + k[d];
    for (int a = 0; a < dim; ++a) {
      grad[a] = dw[a][k[a]];
      for (int d = 0; d < dim; ++d)
        if (d != a) grad[a] *= w[d][k[d]];
    }
    sum += s;
    for (int a = 0; a < dim; ++a) {
      sx[a] += s * xn[a], g[a] += grad[a];
      for (int b = 0; b < dim; ++b) m[a][b] += xn[a] * grad[b];
    }
  }
  e->unity = fmax(e->unity, fabs(sum - 1.0));
  for (int a = 0; a < dim; ++a) {
    e->linear = fmax(e->linear, fabs(sx[a] - xi[a]));
    e->grad_sum = fmax(e->grad_sum, fabs(g[a]));
    for (int b = 0; b < dim; ++b)
      e->grad_moment = fmax(e->grad_moment, fabs(m[a][b] - (a == b ? 1.0 : 0.0)));
  }
}

static void run_reproduction(const shape_case *c, int dim) {
  uint64_t state = 12345u + 77u * (uint64_t)c->kind + (uint64_t)(c->lp * 1000) + (uint64_t)dim;
  max_errors e = {0, 0, 0, 0};
  for (int p = 0; p < NPOINTS; ++p) {
    double xi[3];
    for (int d = 0; d < dim; ++d) xi[d] = random_xi(&state);
    check_point(c, dim, xi, &e);
  }
  printf("  %-13s %d-D, %d points: max |sum S-1| %.2e, |sum S x - x| %.2e, |sum grad S| %.2e, "
         "|sum x (x) grad S - I| %.2e\n",
         c->label, dim, NPOINTS, e.unity, e.linear, e.grad_sum, e.grad_moment);
  assert_true(e.unity <= TOL);
  assert_true(e.linear <= TOL);
  assert_true(e.grad_sum <= TOL);
  assert_true(e.grad_moment <= TOL);
}

static void test_reproduction_2d(void **state) {
  run_reproduction(*state, 2);
}
static void test_reproduction_3d(void **state) {
  run_reproduction(*state, 3);
}

/* -------------------------------------------------------------------- 1-D checks --- */

/* The evaluated weights equal the reference at every stencil node, every weight is
 * non-negative, unused slots are zero, and the nodes just outside the stencil would get
 * nothing: the stencil misses no weight. */
static void test_weights_and_support(void **state) {
  const shape_case *c = *state;
  const int n = mpm_shape_support(c->kind);
  uint64_t seed = 999u + (uint64_t)c->kind;
  double worst = 0.0;
  for (int p = 0; p < NPOINTS; ++p) {
    double xi = random_xi(&seed), w[MPM_SHAPE_MAX_SUPPORT], dw[MPM_SHAPE_MAX_SUPPORT];
    int base = mpm_shape_1d(c->kind, xi, c->lp, w, dw), cell = (int)floor(xi);
    for (int k = 0; k < MPM_SHAPE_MAX_SUPPORT; ++k) {
      assert_true(w[k] >= 0.0);
      if (k >= n)
        assert_true(w[k] == 0.0 && dw[k] == 0.0);
      else
        worst = fmax(worst, fabs(w[k] - reference_weight(c->kind, xi - (base + k), c->lp)));
    }
    assert_true(reference_weight(c->kind, xi - (base - 1), c->lp) == 0.0);
    assert_true(reference_weight(c->kind, xi - (base + n), c->lp) == 0.0);
    /* The documented reach: a particle in cell c touches nodes c-1 .. c+2 at most. */
    assert_true(base >= cell - 1 && base + n - 1 <= cell + 2);
    assert_true(cell - base <= mpm_shape_ghost_width(c->kind));
  }
  printf("  %-13s max |w - reference| %.2e\n", c->label, worst);
  assert_true(worst <= TOL);
}

/* Distance from xi to the nearest point where some node's weight has a kink (a jump of
 * the first derivative for linear, of the second for GIMP and quadratic, of the third for
 * cubic), where a central difference loses its accuracy. Only the fractional part counts. */
static double distance_to_breakpoint(const shape_case *c, double xi) {
  double f = xi - floor(xi);
  double b[4] = {0.0, 1.0, 0.5, 0.5}; /* linear, cubic: integers; quadratic: half-integers */
  if (c->kind == MPM_SHAPE_GIMP) b[2] = c->lp, b[3] = 1.0 - c->lp; /* +-lp, +-(1 -+ lp) */
  if (c->kind == MPM_SHAPE_QUADRATIC) b[0] = b[1] = 0.5;
  double best = 1.0;
  for (int i = 0; i < 4; ++i) best = fmin(best, fabs(f - b[i]));
  return best;
}

/* dw against the central difference of w for every node of the stencil. */
static void test_derivative_fd(void **state) {
  const shape_case *c = *state;
  uint64_t seed = 4242u + (uint64_t)c->kind;
  double worst = 0.0;
  for (int p = 0; p < NPOINTS; ++p) {
    double xi = random_xi(&seed), w[MPM_SHAPE_MAX_SUPPORT], dw[MPM_SHAPE_MAX_SUPPORT];
    if (distance_to_breakpoint(c, xi) < 10.0 * FD_STEP) continue;
    int base = mpm_shape_1d(c->kind, xi, c->lp, w, dw);
    for (int k = 0; k < mpm_shape_support(c->kind); ++k) {
      double fd = (node_weight(c->kind, xi + FD_STEP, c->lp, base + k, NULL) -
                   node_weight(c->kind, xi - FD_STEP, c->lp, base + k, NULL)) /
                  (2.0 * FD_STEP);
      worst = fmax(worst, fabs(fd - dw[k]));
    }
  }
  printf("  %-13s max |dw - central difference| %.2e\n", c->label, worst);
  assert_true(worst <= FD_TOL);
}

/* At every multiple of 1/8 (this covers the breakpoints of every kind, GIMP's +-lp,
 * +-(1-lp), +-(1+lp) for lp = 0.25 and 0.5, and the points where the stencil base moves),
 * each node's weight is the same just below, at and just above the point; so is its
 * derivative for the C1 kinds (all but linear). Partition of unity holds exactly there. */
static void test_continuity(void **state) {
  const shape_case *c = *state;
  double worst_w = 0.0, worst_dw = 0.0;
  for (int s = 0; s <= 64; ++s) {
    double xi = 4.0 + s / 8.0, sides[3] = {nextafter(xi, 0.0), xi, nextafter(xi, 100.0)};
    for (int j = (int)xi - 3; j <= (int)xi + 3; ++j) {
      double w[3], dw[3];
      for (int t = 0; t < 3; ++t) w[t] = node_weight(c->kind, sides[t], c->lp, j, &dw[t]);
      worst_w = fmax(worst_w, fmax(fabs(w[0] - w[1]), fabs(w[2] - w[1])));
      worst_dw = fmax(worst_dw, fmax(fabs(dw[0] - dw[1]), fabs(dw[2] - dw[1])));
      assert_true(fabs(w[1] - reference_weight(c->kind, xi - j, c->lp)) <= TOL);
    }
    max_errors e = {0, 0, 0, 0};
    double x2[2] = {xi, xi};
    check_point(c, 2, x2, &e);
    assert_true(e.unity <= TOL && e.linear <= TOL && e.grad_sum <= TOL);
  }
  printf("  %-13s at breakpoints: max jump of w %.2e, of dw %.2e\n", c->label, worst_w, worst_dw);
  assert_true(worst_w <= 1e-12);
  if (c->kind != MPM_SHAPE_LINEAR) assert_true(worst_dw <= 1e-12);
}

/* GIMP's pieces meet: evaluate one node on both sides of each piece boundary. */
static void test_gimp_pieces(void **state) {
  (void)state;
  const double lps[] = {0.1, 0.25, 0.4, 0.5};
  for (int i = 0; i < 4; ++i) {
    const double lp = lps[i], b[] = {0.0, lp, 1.0 - lp, 1.0 + lp};
    for (int k = 0; k < 4; ++k)
      for (int sign = -1; sign <= 1; sign += 2) {
        double r = sign * b[k], w0, dw0, w1, dw1;
        mpm_shape_gimp_node(nextafter(r, -10.0), lp, &w0, &dw0);
        mpm_shape_gimp_node(nextafter(r, 10.0), lp, &w1, &dw1);
        assert_true(fabs(w0 - w1) <= 1e-12 && fabs(dw0 - dw1) <= 1e-12);
        mpm_shape_gimp_node(r, lp, &w0, &dw0);
        assert_true(fabs(w0 - reference_weight(MPM_SHAPE_GIMP, r, lp)) <= TOL);
      }
  }
}

static void test_names(void **state) {
  (void)state;
  for (int k = 0; k < MPM_SHAPE_COUNT; ++k)
    assert_int_equal(mpm_shape_parse(mpm_shape_name((mpm_shape_kind)k)), k);
  assert_string_equal(mpm_shape_name(MPM_SHAPE_QUADRATIC), "quadratic");
  assert_int_equal(mpm_shape_parse("gimp"), MPM_SHAPE_GIMP);
  assert_int_equal(mpm_shape_parse("bspline"), -1);
  assert_int_equal(mpm_shape_parse(""), -1);
  assert_string_equal(mpm_shape_name(MPM_SHAPE_COUNT), "unknown");
}

/* One named test per property and case, so a failure names the kind. */
static void add_test(struct CMUnitTest *t, int *n, CMUnitTestFunction f, const char *property,
                     const shape_case *c) {
  static char names[5 * NCASES][64];
  snprintf(names[*n], sizeof names[*n], "%s: %s", property, c->label);
  t[*n] = (struct CMUnitTest){names[*n], f, NULL, NULL, (void *)c};
  ++*n;
}

int main(void) {
  struct CMUnitTest tests[5 * NCASES + 2];
  int n = 0;
  for (int i = 0; i < NCASES; ++i) {
    add_test(tests, &n, test_reproduction_2d, "reproduction 2-D", &g_cases[i]);
    add_test(tests, &n, test_reproduction_3d, "reproduction 3-D", &g_cases[i]);
    add_test(tests, &n, test_weights_and_support, "weights and support", &g_cases[i]);
    add_test(tests, &n, test_derivative_fd, "derivative vs FD", &g_cases[i]);
    add_test(tests, &n, test_continuity, "continuity", &g_cases[i]);
  }
  tests[n++] = (struct CMUnitTest)cmocka_unit_test(test_gimp_pieces);
  tests[n++] = (struct CMUnitTest)cmocka_unit_test(test_names);
  return cmocka_run_group_tests_name("shape", tests, NULL, NULL);
}
