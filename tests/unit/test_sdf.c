/* Signed distances (mpm_sdf.h): exact values and normals of boxes, circles, spheres, polygons
 * (2-D and extruded), the wedge helper, self-intersection, and the RAE 2822 aerofoil read from
 * the shared coordinate file (maximum thickness 0.121 c, closed outline, angle of attack).
 * Tolerances: 1e-12 on distances computed from a few exact operations (roundoff); the
 * aerofoil's thickness to 5e-4 c (the ordinates are given to 1e-6 c; the maximum is found
 * on a 1e-4 c grid of stations, between the tabulated ones). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>

#include "mpm_sdf.h"

#define TOL  1e-12
#define M_PI 3.14159265358979323846

static const char *g_airfoil; /* argv[1]: the RAE 2822 coordinate file */

static void expect(const mpm_sdf *s, const double *x, double phi, const double *n) {
  double nrm[3];
  const double got = mpm_sdf_eval(s, x, nrm);
  if (!(fabs(got - phi) <= TOL))
    printf("phi(%g, %g) = %.17g, expected %.17g\n", x[0], x[1], got, phi);
  assert_true(fabs(got - phi) <= TOL);
  for (int d = 0; n && d < s->dim; ++d) assert_true(fabs(nrm[d] - n[d]) <= TOL);
}

static void test_box(void **state) {
  (void)state;
  mpm_sdf s;
  mpm_sdf_box(&s, 2, (double[]){0, 0}, (double[]){2, 1});
  expect(&s, (double[]){1, 0.5}, -0.5, (double[]){0, 1});   /* centre: nearest face y */
  expect(&s, (double[]){1.8, 0.5}, -0.2, (double[]){1, 0}); /* inside near x_hi */
  expect(&s, (double[]){3, 0.5}, 1.0, (double[]){1, 0});    /* beside a face */
  expect(&s, (double[]){5, 5}, 5.0, (double[]){0.6, 0.8});  /* beyond the corner (3, 4, 5) */
  expect(&s, (double[]){-1, -1}, sqrt(2.0), (double[]){-sqrt(0.5), -sqrt(0.5)});
  mpm_sdf_box(&s, 3, (double[]){0, 0, 0}, (double[]){1, 1, 1});
  expect(&s, (double[]){0.5, 0.5, 0.9}, -0.1, (double[]){0, 0, 1});
  expect(&s, (double[]){0.5, 2, 3}, sqrt(5.0), (double[]){0, 1 / sqrt(5.0), 2 / sqrt(5.0)});
}

static void test_ball(void **state) {
  (void)state;
  mpm_sdf s;
  mpm_sdf_ball(&s, 2, (double[]){1, 1}, 0.5);
  expect(&s, (double[]){1, 1}, -0.5, NULL);
  expect(&s, (double[]){1.3, 1.4}, 0.0, (double[]){0.6, 0.8});
  expect(&s, (double[]){4, 5}, 4.5, (double[]){0.6, 0.8});
  mpm_sdf_ball(&s, 3, (double[]){0, 0, 0}, 1);
  expect(&s, (double[]){0, 0, -3}, 2.0, (double[]){0, 0, -1});
}

/* A unit square given clockwise (the sign must not depend on the orientation) and an L. */
static void test_polygon(void **state) {
  (void)state;
  mpm_sdf s;
  const double cw[] = {0, 0, 0, 1, 1, 1, 1, 0};
  assert_int_equal(mpm_sdf_polygon(&s, 2, cw, 4, NULL), 0);
  expect(&s, (double[]){0.5, 0.5}, -0.5, NULL);
  expect(&s, (double[]){0.5, 0.9}, -0.1, (double[]){0, 1});
  expect(&s, (double[]){0.5, 0}, 0.0, (double[]){0, -1}); /* on an edge: its outward normal */
  expect(&s, (double[]){2, 2}, sqrt(2.0), (double[]){sqrt(0.5), sqrt(0.5)});
  mpm_sdf_free(&s);
  const double L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
  assert_int_equal(mpm_sdf_polygon(&s, 2, L, 6, NULL), 0);
  expect(&s, (double[]){1.2, 1.5}, 0.2, (double[]){1, 0});  /* in the notch */
  expect(&s, (double[]){1.5, 0.9}, -0.1, (double[]){0, 1}); /* under the notch */
  expect(&s, (double[]){0.9, 0.9}, -sqrt(0.02), NULL);      /* nearest the re-entrant corner */
  mpm_sdf_free(&s);
  /* 3-D extrusion between z = 0 and 1, and endless. */
  assert_int_equal(mpm_sdf_polygon(&s, 3, cw, 4, (double[]){0, 1}), 0);
  expect(&s, (double[]){0.5, 0.5, 0.8}, -0.2, (double[]){0, 0, 1});
  expect(&s, (double[]){1.3, 0.5, 1.4}, 0.5, (double[]){0.6, 0, 0.8});
  mpm_sdf_free(&s);
  assert_int_equal(mpm_sdf_polygon(&s, 3, cw, 4, NULL), 0);
  expect(&s, (double[]){0.5, 0.9, 100}, -0.1, (double[]){0, 1, 0});
  mpm_sdf_free(&s);
}

