/* Geometry (mpm_geometry.h): regions built from case text, their inside tests, and
 * lattice seeding. Seeding is checked by exact counts where the lattice makes them exact
 * (cell-aligned boxes and polygons, a triangle counted column by column), by area and
 * volume bounds elsewhere, and by rank independence: the particles seeded by fake ranks
 * of a split grid, put together, are exactly those of one rank, ids and positions alike.
 *
 * The grids here are filled by hand (only the fields seeding reads), so that a split into
 * several "ranks" can be tried in one process. */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

#include <cmocka.h>
#include <math.h>

#include "mpm_config.h"
#include "mpm_error.h"
#include "mpm_geometry.h"

#define PI 3.14159265358979323846

static char g_dir[64] = "/tmp/mpm_geometry_XXXXXX"; /* polygon files live here */
static char g_files[16][128];                       /* and are removed at the end */
static int g_nfiles;

/* -------------------------------------------------------------------- fixtures --- */

typedef struct fake_grid {
  mpm_grid g;
  int split[MPM_MAX_DIM][3];
} fake_grid;

/* A grid over lo + [0, ncells dx]; cut[d] > 0 splits direction d into two fake ranks at
 * that cell, and coord[d] picks which one this grid is (cut and coord may be NULL). Keep
 * it in place: cell_split points into the struct. */
static void fake_grid_init(fake_grid *f, int dim, const double *lo, double dx, const int *ncells,
                           const int *cut, const int *coord) {
  memset(f, 0, sizeof *f);
  f->g.comm = MPI_COMM_NULL, f->g.size = 1, f->g.dim = dim, f->g.dx = dx;
  for (int d = 0; d < dim; ++d) {
    int c = cut ? cut[d] : 0;
    f->g.lo[d] = lo[d], f->g.hi[d] = lo[d] + ncells[d] * dx, f->g.ncells[d] = ncells[d];
    f->g.nproc[d] = c ? 2 : 1;
    f->g.coord[d] = c && coord ? coord[d] : 0;
    f->split[d][0] = 0, f->split[d][1] = c ? c : ncells[d], f->split[d][2] = ncells[d];
    f->g.cell_split[d] = f->split[d];
  }
}

static mpm_config *config_from(const char *text) {
  mpm_config *cfg = NULL;
  assert_int_equal(mpm_config_new(&cfg, MPI_COMM_SELF), 0);
  assert_int_equal(mpm_config_add_schema(cfg, mpm_geometry_keys, mpm_geometry_nkeys), 0);
  assert_int_equal(mpm_config_read_string(cfg, text, "geometry-test.ini", g_dir), 0);
  return cfg;
}

/* Region `name` of case text that must be valid. */
static mpm_region *region_from(const char *text, int dim, const char *name) {
  mpm_config *cfg = config_from(text);
  mpm_region *r = NULL;
  assert_int_equal(mpm_region_from_config(&r, cfg, dim, name), 0);
  assert_non_null(r);
  mpm_config_destroy(&cfg);
  return r;
}

typedef struct seeded {
  mpm_lidx n;
  double *x;
  mpm_gidx *id;
} seeded;

static seeded seed(const mpm_region *r, const fake_grid *f, int ppc, mpm_gidx id_base) {
  seeded s = {0, NULL, NULL};
  assert_int_equal(mpm_region_seed(r, &f->g, ppc, id_base, &s.n, &s.x, &s.id), 0);
  return s;
}

static void seeded_free(seeded *s) {
  free(s->x), free(s->id);
  s->x = NULL, s->id = NULL;
}

static mpm_lidx count_in(const mpm_region *r, const fake_grid *f, int ppc) {
  seeded s = seed(r, f, ppc, 0);
  seeded_free(&s);
  return s.n;
}

