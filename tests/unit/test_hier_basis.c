/* The composite basis of the refinement hierarchy (mpm_hier.h) on static hierarchies with a
 * re-entrant corner (hier_fixture.h): 2-D and 3-D two-level L shapes and a 2-D three-level
 * case.
 *
 *  (1) Partition of unity at 10,000 random points per case: sum w = 1 to 1e-14, sum grad w = 0
 *      to 1e-12 / h (h the point's level spacing), every weight >= 0, and every level holds at
 *      least 2 % of the points. Each weight is a sum of at most (levels) products of three
 *      1-D weights and a few two-scale factors, and the sums have at most 27 x levels terms of
 *      size <= 1: rounding stays near 1e-15; a wrong mask or two-scale weight is off by O(0.01).
 *  (2) C1 across the interface: along random lines (axis-parallel and oblique) every change of
 *      level is located by bisection; the weights and gradients of every active node just
 *      before and after it (1e-12 h apart) agree to 1e-10 (gradients times h). For a C1 basis
 *      the difference is |w'| 2e-12 h <= 4e-12 and |w''| 2e-12 h^2 <= 1e-11; a truncation
 *      that breaks continuity jumps by O(0.01). At each crossing, and at 1,000 random points,
 *      mpm_hier_eval's gradient matches a central difference of w with step 1e-7 h to 1e-6
 *      (relative to 1/h): truncation there is about step x the jump of w'' (1e-7), roundoff
 *      1e-16 / 1e-7 = 1e-9.
 *  (6) Adjointness of restriction and prolongation on every level pair: <R u, v> = <u, P v>
 *      over random u, v (u zero on the inactive nodes far from the region, which no deposit
 *      reaches: hier_near.h), to 1e-13 of the sum of |terms| (the same products summed in two
 *      orders); restriction zeroes exactly the inactive nodes near the region and leaves the
 *      others alone.
 *  (7) Bad input: every refusal of mpm_hier_new returns MPM_ERR_INPUT, creates nothing and
 *      names the box (by its index) or the level at fault; the buffer check is exact (a box
 *      that fits with buffer 2 fails with 3). A grid split over ranks is test_hier_ranks's (it
 *      needs two). A box grid refuses the halo exchanges.
 *  (8) Remembered levels (mpm_hier_levels): over 10,000 random points, then again with every
 *      third point moved to a fresh random point, the set shortened and then grown past its
 *      first size, every level equals mpm_hier_level_of's exactly (levels are integers); the
 *      moves must change some levels (else the check could not see a stale one); and after the
 *      set is compacted (mpm_hier_levels_keep), moved to new arrays and grown by appended
 *      points, the memory following it; six sets asked about
 *      in turn (more than the memory holds), some moved between their calls, answer alike. */
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

#include "hier_level_check.h"
#include "hier_fixture.h"
#include "hier_near.h"
#include "mpm_error.h"

#define NPOINTS 10000
#define MAXW    (27 * MPM_HIER_MAX_LEVELS)

static double spacing(const fixture *f, const double *x) {
  return f->h->level[mpm_hier_level_of(f->h, x)].grid->dx;
}

/* ---- (1) partition of unity --------------------------------------------------------------- */

static void check_pou(hier_case c) {
  fixture f;
  assert_int_equal(fixture_make(&f, c), 0);
  const int dim = f.grid->dim;
  uint64_t rng = 1000 + (uint64_t)c;
  int per_level[MPM_HIER_MAX_LEVELS] = {0};
  double ew = 0.0, edw = 0.0;
  mpm_hier_weight w[MAXW];
  for (int k = 0; k < NPOINTS; ++k) {
    double x[3];
    fixture_point(&f, &rng, k, x);
    per_level[mpm_hier_level_of(f.h, x)]++;
    hier_check_level(f.h, x);
    const int n = mpm_hier_eval(f.h, x, w, MAXW);
    assert_true(n > 0);
    double sw = 0.0, sdw[3] = {0, 0, 0};
    for (int q = 0; q < n; ++q) {
      assert_true(w[q].w >= 0.0);
      sw += w[q].w;
      for (int d = 0; d < dim; ++d) sdw[d] += w[q].dw[d];
    }
    ew = fmax(ew, fabs(sw - 1.0));
    for (int d = 0; d < dim; ++d) edw = fmax(edw, fabs(sdw[d]) * spacing(&f, x));
  }
  printf("PoU %-13s max |sum w - 1| = %.2e, max |sum grad w| h = %.2e, points per level:",
         hier_case_name[c], ew, edw);
  for (int l = 0; l < f.h->nlevels; ++l) printf(" %d", per_level[l]);
  printf("\n");
  assert_true(ew <= 1e-14);
  assert_true(edw <= 1e-12);
  for (int l = 0; l < f.h->nlevels; ++l) assert_true(per_level[l] >= NPOINTS / 50);
  fixture_free(&f);
}