/* Grid nodes on an edge through round coordinates: x = i * 0.02 is on the edge y = 0.1 only up
 * to roundoff in the projection, so the distance is ~1e-17 and the direction from the nearest
 * point anywhere. The normal must still be the edge's (it was +-x: a slip wall stopped the
 * flow along it). Every node of the edge, in both orientations, and a slanted edge. */
static void test_polygon_on_edge(void **state) {
  (void)state;
  mpm_sdf s;
  const double below[] = {-0.2, 0.1, 1.2, 0.1, 1.2, -0.2, -0.2, -0.2}; /* clockwise */
  const double ccw[] = {-0.2, -0.2, 1.2, -0.2, 1.2, 0.1, -0.2, 0.1};
  const double *outlines[] = {below, ccw};
  for (int k = 0; k < 2; ++k) {
    assert_int_equal(mpm_sdf_polygon(&s, 2, outlines[k], 4, NULL), 0);
    for (int i = 0; i <= 50; ++i) {
      const double dx = 1.0 / 50;
      double nrm[2];
      const double phi = mpm_sdf_eval(&s, (double[]){i * dx, 5 * dx}, nrm);
      if (!(fabs(phi) <= TOL && fabs(nrm[0]) <= TOL && fabs(nrm[1] - 1) <= TOL))
        printf("node %d: phi %.3g, normal (%.17g, %.17g)\n", i, phi, nrm[0], nrm[1]);
      assert_true(fabs(phi) <= TOL && fabs(nrm[0]) <= TOL && fabs(nrm[1] - 1) <= TOL);
    }
    mpm_sdf_free(&s);
  }
  const double t = tan(10 * M_PI / 180), c = cos(10 * M_PI / 180), sn = sin(10 * M_PI / 180);
  const double slant[] = {-0.2, 0.1 - 0.2 * t, 1.2, 0.1 + 1.2 * t, 1.2, -0.2, -0.2, -0.2};
  assert_int_equal(mpm_sdf_polygon(&s, 2, slant, 4, NULL), 0);
  for (int i = 0; i <= 50; ++i) { /* points on the slanted edge, from its own parametrisation */
    const double x = i / 50.0;
    expect(&s, (double[]){x, 0.1 + x * t}, 0.0, (double[]){-sn, c});
  }
  mpm_sdf_free(&s);
}

static void test_self_intersection(void **state) {
  (void)state;
  const double bow[] = {0, 0, 1, 1, 1, 0, 0, 1}; /* a bow tie: edges 0 and 2 cross */
  const double sq[] = {0, 0, 1, 0, 1, 1, 0, 1};
  int i, j;
  assert_int_equal(mpm_polygon_self_intersects(bow, 4, &i, &j), 1);
  assert_int_equal(i, 0);
  assert_int_equal(j, 2);
  assert_int_equal(mpm_polygon_self_intersects(sq, 4, &i, &j), 0);
  const double touch[] = {0, 0, 2, 0, 2, 2, 1, 0, 0, 2}; /* vertex 3 lies on edge 0 */
  assert_int_equal(mpm_polygon_self_intersects(touch, 5, &i, &j), 1);
}

/* The 15 degree ramp: the surface rises from the foot, the distance above it is measured
 * along its normal (-sin, cos). */