static void write_file(const char *path, const char *text) {
  int known = 0;
  for (int i = 0; i < g_nfiles; ++i) known |= strcmp(g_files[i], path) == 0;
  if (!known && g_nfiles < 16) snprintf(g_files[g_nfiles++], sizeof g_files[0], "%s", path);
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

/* --------------------------------------------------------------------- boxes --- */

static void test_box_count(void **state) {
  (void)state;
  fake_grid f2, f3;
  const double lo2[2] = {0, 0}, lo3[3] = {-1, -1, -1};
  fake_grid_init(&f2, 2, lo2, 0.1, (int[]){20, 16}, NULL, NULL);
  fake_grid_init(&f3, 3, lo3, 0.25, (int[]){8, 6, 5}, NULL, NULL);
  mpm_region *b2 = region_from("[geometry.b]\ntype = box\nlo = 0.2 0.3\nhi = 0.7, 0.9\n", 2, "b");
  mpm_region *b3 =
      region_from("[geometry.b]\ntype = box\nlo = -0.5 -0.75 0\nhi = 0.25 0.5 0.25\n", 3, "b");
  mpm_region *all = region_from("[geometry.b]\ntype = box\nlo = -5 -5\nhi = 5 5\n", 2, "b");
  for (int ppc = 1; ppc <= 3; ++ppc) {
    assert_int_equal(count_in(b2, &f2, ppc), 5 * 6 * ppc * ppc);           /* 5 x 6 cells */
    assert_int_equal(count_in(b3, &f3, ppc), 3 * 5 * 1 * ppc * ppc * ppc); /* 3 x 5 x 1 */
    assert_int_equal(count_in(all, &f2, ppc), 20 * 16 * ppc * ppc);        /* clipped */
  }
  double lo[2], hi[2];
  mpm_region_bounds(b2, lo, hi);
  assert_true(lo[0] == 0.2 && lo[1] == 0.3 && hi[0] == 0.7 && hi[1] == 0.9);
  assert_true(mpm_region_contains(b2, (double[]){0.2, 0.9})); /* the boundary is inside */
  assert_false(mpm_region_contains(b2, (double[]){0.19, 0.5}));
  mpm_region *far = region_from("[geometry.b]\ntype = box\nlo = 1e30 0\nhi = 2e30 1\n", 2, "b");
  seeded none = seed(far, &f2, 2, 0); /* outside the domain: nothing, and no overflow */
  assert_int_equal(none.n, 0);
  seeded_free(&none);
  mpm_region_destroy(&b2), mpm_region_destroy(&b3), mpm_region_destroy(&all);
  mpm_region_destroy(&far);
  assert_null(b2);
  mpm_region_destroy(&b2); /* NULL is fine */
}

/* Every position is a lattice point lo + (L + 0.5) h inside the region, and the id is
 * id_base plus the linearised lattice index L (x fastest). */
static void check_lattice(const mpm_region *r, const fake_grid *f, int ppc, mpm_gidx base,
                          const seeded *s) {
  const mpm_grid *g = &f->g;
  const double h = g->dx / ppc;
  for (mpm_lidx i = 0; i < s->n; ++i) {
    mpm_gidx index = s->id[i] - base, stride = 1;
    double x[3];
    assert_true(index >= 0 && index < mpm_region_seed_span(g, ppc));
    for (int d = 0; d < g->dim; ++d) {
      mpm_gidx l = (index / stride) % ((mpm_gidx)g->ncells[d] * ppc);
      x[d] = s->x[d * s->n + i];
      assert_true(fabs(x[d] - (g->lo[d] + (l + 0.5) * h)) <= 1e-12);
      stride *= (mpm_gidx)g->ncells[d] * ppc;
    }
    assert_true(mpm_region_contains(r, x));
  }
}

static void test_ids_and_span(void **state) {
  (void)state;
  fake_grid f;
  fake_grid_init(&f, 3, (double[]){0, 0, 0}, 0.1, (int[]){7, 5, 3}, NULL, NULL);
  assert_int_equal(mpm_region_seed_span(&f.g, 2), 14 * 10 * 6);
  mpm_region *b =
      region_from("[geometry.b]\ntype = box\nlo = 0.1 0 0.1\nhi = 0.4 0.3 0.3\n", 3, "b");
  seeded s = seed(b, &f, 2, 1000);
  assert_int_equal(s.n, 3 * 3 * 2 * 8);
  check_lattice(b, &f, 2, 1000, &s);
  seeded_free(&s);
  mpm_lidx n = 7;
  double *x = NULL;
  mpm_gidx *id = NULL;
  assert_int_equal(mpm_region_seed(b, &f.g, 0, 0, &n, &x, &id), MPM_ERR_INPUT);
  assert_int_equal(n, 0);
  mpm_region_destroy(&b);
}

/* ----------------------------------------------------------- balls and cylinders --- */

/* A point's lattice cell (side h) lies within half a diagonal, delta, of the point. So the
 * cells of the inside points cover the region shrunk by delta and stay inside the region
 * grown by delta: N h^dim lies between those two measures. */
static void check_measure(const char *what, double measure, double shrunk, double grown, mpm_lidx n,
                          double cell) {
  double estimate = n * cell;
  printf("  %-9s N = %7d, N h^d = %.6f, exact %.6f, relative error %.2e (bound [%.6f, %.6f])\n",
         what, n, estimate, measure, fabs(estimate - measure) / measure, shrunk, grown);
  assert_true(estimate >= shrunk && estimate <= grown);
}

static void test_disk_area(void **state) {
  (void)state;
  fake_grid f;
  fake_grid_init(&f, 2, (double[]){0, 0}, 0.1, (int[]){20, 20}, NULL, NULL);
  mpm_region *r =
      region_from("[geometry.d]\ntype = disk\ncenter = 1.03 0.97\nradius = 0.7\n", 2, "d");
  const double R = 0.7;
  for (int ppc = 1; ppc <= 4; ppc *= 2) {
    double h = 0.1 / ppc, delta = h / sqrt(2.0);
    check_measure("disk", PI * R * R, PI * (R - delta) * (R - delta),
                  PI * (R + delta) * (R + delta), count_in(r, &f, ppc), h * h);
  }
  double lo[2], hi[2];
  mpm_region_bounds(r, lo, hi);
  assert_true(fabs(lo[0] - 0.33) < 1e-15 && fabs(hi[1] - 1.67) < 1e-15);
  mpm_region_destroy(&r);
}

/* mpm_region_volume: a box (its lattice divides the box exactly) to roundoff; a disk and a
 * difference (box minus disk) within the midpoint rule's bound, the perimeter times the sample
 * spacing's half-diagonal; the point cap widens the spacing and keeps the bound with it. */
static void test_region_volume(void **state) {
  (void)state;
  mpm_region *box =
      region_from("[geometry.b]\ntype = box\nlo = 0.1 0.2\nhi = 0.106 0.23\n", 2, "b");
  const double vb = mpm_region_volume(box, 0.0001, 4e6);
  printf("  box      %.12e against %.12e\n", vb, 0.006 * 0.03);
  assert_true(fabs(vb - 0.006 * 0.03) <= 1e-12 * 0.006 * 0.03);
  mpm_region_destroy(&box);
  const char *text = "[geometry.d]\ntype = disk\ncenter = 1.03 0.97\nradius = 0.7\n"
                     "[geometry.b]\ntype = box\nlo = 0 0\nhi = 2 2\n"
                     "[geometry.c]\ntype = difference\nof = b d\n";
  mpm_region *d = region_from(text, 2, "d"), *c = region_from(text, 2, "c");
  const double disk = PI * 0.7 * 0.7, perimeter = 2.0 * PI * 0.7;
  const double h[] = {0.01, 0.001}, cap[] = {4e6, 1e4};
  for (int k = 0; k < 2; ++k) {
    /* The sample spacing: h, or where the cap binds, at most the spacing that puts 1.25^2 cap
     * points on the bounding box (each widening multiplies it by 1.25). A cut cell is wrong by
     * at most its area, and the cells the circle cuts cover at most its perimeter times the
     * cell's diagonal. */
    const double bbox_d = 1.4 * 1.4, bbox_c = 2.0 * 2.0;
    const double wd = fmax(h[k], sqrt(bbox_d * 1.5625 / cap[k]));
    const double wc = fmax(h[k], sqrt(bbox_c * 1.5625 / cap[k]));
    const double vd = mpm_region_volume(d, h[k], cap[k]), vc = mpm_region_volume(c, h[k], cap[k]);
    printf("  disk     %.6f against %.6f (bound %.2e); box minus disk %.6f against %.6f (bound "
           "%.2e)\n",
           vd, disk, perimeter * wd * sqrt(2.0), vc, 4.0 - disk, perimeter * wc * sqrt(2.0));
    assert_true(fabs(vd - disk) <= perimeter * wd * sqrt(2.0));
    assert_true(fabs(vc - (4.0 - disk)) <= perimeter * wc * sqrt(2.0));
  }
  mpm_region_destroy(&d);
  mpm_region_destroy(&c);
}

static double ball_volume(double r) {
  return 4.0 / 3.0 * PI * r * r * r;
}

static void test_sphere_volume(void **state) {
  (void)state;
  fake_grid f;
  fake_grid_init(&f, 3, (double[]){0, 0, 0}, 0.1, (int[]){20, 20, 20}, NULL, NULL);
  mpm_region *r =
      region_from("[geometry.s]\ntype = sphere\ncenter = 1.01 0.98 1.03\nradius = 0.6\n", 3, "s");
  for (int ppc = 1; ppc <= 2; ++ppc) {
    double h = 0.1 / ppc, delta = 0.5 * sqrt(3.0) * h;
    check_measure("sphere", ball_volume(0.6), ball_volume(0.6 - delta), ball_volume(0.6 + delta),
                  count_in(r, &f, ppc), h * h * h);
  }
  mpm_region_destroy(&r);
}

/* A tilted cylinder: the same bound, with the radius and the length (twice, one per end)
 * grown or shrunk by delta. Its bounding box must hold every seeded point. */
static void test_cylinder_volume(void **state) {
  (void)state;
  fake_grid f;
  fake_grid_init(&f, 3, (double[]){0, 0, 0}, 0.1, (int[]){20, 20, 20}, NULL, NULL);
  mpm_region *r = region_from("[geometry.c]\ntype = cylinder\np0 = 0.4 0.5 0.6\n"
                              "p1 = 1.5 1.3 1.2\nradius = 0.3\n",
                              3, "c");
  const double R = 0.3, L = sqrt(1.1 * 1.1 + 0.8 * 0.8 + 0.6 * 0.6), h = 0.05;
  const double delta = 0.5 * sqrt(3.0) * h;
  seeded s = seed(r, &f, 2, 0);
  check_measure("cylinder", PI * R * R * L, PI * (R - delta) * (R - delta) * (L - 2 * delta),
                PI * (R + delta) * (R + delta) * (L + 2 * delta), s.n, h * h * h);
  double lo[3], hi[3];
  mpm_region_bounds(r, lo, hi);
  for (mpm_lidx i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) assert_true(s.x[d * s.n + i] >= lo[d] && s.x[d * s.n + i] <= hi[d]);
  assert_true(mpm_region_contains(r, (double[]){0.4, 0.5, 0.6})); /* an end centre */
  assert_false(mpm_region_contains(r, (double[]){0.4 - 0.011, 0.5 - 0.008, 0.6 - 0.006}));
  seeded_free(&s);
  mpm_region_destroy(&r);
}

/* ------------------------------------------------------------------ polygons --- */

/* Right triangle (x0, y0), (x0 + A, y0), (x0, y0 + B) with x0, y0 on lattice lines: column
 * by column the inside points are those below the hypotenuse, counted here in closed form.
 * A and B are chosen so that no lattice point is within 1e-6 h of the hypotenuse. */
static mpm_lidx triangle_count(double A, double B, double h) {
  mpm_lidx n = 0;
  for (int i = 0; (i + 0.5) * h < A; ++i) {
    double height = B * (1.0 - (i + 0.5) * h / A), rows = height / h + 0.5;
    assert_true(fabs(rows - round(rows)) > 1e-6);
    if (rows > 0) n += (mpm_lidx)floor(rows);
  }
  return n;
}

static void test_polygon_triangle(void **state) {
  (void)state;
  char path[128], text[512];
  snprintf(path, sizeof path, "%s/triangle.csv", g_dir);
  write_file(path, "# triangle, x,y per line\r\n0.2,0.3\r\n\r\n1.03, 0.3  # right corner\n"
                   "0.2,0.91\n");
  snprintf(text, sizeof text, "[geometry.t]\ntype = polygon\nfile = %s\n", path);
  mpm_region *r = region_from(text, 2, "t");
  fake_grid f;
  fake_grid_init(&f, 2, (double[]){0, 0}, 0.1, (int[]){12, 10}, NULL, NULL);
  for (int ppc = 1; ppc <= 4; ++ppc) {
    double h = 0.1 / ppc;
    mpm_lidx n = count_in(r, &f, ppc), expect = triangle_count(0.83, 0.61, h);
    printf("  triangle ppc %d: N = %d (column count %d), N h^2 = %.5f, area %.5f\n", ppc, n, expect,
           n * h * h, 0.5 * 0.83 * 0.61);
    assert_int_equal(n, expect);
  }
  double lo[2], hi[2];
  mpm_region_bounds(r, lo, hi);
  assert_true(lo[0] == 0.2 && lo[1] == 0.3 && hi[0] == 1.03 && hi[1] == 0.91);
  mpm_region_destroy(&r);
}

/* An L (clockwise, with an explicit closing vertex) whose corners sit on lattice lines:
 * the points are the centres of the h-squares that tile it, so N h^2 is its area exactly. */
static const char g_ell[] = "0.2 0.2\n0.2 1.4\n0.6 1.4\n0.6 0.6\n1.2 0.6\n1.2 0.2\n0.2 0.2\n";

static void test_polygon_ell(void **state) {
  (void)state;
  char path[128], text[512];
  snprintf(path, sizeof path, "%s/ell.xy", g_dir);
  write_file(path, g_ell);
  snprintf(text, sizeof text, "[geometry.l]\ntype = polygon\nfile = %s\n", path);
  mpm_region *r = region_from(text, 2, "l");
  fake_grid f;
  fake_grid_init(&f, 2, (double[]){0, 0}, 0.1, (int[]){16, 16}, NULL, NULL);
  for (int ppc = 1; ppc <= 4; ++ppc)
    assert_int_equal(count_in(r, &f, ppc), 72 * ppc * ppc);   /* area 0.72 = 72 cells */
  assert_true(mpm_region_contains(r, (double[]){0.6, 1.0}));  /* on an edge */
  assert_true(mpm_region_contains(r, (double[]){0.6, 0.6}));  /* the reflex corner */
  assert_true(mpm_region_contains(r, (double[]){1.2, 0.2}));  /* a convex corner */
  assert_false(mpm_region_contains(r, (double[]){0.8, 0.8})); /* in the notch */
  mpm_region_destroy(&r);

  /* Extruded in 3-D over z in [0.1, 0.5]: 4 cells deep. */
  snprintf(text, sizeof text, "[geometry.l]\ntype = polygon\nfile = %s\nz = 0.1 0.5\n", path);
  r = region_from(text, 3, "l");
  fake_grid_init(&f, 3, (double[]){0, 0, 0}, 0.1, (int[]){16, 16, 8}, NULL, NULL);
  assert_int_equal(count_in(r, &f, 2), 72 * 4 * 8);
  assert_false(mpm_region_contains(r, (double[]){0.3, 0.3, 0.55}));
  mpm_region_destroy(&r);
}

/* ---------------------------------------------------------------- composites --- */

static const char g_sets[] = "[geometry.box]\ntype = box\nlo = 0.2 0.2\nhi = 1.8 1.8\n"
                             "[geometry.hole]\ntype = disk\ncenter = 1.0 1.05\nradius = 0.5\n"
                             "[geometry.cap]\ntype = disk\ncenter = 1.0 1.9\nradius = 0.4\n"
                             "[geometry.plate]\ntype = difference\nof = box hole\n"
                             "[geometry.both]\ntype = union\nof = box, cap\n"
                             "[geometry.capout]\ntype = difference\nof = cap box\n"
                             "[geometry.nested]\ntype = difference\nof = both hole\n"
                             "[geometry.far]\ntype = box\nlo = 2.5 0.1\nhi = 2.9 0.3\n"
                             "[geometry.apart]\ntype = union\nof = box far\n";

static void test_union_difference(void **state) {
  (void)state;
  const char *names[] = {"box", "hole", "cap", "plate", "both", "capout", "nested", "far", "apart"};
  mpm_lidx n[9];
  mpm_region *r[9];
  fake_grid f;
  fake_grid_init(&f, 2, (double[]){0, 0}, 0.1, (int[]){30, 24}, NULL, NULL);
  for (int i = 0; i < 9; ++i) {
    r[i] = region_from(g_sets, 2, names[i]);
    n[i] = count_in(r[i], &f, 2);
  }
  assert_int_equal(n[0], 16 * 16 * 4);
  assert_int_equal(n[3], n[0] - n[1]);      /* the hole lies inside the box */
  assert_int_equal(n[4], n[0] + n[5]);      /* box + the part of the cap outside it */
  assert_int_equal(n[6], n[4] - n[1]);      /* nested composites */
  assert_int_equal(n[8], n[0] + 4 * 2 * 4); /* disjoint union */
  assert_true(n[5] > 0 && n[5] < n[2]);
  double lo[2], hi[2];
  mpm_region_bounds(r[4], lo, hi);
  assert_true(lo[0] == 0.2 && hi[1] == 1.9 + 0.4);
  mpm_region_bounds(r[3], lo, hi); /* a difference stays within its first region */
  assert_true(lo[0] == 0.2 && hi[0] == 1.8);
  seeded s = seed(r[3], &f, 2, 0);
  for (mpm_lidx i = 0; i < s.n; ++i)
    assert_false(mpm_region_contains(r[1], (double[]){s.x[i], s.x[s.n + i]}));
  seeded_free(&s);
  for (int i = 0; i < 9; ++i) mpm_region_destroy(&r[i]);
}

/* ---------------------------------------------------------- rank independence --- */

typedef struct row {
  mpm_gidx id;
  double x[MPM_MAX_DIM];
} row;

static int by_id(const void *a, const void *b) {
  const row *p = a, *q = b;
  return (p->id > q->id) - (p->id < q->id);
}

/* Particles of several parts as (id, x) rows sorted by id, for comparing sets. */
static row *sorted_rows(const seeded *parts, int nparts, int dim, mpm_lidx *total) {
  *total = 0;
  for (int p = 0; p < nparts; ++p) *total += parts[p].n;
  row *rows = calloc((size_t)*total + 1, sizeof *rows);
  assert_non_null(rows);
  mpm_lidx k = 0;
  for (int p = 0; p < nparts; ++p)
    for (mpm_lidx i = 0; i < parts[p].n; ++i, ++k) {
      rows[k].id = parts[p].id[i];
      for (int d = 0; d < dim; ++d) rows[k].x[d] = parts[p].x[d * parts[p].n + i];
    }
  qsort(rows, (size_t)*total, sizeof *rows, by_id);
  return rows;
}

/* Seed on one rank and on every rank of a 2-way split along the directions cut[d] > 0
 * names; the merged parts must equal the single-rank set exactly. */
static void check_split(const mpm_region *r, int dim, const int *ncells, const int *cut) {
  const double lo[3] = {0, 0, 0};
  fake_grid one, part;
  fake_grid_init(&one, dim, lo, 0.1, ncells, NULL, NULL);
  seeded whole = seed(r, &one, 2, 77), parts[8];
  int nparts = 0;
  for (int c = 0; c < (1 << dim); ++c) {
    int coord[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1}, skip = 0;
    for (int d = 0; d < dim; ++d) skip |= coord[d] && !cut[d];
    if (skip) continue;
    fake_grid_init(&part, dim, lo, 0.1, ncells, cut, coord);
    parts[nparts++] = seed(r, &part, 2, 77);
  }
  mpm_lidx n1, n2;
  row *a = sorted_rows(&whole, 1, dim, &n1), *b = sorted_rows(parts, nparts, dim, &n2);
  assert_true(n1 > 0);
  assert_int_equal(n1, n2);
  assert_memory_equal(a, b, (size_t)n1 * sizeof *a); /* same ids, bit-identical positions */
  for (mpm_lidx k = 1; k < n1; ++k) assert_true(a[k - 1].id < a[k].id); /* unique */
  check_lattice(r, &one, 2, 77, &whole);
  free(a), free(b), seeded_free(&whole);
  for (int p = 0; p < nparts; ++p) seeded_free(&parts[p]);
}

static void test_rank_independence(void **state) {
  (void)state;
  char path[128], text[1024];
  snprintf(path, sizeof path, "%s/ell_split.xy", g_dir);
  write_file(path, g_ell);
  const char *names2[] = {"plate", "both", "hole"};
  for (int i = 0; i < 3; ++i) {
    mpm_region *r = region_from(g_sets, 2, names2[i]);
    check_split(r, 2, (int[]){30, 24}, (int[]){7, 0});
    check_split(r, 2, (int[]){30, 24}, (int[]){0, 11});
    check_split(r, 2, (int[]){30, 24}, (int[]){13, 9});
    mpm_region_destroy(&r);
  }
  snprintf(text, sizeof text,
           "[geometry.s]\ntype = sphere\ncenter = 0.7 0.8 0.6\nradius = 0.45\n"
           "[geometry.c]\ntype = cylinder\np0 = 0.3 0.4 0.2\np1 = 1.1 0.9 1.0\nradius = 0.2\n"
           "[geometry.p]\ntype = polygon\nfile = %s\nz = 0.2 0.7\n"
           "[geometry.u]\ntype = union\nof = s c p\n",
           path);
  mpm_region *r = region_from(text, 3, "u");
  check_split(r, 3, (int[]){16, 16, 12}, (int[]){5, 0, 0});
  check_split(r, 3, (int[]){16, 16, 12}, (int[]){0, 0, 6});
  check_split(r, 3, (int[]){16, 16, 12}, (int[]){9, 3, 7});
  mpm_region_destroy(&r);
}

/* The fake grids stand for what mpm_grid_new builds: on one rank, a real grid must seed
 * exactly what the fake one does. */
static void test_real_grid(void **state) {
  (void)state;
  const double lo[2] = {0, 0}, hi[2] = {3.0, 2.4};
  mpm_grid *g = NULL;
  assert_int_equal(
      mpm_grid_new(&g, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, (int[]){0, 0, 0}), 0);
  fake_grid f;
  fake_grid_init(&f, 2, lo, 0.1, (int[]){30, 24}, NULL, NULL);
  mpm_region *r = region_from(g_sets, 2, "nested");
  seeded real = {0, NULL, NULL}, fake = seed(r, &f, 3, 5);
  assert_int_equal(mpm_region_seed(r, g, 3, 5, &real.n, &real.x, &real.id), 0);
  assert_int_equal(mpm_region_seed_span(g, 3), mpm_region_seed_span(&f.g, 3));
  assert_int_equal(real.n, fake.n);
  assert_memory_equal(real.id, fake.id, (size_t)real.n * sizeof *real.id);
  assert_memory_equal(real.x, fake.x, (size_t)real.n * 2 * sizeof *real.x);
  seeded_free(&real), seeded_free(&fake);
  mpm_region_destroy(&r);
  mpm_grid_destroy(&g);
}

/* ------------------------------------------------------------- bad input --- */

/* Build region name with stderr sent to a file; return what was written (static buffer). */
static const char *build_capturing(const char *text, int dim, const char *name, int *rc) {
  static char out[8192];
  char log[128];
  snprintf(log, sizeof log, "%s/stderr.txt", g_dir);
  write_file(log, "");
  mpm_config *cfg = config_from(text);
  mpm_region *r = NULL;
  fflush(stderr);
  int saved = dup(2), fd = open(log, O_WRONLY | O_TRUNC);
  assert_true(saved >= 0 && fd >= 0);
  dup2(fd, 2);
  close(fd);
  *rc = mpm_region_from_config(&r, cfg, dim, name);
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  FILE *fp = fopen(log, "r");
  size_t n = fp ? fread(out, 1, sizeof out - 1, fp) : 0;
  if (fp) fclose(fp);
  out[n] = '\0';
  assert_null(r); /* nothing is returned on failure */
  mpm_config_destroy(&cfg);
  return out;
}

typedef struct bad_case {
  const char *why, *text, *name;
  int dim;
  const char *says; /* a piece of the message, or NULL */
} bad_case;

static void test_bad_configs(void **state) {
  (void)state;
  char two[128], junk[128], line[128], ok[128], texts[6][256];
  snprintf(two, sizeof two, "%s/two.xy", g_dir);
  snprintf(junk, sizeof junk, "%s/junk.xy", g_dir);
  snprintf(line, sizeof line, "%s/line.xy", g_dir);
  write_file(two, "0 0\n1 0\n0 0\n");
  write_file(junk, "# outline\n0 0\nx,y\n1 0\n1 1 1\n0 1\n");
  write_file(line, "0 0\n1 1\n2 2\n");
  snprintf(ok, sizeof ok, "%s/ok.xy", g_dir);
  write_file(ok, "0 0\n1 0\n0 1\n");
  snprintf(texts[5], sizeof texts[5], "[geometry.p]\ntype = polygon\nfile = %s\nz = 1 0\n", ok);
  snprintf(texts[0], sizeof texts[0], "[geometry.p]\ntype = polygon\nfile = %s\n", two);
  snprintf(texts[1], sizeof texts[1], "[geometry.p]\ntype = polygon\nfile = %s\n", junk);
  snprintf(texts[2], sizeof texts[2], "[geometry.p]\ntype = polygon\nfile = %s\n", line);
  snprintf(texts[3], sizeof texts[3], "[geometry.p]\ntype = polygon\nfile = %s\n", junk);
  snprintf(texts[4], sizeof texts[4], "[geometry.p]\ntype = polygon\nfile = %s\nz = 0 1\n", two);
  const bad_case cases[] = {
      {"no type", "[geometry.a]\nlo = 0 0\nhi = 1 1\n", "a", 2, "no type"},
      {"no such region", "[geometry.a]\ntype = box\nlo = 0 0\nhi = 1 1\n", "zz", 2, "zz"},
      {"unknown type", "[geometry.a]\ntype = blob\n", "a", 2, NULL},
      {"disk in 3-D", "[geometry.a]\ntype = disk\ncenter = 0 0 0\nradius = 1\n", "a", 3, "2-D"},
      {"sphere in 2-D", "[geometry.a]\ntype = sphere\ncenter = 0 0\nradius = 1\n", "a", 2, "3-D"},
      {"cylinder in 2-D", "[geometry.a]\ntype = cylinder\np0 = 0 0 0\np1 = 0 0 1\nradius = 1\n",
       "a", 2, "3-D"},
      {"box lo count", "[geometry.a]\ntype = box\nlo = 0 0 0\nhi = 1 1\n", "a", 2, "lower corner"},
      {"box lo = hi", "[geometry.a]\ntype = box\nlo = 0 1\nhi = 1 1\n", "a", 2, "above lo in y"},
      {"box hi missing", "[geometry.a]\ntype = box\nlo = 0 0\n", "a", 2, "`hi = ...`"},
      {"radius missing", "[geometry.a]\ntype = disk\ncenter = 0 0\n", "a", 2, "`radius = ...`"},
      {"radius < 0", "[geometry.a]\ntype = disk\ncenter = 0 0\nradius = -1\n", "a", 2, NULL},
      {"radius = 0", "[geometry.a]\ntype = sphere\ncenter = 0 0 0\nradius = 0\n", "a", 3, NULL},
      {"center count", "[geometry.a]\ntype = disk\ncenter = 0\nradius = 1\n", "a", 2,
       "needs 2 values"},
      {"cylinder p1 = p0", "[geometry.a]\ntype = cylinder\np0 = 1 2 3\np1 = 1 2 3\nradius = 1\n",
       "a", 3, "p0"},
      {"unused key", "[geometry.a]\ntype = box\nlo = 0 0\nhi = 1 1\nradius = 2\n", "a", 2,
       "not used by a box"},
      {"polygon 2 vertices", texts[0], "p", 2, "at least 3"},
      {"polygon bad lines", texts[1], "p", 2, "junk.xy:3:"},
      {"polygon no area", texts[2], "p", 2, "no area"},
      {"polygon 3-D without z", texts[3], "p", 3, "`z = ...`"},
      {"polygon z in 2-D", texts[4], "p", 2, "3-D"},
      {"polygon z reversed", texts[5], "p", 3, "below"},
      {"polygon file missing", "[geometry.p]\ntype = polygon\nfile = /nonexistent.xy\n", "p", 2,
       NULL},
      {"union unknown name", "[geometry.a]\ntype = union\nof = b\n", "a", 2, "'b'"},
      {"difference of one",
       "[geometry.a]\ntype = difference\nof = b\n"
       "[geometry.b]\ntype = box\nlo = 0 0\nhi = 1 1\n",
       "a", 2, "at least 2"},
      {"self cycle", "[geometry.a]\ntype = union\nof = a\n", "a", 2, "a -> a"},
      {"cycle",
       "[geometry.a]\ntype = union\nof = b\n[geometry.b]\ntype = difference\nof = c a\n"
       "[geometry.c]\ntype = box\nlo = 0 0\nhi = 1 1\n",
       "a", 2, "a -> b -> a"},
      {"deep cycle",
       "[geometry.a]\ntype = union\nof = b\n[geometry.b]\ntype = union\nof = c\n"
       "[geometry.c]\ntype = union\nof = b\n",
       "a", 2, "a -> b -> c -> b"},
      {"dimension 4", "[geometry.a]\ntype = box\nlo = 0 0\nhi = 1 1\n", "a", 4, NULL},
  };
  const int n = (int)(sizeof cases / sizeof cases[0]);
  for (int i = 0; i < n; ++i) {
    int rc = 0;
    const char *out = build_capturing(cases[i].text, cases[i].dim, cases[i].name, &rc);
    printf("  %-22s -> %s: %.*s\n", cases[i].why, mpm_error_string(rc), (int)strcspn(out, "\n"),
           out);
    assert_int_equal(rc, MPM_ERR_INPUT);
    if (cases[i].says && !strstr(out, cases[i].says)) fail_msg("message lacks '%s'", cases[i].says);
  }
}

/* A case with every region type passes schema validation: the keys a type does not use
 * are optional. */
static void test_schema_validates(void **state) {
  (void)state;
  char path[128], text[1024];
  snprintf(path, sizeof path, "%s/ell_valid.xy", g_dir);
  write_file(path, g_ell);
  snprintf(text, sizeof text,
           "[geometry.s]\ntype = sphere\ncenter = 0.7 0.8 0.6\nradius = 0.45\n"
           "[geometry.c]\ntype = cylinder\np0 = 0.3 0.4 0.2\np1 = 1.1 0.9 1.0\nradius = 0.2\n"
           "[geometry.p]\ntype = polygon\nfile = %s\nz = 0.2 0.7\n"
           "[geometry.b]\ntype = box\nlo = 0 0 0\nhi = 1 1 1\n"
           "[geometry.u]\ntype = union\nof = s c p\n"
           "[geometry.d]\ntype = difference\nof = b u\n",
           path);
  mpm_config *cfg = config_from(text);
  mpm_region *r = NULL;
  int rc_valid = mpm_config_validate(cfg), rc_build = mpm_region_from_config(&r, cfg, 3, "d");
  mpm_region_destroy(&r);
  mpm_config_destroy(&cfg);
  assert_int_equal(rc_build, 0);
  assert_int_equal(rc_valid, 0);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  if (!mkdtemp(g_dir)) {
    perror("mkdtemp");
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_count),        cmocka_unit_test(test_ids_and_span),
      cmocka_unit_test(test_disk_area),        cmocka_unit_test(test_region_volume),
      cmocka_unit_test(test_sphere_volume),    cmocka_unit_test(test_cylinder_volume),
      cmocka_unit_test(test_polygon_triangle), cmocka_unit_test(test_polygon_ell),
      cmocka_unit_test(test_union_difference), cmocka_unit_test(test_rank_independence),
      cmocka_unit_test(test_real_grid),        cmocka_unit_test(test_bad_configs),
      cmocka_unit_test(test_schema_validates),
  };
  int failed = cmocka_run_group_tests_name("geometry", tests, NULL, NULL);
  for (int i = 0; i < g_nfiles; ++i) unlink(g_files[i]);
  rmdir(g_dir);
  MPI_Finalize();
  return failed;
}
