/* The refinement hierarchy (mpm_hier.h) across periodic faces: levels whose regions touch, cross
 * or span a periodic axis, on one rank.
 *   BAND  2-D [0, 2] x [0, 1], dx = 0.1, periodic in y; level 1 the band x in [0.6, 1.4], all y
 *         (it spans the period; its box stores the whole period along y).
 *   WRAP  2-D [0, 2] x [0, 1], dx = 0.1, periodic in x and y; level 1 x in [-0.5, 0.5] (across
 *         the x faces), all y; level 2 x in [-0.2, 0.2], y in [0.3, 0.7] (across the x faces,
 *         inside the period along y: a level with a period along x only).
 *   BAND3 3-D [0, 1.2] x [0, 0.6]^2, dx = 0.1, periodic in y and z; level 1 x in [0.3, 0.9].
 *   WRAP4 2-D as WRAP with four levels: level 1 x in [-0.5, 0.5], all y; level 2 x in
 *         [-0.3, 0.3], y in [0.2, 0.8]; level 3 x in [-0.01, 0.1], y in [0.4, 0.6], whose region
 *         begins at level 2's span 1, wholly below the face x = 0 (its box begins at node 0: a
 *         level >= 3 must store the whole period there; it once did not, and wrote outside
 *         its box).
 *
 *  (1) Partition of unity at 10,000 random points per case (half over the domain, half within
 *      0.15 of a periodic face): sum w = 1 to 1e-14, sum grad w = 0 to 1e-12 / h, w >= 0, every
 *      level holds >= 2 % of the points (the tolerances of test_hier_basis: at most 27 x levels
 *      terms <= 1, each a product of a few exact factors; a wrong mask or fold is off by 1e-2).
 *  (2) Periodicity: mpm_hier_eval at x and at x shifted by a period along each periodic axis
 *      gives the same nodes and weights to 1e-14 (the shifted point is wrapped back: its
 *      position differs from x by the roundoff of x + L - L, 2e-16 L), times 0.025 / h where
 *      the finest spacing h is finer (the weights' slope grows as 1 / h: WRAP4, 2e-14).
 *  (3) Conservation: 20,000 random particles deposited and restricted: the active nodes that
 *      are not images (level 0: all nodes, its ghosts included, since no halo ran) hold the
 *      total mass to 1e-14 and momentum to 1e-14 of sum m |v| (summed in long double); every
 *      inactive node and every image of a finer level ends at exactly zero.
 *  (4) P2G = eval: single particles (unit mass) deposited, restricted, level 0's ghosts summed
 *      into their owners: the owned level-0 nodes and the finer non-image nodes equal eval's
 *      weights to 1e-15 (the same products in another order).
 *  (5) Reproduction: v affine along the non-periodic axes (constant along the periodic ones,
 *      so it is periodic) on level 0 and the active nodes, garbage (1e30) on the rest of the
 *      finer levels: prolongation gives the field on every node of every finer level it fills
 *      (hier_near.h: images included; the rest keep their garbage, which no particle reads),
 *      and G2P at random particles returns it with L = the slope, to 1e-12 of the
 *      field's scale (5). */
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
#include "hier_near.h"
#include "mpm_hier.h"
#include "mpm_random.h"

#define NPOINTS 10000
#define MAXW    (27 * MPM_HIER_MAX_LEVELS)

typedef enum { P_BAND, P_WRAP, P_BAND3, P_WRAP4, P_NCASES } pcase;
static const char *const g_name[P_NCASES] = {"2-D band", "2-D across x", "3-D band",
                                             "2-D 4 levels across x"};

typedef struct pfix {
  mpm_grid *grid;
  mpm_hier *h;
  int phase;
} pfix;