static void test_wedge(void **state) {
  (void)state;
  mpm_sdf s;
  const double a = 15.0 * M_PI / 180.0;
  assert_int_equal(mpm_sdf_wedge(&s, 2, (double[]){0.5, 0}, 1.0, 15.0, NULL), 0);
  const double on[2] = {0.5 + 0.4, 0.4 * tan(a)}, up = 0.01;
  expect(&s, (double[]){on[0] - up * sin(a), on[1] + up * cos(a)}, up, (double[]){-sin(a), cos(a)});
  expect(&s, (double[]){1.4, 0.01}, -0.01, (double[]){0, -1}); /* just above the base */
  expect(&s, (double[]){0.2, 0.0}, 0.3, (double[]){-1, 0});    /* upstream on the wall */
  assert_true(fabs(s.hi[1] - tan(a)) <= TOL);
  mpm_sdf_free(&s);
}

/* Largest distance between the lower and upper surface along y at a station x (bisection on
 * the sign of phi from the chord line, which is inside for 0 < x < c). */
static double surface_at(const mpm_sdf *s, double x, double dir) {
  double in = 0.0, out = 0.2 * dir;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (in + out);
    if (mpm_sdf_eval(s, (double[]){x, mid}, NULL) < 0)
      in = mid;
    else
      out = mid;
  }
  return 0.5 * (in + out);
}

static void test_airfoil(void **state) {
  (void)state;
  const char *path = g_airfoil;
  double *xy = NULL, err_le[2] = {0, 0};
  int nv = 0;
  char err[256];
  assert_int_equal(mpm_airfoil_read(path, 1.0, err_le, 0.0, &xy, &nv, err, sizeof err), 0);
  assert_int_equal(nv, 128); /* 129 rows, the closing (1, 0) dropped */
  int i, j;
  assert_int_equal(mpm_polygon_self_intersects(xy, nv, &i, &j), 0);
  mpm_sdf s;
  assert_int_equal(mpm_sdf_polygon(&s, 2, xy, nv, NULL), 0);
  for (int k = 0; k < nv; ++k) assert_true(fabs(mpm_sdf_eval(&s, &xy[2 * k], NULL)) <= TOL);
  double tmax = 0.0;
  for (double x = 0.2; x <= 0.6; x += 1e-4)
    tmax = fmax(tmax, surface_at(&s, x, 1) - surface_at(&s, x, -1));
  printf("RAE 2822 maximum thickness %.5f c\n", tmax);
  assert_true(fabs(tmax - 0.121) <= 5e-4);
  assert_true(mpm_sdf_eval(&s, (double[]){0.5, 0.0}, NULL) < 0);  /* closed: inside */
  assert_true(mpm_sdf_eval(&s, (double[]){-0.1, 0.0}, NULL) > 0); /* ahead of the nose */
  assert_true(mpm_sdf_eval(&s, (double[]){1.1, 0.0}, NULL) > 0);  /* behind the tail */
  mpm_sdf_free(&s);
  free(xy);
  /* Chord 2, leading edge at (1, 1), 10 degrees: the trailing edge goes to
   * (1 + 2 cos 10, 1 - 2 sin 10) (nose up for a flow along +x). */
  const double le[2] = {1, 1}, a = 10.0 * M_PI / 180.0;
  assert_int_equal(mpm_airfoil_read(path, 2.0, le, 10.0, &xy, &nv, err, sizeof err), 0);
  assert_true(fabs(xy[0] - (1 + 2 * cos(a))) <= TOL && fabs(xy[1] - (1 - 2 * sin(a))) <= TOL);
  free(xy);
  assert_int_not_equal(mpm_airfoil_read("/nonexistent.csv", 1, le, 0, &xy, &nv, err, sizeof err),
                       0);
  assert_non_null(strstr(err, "/nonexistent.csv"));
}

int main(int argc, char **argv) {
  g_airfoil = argc > 1 ? argv[1] : "cases/rae2822_coordinates.csv";
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box),
      cmocka_unit_test(test_ball),
      cmocka_unit_test(test_polygon),
      cmocka_unit_test(test_polygon_on_edge),
      cmocka_unit_test(test_self_intersection),
      cmocka_unit_test(test_wedge),
      cmocka_unit_test(test_airfoil),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