static void test_pou(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) check_pou((hier_case)c);
}

/* ---- (2) C1 across the interface ---------------------------------------------------------- */

typedef struct line {
  double a[3], dir[3], len;
} line;

static void line_at(const line *s, double t, double *x) {
  for (int d = 0; d < 3; ++d) x[d] = s->a[d] + t * s->len * s->dir[d];
}

static int level_at(const fixture *f, const line *s, double t) {
  double x[3];
  line_at(s, t, x);
  return mpm_hier_level_of(f->h, x);
}

/* Weight (and gradient) of node (level, node) in w[n]; zero if absent. */
static const mpm_hier_weight *find(const mpm_hier_weight *w, int n, const mpm_hier_weight *key) {
  for (int q = 0; q < n; ++q)
    if (w[q].level == key->level && w[q].node == key->node) return &w[q];
  return NULL;
}

/* Largest difference between two weight sets, weights and gradients times h. */
static void jumps(const mpm_hier_weight *a, int na, const mpm_hier_weight *b, int nb, int dim,
                  double h, double *jw, double *jdw) {
  const mpm_hier_weight zero = {0};
  for (int pass = 0; pass < 2; ++pass) {
    const mpm_hier_weight *p = pass ? b : a, *o = pass ? a : b;
    const int np = pass ? nb : na, no = pass ? na : nb;
    for (int q = 0; q < np; ++q) {
      const mpm_hier_weight *m = find(o, no, &p[q]);
      if (!m) m = &zero;
      *jw = fmax(*jw, fabs(p[q].w - m->w));
      for (int d = 0; d < dim; ++d) *jdw = fmax(*jdw, fabs(p[q].dw[d] - m->dw[d]) * h);
    }
  }
}

/* Largest |central difference of w - grad w| h at x, step 1e-7 h. */
static double fd_error(const fixture *f, const double *x) {
  const int dim = f->grid->dim;
  const double h = spacing(f, x), step = 1e-7 * h;
  mpm_hier_weight w0[MAXW], wp[MAXW], wm[MAXW];
  const int n0 = mpm_hier_eval(f->h, x, w0, MAXW);
  double err = 0.0;
  for (int d = 0; d < dim; ++d) {
    double xp[3], xm[3];
    memcpy(xp, x, sizeof xp), memcpy(xm, x, sizeof xm);
    xp[d] += step, xm[d] -= step;
    const int np = mpm_hier_eval(f->h, xp, wp, MAXW), nm = mpm_hier_eval(f->h, xm, wm, MAXW);
    for (int q = 0; q < n0; ++q) {
      const mpm_hier_weight *a = find(wp, np, &w0[q]), *b = find(wm, nm, &w0[q]);
      const double fd = ((a ? a->w : 0.0) - (b ? b->w : 0.0)) / (xp[d] - xm[d]);
      err = fmax(err, fabs(fd - w0[q].dw[d]) * h);
    }
  }
  return err;
}

/* A random line across the refined hull: axis-parallel for k < 2 dim, oblique otherwise. */
static line random_line(const fixture *f, uint64_t *rng, int k) {
  const int dim = f->grid->dim;
  line s = {{0, 0, 0}, {0, 0, 0}, 0};
  double b[3] = {0, 0, 0}, n = 0;
  fixture_point(f, rng, 1, s.a);
  fixture_point(f, rng, 1, b);
  if (k % (2 * dim) < dim) { /* axis-parallel: from face to face of the hull */
    const int d = k % dim;
    s.a[d] = f->hull_lo[d], b[d] = f->hull_hi[d];
    for (int e = 0; e < dim; ++e)
      if (e != d) b[e] = s.a[e];
  }
  for (int d = 0; d < dim; ++d) n += (b[d] - s.a[d]) * (b[d] - s.a[d]);
  s.len = sqrt(n);
  for (int d = 0; d < dim; ++d) s.dir[d] = (b[d] - s.a[d]) / s.len;
  return s;
}