static void pfix_make(pfix *f, pcase c) {
  memset(f, 0, sizeof *f);
  const int dim = c == P_BAND3 ? 3 : 2, nproc[3] = {1, 1, 1};
  const double lo[3] = {0, 0, 0}, hi2[3] = {2, 1, 0}, hi3[3] = {1.2, 0.6, 0.6};
  const int per[P_NCASES][3] = {{0, 1, 0}, {1, 1, 0}, {0, 1, 1}, {1, 1, 0}};
  assert_int_equal(mpm_grid_new_periodic(&f->grid, MPI_COMM_SELF, dim, lo, dim == 3 ? hi3 : hi2,
                                         0.1, MPM_SHAPE_QUADRATIC, nproc, per[c]),
                   0);
  assert_int_equal(mpm_grid_add_phase(f->grid, "test", &f->phase), 0);
  mpm_hier_box b[3];
  int nbox = 1, nlev = 2;
  if (c == P_BAND) {
    b[0] = (mpm_hier_box){1, {0.6, 0.0}, {1.4, 1.0}};
  } else if (c == P_WRAP) {
    b[0] = (mpm_hier_box){1, {-0.5, 0.0}, {0.5, 1.0}};
    b[1] = (mpm_hier_box){2, {-0.2, 0.3}, {0.2, 0.7}};
    nbox = 2, nlev = 3;
  } else if (c == P_WRAP4) {
    b[0] = (mpm_hier_box){1, {-0.5, 0.0}, {0.5, 1.0}};
    b[1] = (mpm_hier_box){2, {-0.3, 0.2}, {0.3, 0.8}};
    b[2] = (mpm_hier_box){3, {-0.01, 0.4}, {0.1, 0.6}};
    nbox = 3, nlev = 4;
  } else {
    b[0] = (mpm_hier_box){1, {0.3, 0.0, 0.0}, {0.9, 0.6, 0.6}};
  }
  char why[256] = "";
  const int rc = mpm_hier_new(&f->h, f->grid, nlev, b, nbox, 1, why, sizeof why);
  if (rc) fprintf(stderr, "%s: %s\n", g_name[c], why);
  assert_int_equal(rc, 0);
  assert_true(f->h->wraps);
}

static void pfix_free(pfix *f) {
  mpm_hier_destroy(&f->h);
  mpm_grid_destroy(&f->grid);
}

/* Random point k: even k over the domain, odd k within 0.15 of a periodic face. */
static void pfix_point(const pfix *f, uint64_t *rng, int k, double *x) {
  const mpm_grid *g = f->grid;
  for (int d = 0; d < 3; ++d) x[d] = 0.0;
  for (int d = 0; d < g->dim; ++d) x[d] = g->lo[d] + (g->hi[d] - g->lo[d]) * mpm_test_uniform(rng);
  if (k % 2 == 0) return;
  for (int d = 0; d < g->dim; ++d)
    if (g->periodic[d]) {
      const double u = 0.3 * mpm_test_uniform(rng) - 0.15;
      x[d] = u < 0 ? g->hi[d] + u : g->lo[d] + u;
      return;
    }
}

static double spacing(const pfix *f, const double *x) {
  return f->h->level[mpm_hier_level_of(f->h, x)].grid->dx;
}

/* Is box node n of level l an image (levels >= 1 with a period)? */
static int is_image(const pfix *f, int l, mpm_lidx n) {
  return l > 0 && f->h->level[l].is_image && f->h->level[l].is_image[n];
}

/* ---- (1) partition of unity, (2) periodicity --------------------------------------------- */

static void check_pou(pcase c) {
  pfix f;
  pfix_make(&f, c);
  const int dim = f.grid->dim;
  uint64_t rng = 100 + (uint64_t)c;
  int per_level[MPM_HIER_MAX_LEVELS] = {0};
  double ew = 0.0, edw = 0.0, eper = 0.0;
  mpm_hier_weight w[MAXW], v[MAXW];
  for (int k = 0; k < NPOINTS; ++k) {
    double x[3];
    pfix_point(&f, &rng, k, x);
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
    for (int d = 0; d < dim; ++d) {
      if (!f.grid->periodic[d]) continue;
      double y[3] = {x[0], x[1], x[2]};
      y[d] +=
          (x[d] < 0.5 * (f.grid->lo[d] + f.grid->hi[d]) ? 1 : -1) * (f.grid->hi[d] - f.grid->lo[d]);
      const int m = mpm_hier_eval(f.h, y, v, MAXW);
      assert_int_equal(m, n);
      for (int q = 0; q < n; ++q) {
        int found = 0;
        for (int r = 0; r < m && !found; ++r)
          if (v[r].level == w[q].level && v[r].node == w[q].node)
            found = 1, eper = fmax(eper, fabs(v[r].w - w[q].w));
        assert_true(found);
      }
    }
  }
  printf("PoU %-13s max |sum w - 1| = %.2e, max |sum grad w| h = %.2e, shifted by a period "
         "%.2e, points per level:",
         g_name[c], ew, edw, eper);
  for (int l = 0; l < f.h->nlevels; ++l) printf(" %d", per_level[l]);
  printf("\n");
  assert_true(ew <= 1e-14);
  assert_true(edw <= 1e-12);
  /* The shifted point's roundoff moves the weights by their slope, which grows as 1 / h: the
   * bound of the cases whose finest spacing is 0.025, scaled by 0.025 over this finest one. */
  const double h_fine = f.h->level[f.h->nlevels - 1].grid->dx;
  assert_true(eper <= 1e-14 * fmax(1.0, 0.025 / h_fine));
  for (int l = 0; l < f.h->nlevels; ++l) assert_true(per_level[l] >= NPOINTS / 50);
  pfix_free(&f);
}

static void test_pou(void **state) {
  (void)state;
  for (int c = 0; c < P_NCASES; ++c) check_pou((pcase)c);
}

/* ---- (3) conservation, (4) P2G = eval ----------------------------------------------------- */

typedef struct pset {
  mpm_lidx n;
  double *x[3], *v[3], *m;
} pset;

static double *alloc0(size_t n) {
  double *a = calloc(n ? n : 1, sizeof *a);
  assert_non_null(a);
  return a;
}

static void pset_make(pset *p, const pfix *f, mpm_lidx n, uint64_t seed) {
  memset(p, 0, sizeof *p);
  p->n = n;
  for (int d = 0; d < 3; ++d) p->x[d] = alloc0((size_t)n), p->v[d] = alloc0((size_t)n);
  p->m = alloc0((size_t)n);
  uint64_t rng = seed;
  for (mpm_lidx i = 0; i < n; ++i) {
    double x[3];
    pfix_point(f, &rng, (int)i, x);
    for (int d = 0; d < f->grid->dim; ++d)
      p->x[d][i] = x[d], p->v[d][i] = 2 * mpm_test_uniform(&rng) - 1;
    p->m[i] = 0.5 + mpm_test_uniform(&rng);
  }
}

static void pset_free(pset *p) {
  for (int d = 0; d < 3; ++d) free(p->x[d]), free(p->v[d]);
  free(p->m);
}

static void check_conservation(pcase c) {
  pfix f;
  pfix_make(&f, c);
  const int dim = f.grid->dim, n = 20000;
  pset p;
  pset_make(&p, &f, n, 400 + (uint64_t)c);
  mpm_hier_phase_zero(f.h, f.phase);
  mpm_p2g_args a = {.n = n, .m = p.m};
  for (int d = 0; d < dim; ++d) a.x[d] = p.x[d], a.v[d] = p.v[d];
  assert_int_equal(mpm_hier_p2g(f.h, f.phase, &a), 0);
  mpm_hier_restrict(f.h, f.phase);
  long double M = 0, P[3] = {0}, m = 0, mv[3] = {0}, scale = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    M += p.m[i];
    for (int d = 0; d < dim; ++d)
      P[d] += (long double)p.m[i] * p.v[d][i], scale += p.m[i] * fabs(p.v[d][i]);
  }
  int stray = 0;
  for (int l = 0; l < f.h->nlevels; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f.phase];
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      if (!f.h->level[l].active[i] || is_image(&f, l, i)) {
        stray |= ph->m_i[i] != 0.0;
        continue;
      }
      m += ph->m_i[i];
      for (int d = 0; d < dim; ++d) mv[d] += ph->mv_i[d][i];
    }
  }
  double em = (double)(fabsl(m - M) / M), ep = 0;
  for (int d = 0; d < dim; ++d) ep = fmax(ep, (double)(fabsl(mv[d] - P[d]) / scale));
  printf("conservation %-13s mass %.2e, momentum %.2e\n", g_name[c], em, ep);
  assert_false(stray);
  assert_true(em <= 1e-14);
  assert_true(ep <= 1e-14);
  pset_free(&p);
  pfix_free(&f);
}

static void test_conservation(void **state) {
  (void)state;
  for (int c = 0; c < P_NCASES; ++c) check_conservation((pcase)c);
}

/* Deposit particle i alone (unit mass), restrict, fold level 0; compare with eval. */
static void compare_one(const pfix *f, const pset *p, mpm_lidx i, double *ew) {
  const int dim = f->grid->dim;
  const double one = 1.0, zero[3] = {0, 0, 0};
  mpm_p2g_args a = {.n = 1, .m = &one};
  double x[3] = {0, 0, 0};
  for (int d = 0; d < dim; ++d) a.x[d] = &p->x[d][i], a.v[d] = &zero[d], x[d] = p->x[d][i];
  mpm_hier_phase_zero(f->h, f->phase);
  assert_int_equal(mpm_hier_p2g(f->h, f->phase, &a), 0);
  mpm_hier_restrict(f->h, f->phase);
  double *m0 = f->grid->phase[f->phase].m_i;
  assert_int_equal(mpm_grid_halo_reverse(f->grid, &m0, 1), 0);
  mpm_hier_weight w[MAXW];
  const int n = mpm_hier_eval(f->h, x, w, MAXW);
  assert_true(n > 0);
  for (int q = 0; q < n; ++q) {
    if (w[q].level == 0) assert_true(mpm_grid_node_is_owned(f->grid, w[q].node));
    f->h->level[w[q].level].grid->phase[f->phase].m_i[w[q].node] -= w[q].w;
  }
  for (int l = 0; l < f->h->nlevels; ++l) {
    const mpm_grid *g = f->h->level[l].grid;
    for (mpm_lidx k = 0; k < g->nnodes; ++k)
      if (l ? !is_image(f, l, k) : mpm_grid_node_is_owned(g, k))
        *ew = fmax(*ew, fabs(g->phase[f->phase].m_i[k]));
  }
}