/* Bisect a change of level within [t0, t1]: returns the last t on t0's side. */
static double bisect(const fixture *f, const line *s, double t0, double t1) {
  const int l0 = level_at(f, s, t0);
  for (int it = 0; it < 200; ++it) {
    const double tm = 0.5 * (t0 + t1);
    if (tm == t0 || tm == t1) break;
    if (level_at(f, s, tm) == l0)
      t0 = tm;
    else
      t1 = tm;
  }
  return t0;
}

static void check_c1(hier_case c) {
  fixture f;
  assert_int_equal(fixture_make(&f, c), 0);
  const int dim = f.grid->dim, nscan = 400;
  uint64_t rng = 2000 + (uint64_t)c;
  double jw = 0.0, jdw = 0.0, efd = 0.0;
  int ncross = 0;
  mpm_hier_weight wm[MAXW], wp[MAXW];
  for (int k = 0; k < 60; ++k) {
    const line s = random_line(&f, &rng, k);
    for (int i = 0; i < nscan; ++i) {
      const double t0 = (double)i / nscan, t1 = (double)(i + 1) / nscan;
      if (level_at(&f, &s, t0) == level_at(&f, &s, t1)) continue;
      const double tc = bisect(&f, &s, t0, t1), dt = 1e-12 * f.grid->dx / s.len;
      double xm[3], xp[3], xc[3];
      line_at(&s, tc - dt, xm), line_at(&s, tc + 2 * dt, xp), line_at(&s, tc, xc);
      const int lm = mpm_hier_level_of(f.h, xm), lp = mpm_hier_level_of(f.h, xp);
      assert_int_not_equal(lm, lp); /* the two points straddle the interface */
      const double h = f.h->level[MPM_MAX(lm, lp)].grid->dx;
      const int nm = mpm_hier_eval(f.h, xm, wm, MAXW), np = mpm_hier_eval(f.h, xp, wp, MAXW);
      assert_true(nm > 0 && np > 0);
      jumps(wm, nm, wp, np, dim, h, &jw, &jdw);
      efd = fmax(efd, fd_error(&f, xc));
      ncross++;
    }
  }
  for (int k = 0; k < 1000; ++k) {
    double x[3];
    fixture_point(&f, &rng, k, x);
    efd = fmax(efd, fd_error(&f, x));
  }
  printf("C1  %-13s %d crossings: max jump of w = %.2e, of grad w h = %.2e; max |FD - grad| h "
         "= %.2e\n",
         hier_case_name[c], ncross, jw, jdw, efd);
  assert_true(ncross >= 60);
  assert_true(jw <= 1e-10);
  assert_true(jdw <= 1e-10);
  assert_true(efd <= 1e-6);
  fixture_free(&f);
}

static void test_c1(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) check_c1((hier_case)c);
}

/* ---- (6) adjointness ---------------------------------------------------------------------- */

static double *random_array(mpm_lidx n, uint64_t *rng) {
  double *a = malloc((size_t)n * sizeof *a);
  assert_non_null(a);
  for (mpm_lidx i = 0; i < n; ++i) a[i] = 2.0 * mpm_test_uniform(rng) - 1.0;
  return a;
}