static void test_p2g_is_eval(void **state) {
  (void)state;
  for (int c = 0; c < P_NCASES; ++c) {
    pfix f;
    pfix_make(&f, (pcase)c);
    pset p;
    pset_make(&p, &f, 300, 500 + (uint64_t)c);
    double ew = 0;
    for (mpm_lidx i = 0; i < p.n; ++i) compare_one(&f, &p, i, &ew);
    printf("P2G vs eval %-13s max |m_i - w| = %.2e\n", g_name[c], ew);
    assert_true(ew <= 1e-15);
    pset_free(&p);
    pfix_free(&f);
  }
}

/* ---- (5) reproduction --------------------------------------------------------------------- */

static const double g_v0[3] = {0.7, -1.3, 0.4}, g_s[3] = {1.1, -0.6, 0.3};

/* v_r = v0_r + s_r x along the first non-periodic axis (none: constant). */
static double field(const pfix *f, int r, const double *x, double *slope_axis) {
  for (int d = 0; d < f->grid->dim; ++d)
    if (!f->grid->periodic[d]) {
      if (slope_axis) *slope_axis = d;
      return g_v0[r] + g_s[r] * x[d];
    }
  if (slope_axis) *slope_axis = -1;
  return g_v0[r];
}

static void node_x(const mpm_grid *g, mpm_lidx l, double *x) {
  for (int d = 0; d < 3; ++d) {
    x[d] = d < g->dim ? g->lo[d] + (g->box_lo[d] + (int)(l % g->box_n[d])) * g->dx : 0.0;
    l /= g->box_n[d];
  }
}

static void check_reproduction(pcase c) {
  pfix f;
  pfix_make(&f, c);
  const int dim = f.grid->dim, n = 5000;
  for (int l = 0; l < f.h->nlevels; ++l) {
    mpm_grid *g = f.h->level[l].grid;
    mpm_grid_phase *ph = &g->phase[f.phase];
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      double x[3];
      node_x(g, i, x);
      const int set = l == 0 || (f.h->level[l].active[i] && !is_image(&f, l, i));
      for (int d = 0; d < dim; ++d)
        ph->v_i[d][i] = ph->a_i[d][i] = set ? field(&f, d, x, NULL) : 1e30;
    }
  }
  mpm_hier_prolong(f.h, f.phase);
  double ep = 0, eg = 0, eL = 0;
  for (int l = 1; l < f.h->nlevels; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      if (!hier_node_filled(f.h, l, i)) continue;
      double x[3];
      node_x(g, i, x);
      for (int d = 0; d < dim; ++d)
        ep = fmax(ep, fabs(g->phase[f.phase].v_i[d][i] - field(&f, d, x, NULL)));
    }
  }
  pset p;
  pset_make(&p, &f, n, 600 + (uint64_t)c);
  double *vo[3] = {NULL}, *ao[3] = {NULL}, *L = alloc0((size_t)(9 * n));
  mpm_g2p_args a = {.n = n, .L_out = L};
  for (int d = 0; d < dim; ++d) {
    vo[d] = alloc0(n), ao[d] = alloc0(n);
    a.x[d] = p.x[d], a.v_out[d] = vo[d], a.a_out[d] = ao[d];
  }
  assert_int_equal(mpm_hier_g2p(f.h, f.phase, &a, NULL), 0);
  for (mpm_lidx i = 0; i < n; ++i) {
    double x[3] = {p.x[0][i], p.x[1][i], dim == 3 ? p.x[2][i] : 0}, axis;
    const double h = spacing(&f, x);
    for (int r = 0; r < dim; ++r) {
      eg = fmax(eg, fabs(vo[r][i] - field(&f, r, x, &axis)));
      for (int e = 0; e < dim; ++e) {
        const double want = (int)axis == e ? g_s[r] : 0.0;
        eL = fmax(eL, fabs(L[(size_t)(r * dim + e) * n + i] - want) * h);
      }
    }
  }
  printf("reproduction %-13s prolonged nodes %.2e, G2P v %.2e, L (times h) %.2e\n", g_name[c], ep,
         eg, eL);
  assert_true(ep <= 5e-12);
  assert_true(eg <= 5e-12);
  assert_true(eL <= 5e-12);
  for (int d = 0; d < dim; ++d) free(vo[d]), free(ao[d]);
  free(L);
  pset_free(&p);
  pfix_free(&f);
}

static void test_reproduction(void **state) {
  (void)state;
  for (int c = 0; c < P_NCASES; ++c) check_reproduction((pcase)c);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pou),
      cmocka_unit_test(test_conservation),
      cmocka_unit_test(test_p2g_is_eval),
      cmocka_unit_test(test_reproduction),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