static void check_adjoint(const fixture *f, int l, uint64_t *rng) {
  const mpm_grid *fg = f->h->level[l].grid, *cg = f->h->level[l - 1].grid;
  const unsigned char *act = f->h->level[l].active;
  double *u = random_array(fg->nnodes, rng), *u0 = malloc((size_t)fg->nnodes * sizeof *u0);
  double *v = random_array(cg->nnodes, rng), *pv = random_array(fg->nnodes, rng);
  double *pv0 = malloc((size_t)fg->nnodes * sizeof *pv0), *ru = calloc((size_t)cg->nnodes, 8);
  assert_non_null(u0), assert_non_null(pv0), assert_non_null(ru);
  /* No deposit reaches the inactive nodes far from the region (hier_near.h): they hold zero. */
  for (mpm_lidx j = 0; j < fg->nnodes; ++j)
    if (!hier_node_filled(f->h, l, j)) u[j] = 0.0;
  memcpy(u0, u, (size_t)fg->nnodes * sizeof *u), memcpy(pv0, pv, (size_t)fg->nnodes * sizeof *pv);
  mpm_hier_restrict_level(f->h, l, &u, &ru, 1);
  mpm_hier_prolong_level(f->h, l, (const double *const *)&v, &pv, 1);
  double lhs = 0, rhs = 0, scale = 0;
  for (mpm_lidx i = 0; i < cg->nnodes; ++i) lhs += ru[i] * v[i], scale += fabs(ru[i] * v[i]);
  for (mpm_lidx j = 0; j < fg->nnodes; ++j) {
    const int far = !hier_node_filled(f->h, l, j); /* (left as they were) */
    assert_true(act[j] || far ? u[j] == u0[j] && pv[j] == pv0[j] : u[j] == 0.0);
    if (!act[j] && !far) rhs += u0[j] * pv[j], scale += fabs(u0[j] * pv[j]);
  }
  printf("adjoint level %d-%d: <Ru,v> = %.15e, <u,Pv> = %.15e, |difference| / scale = %.2e\n", l,
         l - 1, lhs, rhs, fabs(lhs - rhs) / scale);
  assert_true(fabs(lhs - rhs) <= 1e-13 * scale);
  free(u), free(u0), free(v), free(pv), free(pv0), free(ru);
}

static void test_adjoint(void **state) {
  (void)state;
  uint64_t rng = 3000;
  for (int c = 0; c < HIER_NCASES; ++c) {
    fixture f;
    assert_int_equal(fixture_make(&f, (hier_case)c), 0);
    for (int l = 1; l < f.h->nlevels; ++l) check_adjoint(&f, l, &rng);
    fixture_free(&f);
  }
}

/* ---- (7) bad input ------------------------------------------------------------------------ */

/* mpm_hier_new must refuse: MPM_ERR_INPUT, no hierarchy, and a reason naming `names`. */
static void refused(mpm_grid *g, int nlev, const mpm_hier_box *b, int nbox, int buffer,
                    const char *names) {
  mpm_hier *h = (mpm_hier *)&h; /* not NULL: the call must reset it */
  char why[512] = "";
  const int rc = mpm_hier_new(&h, g, nlev, b, nbox, buffer, why, sizeof why);
  printf("refused (%s): %s\n", names, why);
  assert_int_equal(rc, MPM_ERR_INPUT);
  assert_null(h);
  assert_non_null(strstr(why, names));
}

static void test_bad_input(void **state) {
  (void)state;
  mpm_grid *g, *lin;
  const double lo[2] = {0, 0}, hi[2] = {2, 2};
  const int nproc[2] = {1, 1};
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc), 0);
  assert_int_equal(mpm_grid_new(&lin, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_LINEAR, nproc), 0);
  const mpm_hier_box ok = {1, {0.4, 0.4}, {1.6, 1.6}};
  refused(g, 0, &ok, 1, 1, "0 levels");
  refused(g, MPM_HIER_MAX_LEVELS + 1, &ok, 1, 1, "6 levels");
  refused(g, 2, &ok, 1, 0, "buffer of 0");
  refused(lin, 2, &ok, 1, 1, "quadratic");
  mpm_hier_box b[3] = {ok, ok, ok};
  b[1].level = 2;
  refused(g, 2, b, 2, 1, "box 1 has level 2");
  b[1].level = 0;
  refused(g, 2, b, 2, 1, "box 1 has level 0");
  b[1] = (mpm_hier_box){1, {0.5, 0.5}, {0.5, 1.0}};
  refused(g, 2, b, 2, 1, "box 1 (level 1) is empty along x");
  b[1] = (mpm_hier_box){1, {0.5, NAN}, {0.6, 1.0}};
  refused(g, 2, b, 2, 1, "box 1 (level 1) is empty along y");
  b[1] = (mpm_hier_box){1, {0.5, 1.0}, {0.6, 2.1}};
  refused(g, 2, b, 2, 1, "box 1 (level 1) spans [1, 2.1] along y, outside the domain");
  refused(g, 3, &ok, 1, 1, "level 2 has no box");
  /* Omega_1 = [0.35, 1.65]^2; a level-2 box from 0.45 leaves two level-1 spans (0.05). */
  b[1] = (mpm_hier_box){2, {0.45, 0.8}, {1.0, 1.2}};
  mpm_hier *h = NULL;
  char why[512];
  assert_int_equal(mpm_hier_new(&h, g, 3, b, 2, 2, why, sizeof why), 0);
  mpm_hier_destroy(&h);
  refused(g, 3, b, 2, 3, "box 1 (level 2) is not inside the region of level 1");
  b[2] = (mpm_hier_box){2, {1.5, 1.5}, {1.9, 1.9}};
  refused(g, 3, b, 3, 1, "box 2 (level 2) is not inside the region of level 1");
  mpm_grid_destroy(&g);
  mpm_grid_destroy(&lin);
}

/* A box grid has no communicator: the halo exchanges refuse it. */
static void test_box_grid(void **state) {
  (void)state;
  mpm_grid *g;
  const double o[2] = {-0.5, 0.25};
  const int blo[2] = {-3, 4}, bn[2] = {7, 5};
  assert_int_equal(mpm_grid_box_new(&g, 2, o, 0.05, MPM_SHAPE_QUADRATIC, blo, bn), 0);
  assert_int_equal(g->nnodes, 35);
  assert_int_equal(g->size, 1);
  assert_true(mpm_grid_node_is_owned(g, 0) && mpm_grid_node_is_owned(g, 34));
  assert_int_equal(mpm_grid_add_phase(g, "p", NULL), 0);
  double *f[1] = {g->phase[0].m_i};
  assert_int_equal(mpm_grid_halo_reverse(g, f, 1), MPM_ERR_INTERNAL);
  assert_int_equal(mpm_grid_halo_forward(g, f, 1), MPM_ERR_INTERNAL);
  mpm_grid_destroy(&g);
  assert_null(g);
}

/* ---- (8) remembered levels ------------------------------------------------------------- */

/* mpm_hier_levels over the first n points of x (component-major, stride NPOINTS) against
 * mpm_hier_level_of at each. */
static void check_levels(const fixture *f, double *const *x, mpm_lidx n) {
  const double *xs[3] = {x[0], x[1], x[2]};
  const unsigned char *lev = mpm_hier_levels(f->h, xs, n);
  assert_non_null(lev);
  for (mpm_lidx i = 0; i < n; ++i) {
    const double p[3] = {x[0][i], x[1][i], x[2][i]};
    assert_int_equal(lev[i], mpm_hier_level_of(f->h, p));
  }
}

static void test_levels(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) {
    fixture f;
    assert_int_equal(fixture_make(&f, (hier_case)c), 0);
    uint64_t rng = 8000 + (uint64_t)c;
    double *x[3];
    for (int d = 0; d < 3; ++d) x[d] = calloc(2 * NPOINTS, sizeof(double));
    for (int k = 0; k < 2 * NPOINTS; ++k) {
      double p[3];
      fixture_point(&f, &rng, k, p);
      for (int d = 0; d < 3; ++d) x[d][k] = p[d];
    }
    check_levels(&f, x, NPOINTS);
    /* Small moves, as a step makes them (up to 0.3 of the finest spacing): most points stay in
     * the box remembered with their level, some leave it within the level, and some change level;
     * every answer stays mpm_hier_level_of's. */
    const double hf = f.h->level[f.h->nlevels - 1].grid->dx;
    int changed = 0;
    for (int round = 0; round < 8; ++round) {
      for (int k = 0; k < NPOINTS; ++k) {
        const double q[3] = {x[0][k], x[1][k], x[2][k]};
        double p[3] = {0, 0, 0};
        for (int d = 0; d < f.grid->dim; ++d)
          p[d] = q[d] + 0.3 * hf * (2.0 * mpm_test_uniform(&rng) - 1.0);
        changed += mpm_hier_level_of(f.h, p) != mpm_hier_level_of(f.h, q);
        for (int d = 0; d < f.grid->dim; ++d) x[d][k] = p[d];
      }
      check_levels(&f, x, NPOINTS);
    }
    assert_true(changed > 0);
    int moved_level = 0;
    for (int k = 0; k < NPOINTS; k += 3) { /* a fresh point at index k */
      double p[3], q[3] = {x[0][k], x[1][k], x[2][k]};
      fixture_point(&f, &rng, k + 1, p);
      moved_level += mpm_hier_level_of(f.h, p) != mpm_hier_level_of(f.h, q);
      for (int d = 0; d < 3; ++d) x[d][k] = p[d];
    }
    assert_true(moved_level > NPOINTS / 30);
    check_levels(&f, x, NPOINTS);
    check_levels(&f, x, NPOINTS / 2);
    check_levels(&f, x, 2 * NPOINTS);
    /* Compacted (every fifth point dropped, as mpm_particles_edit keeps a set): the memory
     * follows the points (a kept level not moved with its point would be another's). */
    unsigned char *keep = malloc(2 * NPOINTS);
    mpm_lidx kept = 0;
    for (mpm_lidx i = 0; i < 2 * NPOINTS; ++i) {
      keep[i] = i % 5 != 2;
      for (int d = 0; d < 3 && keep[i]; ++d) x[d][kept] = x[d][i];
      kept += keep[i];
    }
    mpm_hier_levels_keep(f.h, x[0], x[0], keep, 2 * NPOINTS);
    check_levels(&f, x, kept);
    mpm_hier_levels_keep(f.h, x[0], x[0], keep, 2 * NPOINTS); /* (not the count held) */
    check_levels(&f, x, kept);
    /* Moved to new arrays (an edit's new block), compacted again and then grown by points
     * appended after the kept ones (a split's children), some kept points moved: the memory
     * follows the set to its new address, and every answer stays mpm_hier_level_of's. */
    double *z[3];
    for (int d = 0; d < 3; ++d) z[d] = calloc(2 * NPOINTS, sizeof(double));
    mpm_lidx nz = 0;
    for (mpm_lidx i = 0; i < kept; ++i) {
      keep[i] = i % 7 != 3;
      for (int d = 0; d < 3 && keep[i]; ++d) z[d][nz] = x[d][i];
      nz += keep[i];
    }
    mpm_hier_levels_keep(f.h, x[0], z[0], keep, kept);
    check_levels(&f, z, nz);
    for (int d = 0; d < 3; ++d) memcpy(x[d], z[d], sizeof(double) * (size_t)nz);
    for (mpm_lidx i = nz; i < 2 * nz && i < 2 * NPOINTS; ++i) { /* children, parents moved */
      double p[3];
      fixture_point(&f, &rng, (int)i + 1, p);
      for (int d = 0; d < 3; ++d) x[d][i] = p[d];
      if (i % 11 == 0)
        for (int d = 0; d < 3; ++d) x[d][i - nz] = p[d];
    }
    const mpm_lidx grown = MPM_MIN(2 * nz, 2 * NPOINTS);
    mpm_hier_levels_keep(f.h, z[0], x[0], NULL, nz);
    check_levels(&f, x, grown);
    mpm_hier_levels_keep(f.h, z[0], x[0], NULL, nz); /* (z is no longer remembered: no-op) */
    check_levels(&f, x, grown);
    for (int d = 0; d < 3; ++d) free(z[d]);
    kept = grown;
    free(keep);
    /* Several sets asked about in turn (a gas, a solid, stage positions): each is remembered by
     * its address, more sets than the memory holds evict the least recently used, and every
     * answer stays mpm_hier_level_of's, a set's points moved between its calls too. */
    enum { NSETS = 6 };
    double *y[NSETS][3];
    for (int s = 0; s < NSETS; ++s)
      for (int d = 0; d < 3; ++d) {
        y[s][d] = calloc(NPOINTS, sizeof(double));
        for (mpm_lidx i = 0; i < NPOINTS; ++i) y[s][d][i] = x[d][(i + 97 * s) % kept];
      }
    for (int round = 0; round < 3; ++round)
      for (int s = 0; s < NSETS; ++s) {
        if (round == 1 && s % 2) /* this set's points move between its calls */
          for (mpm_lidx i = 0; i < NPOINTS; i += 7) y[s][0][i] = y[(s + 1) % NSETS][0][i];
        check_levels(&f, y[s], NPOINTS - 13 * s);
        check_levels(&f, y[0], NPOINTS); /* one set asked again between the others */
      }
    for (int s = 0; s < NSETS; ++s)
      for (int d = 0; d < 3; ++d) free(y[s][d]);
    for (int d = 0; d < 3; ++d) free(x[d]);
    fixture_free(&f);
  }
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pou),      cmocka_unit_test(test_c1),
      cmocka_unit_test(test_adjoint),  cmocka_unit_test(test_bad_input),
      cmocka_unit_test(test_box_grid), cmocka_unit_test(test_levels),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
