/* Composite P2G, restriction, prolongation, G2P and the nodal solve of the refinement
 * hierarchy (mpm_hier.h) on the hierarchies of hier_fixture.h (2-D and 3-D L shapes, a 2-D
 * three-level case).
 *
 *  (3) Conservation: random particles on every level (mass, velocity, APIC C, stress, gravity,
 *      mass gradient) deposited and restricted: the active nodes of all levels hold the total
 *      mass to 1e-14 relative and the total momentum to 1e-14 of sum m (|v| + |C| dx); the
 *      total force equals sum m g, and the mass gradients sum to zero, to 1e-13 of the scale of
 *      their terms (sum |V sigma| / h + sum m |g|). Each is a sum of products that add to the
 *      exact total (partition of unity and linear reproduction); the test sums in long double,
 *      so only the deposit's own rounding, about 1e-16 per term, remains. Every inactive node
 *      ends at exactly zero, and level 0's inactive nodes (whose support lies under level 1)
 *      receive nothing at all, before restriction or after: a level-0 particle lies outside
 *      Omega_1, so its stencil never reaches them, and what finer levels restrict lands only on
 *      nodes whose support leaves Omega_1.
 *  (4) P2G weights are mpm_hier_eval's: one particle at a time (unit mass), the deposited mass
 *      and mass gradient at every node of every level equal the composite weight and gradient
 *      to 1e-15 (gradients times h): the same products in another order.
 *  (5) Affine reproduction: with v = v0 + A x (and a, and a nodal scalar, affine) on level 0
 *      and the active nodes of finer levels, prolongation reproduces the field on every
 *      inactive node it fills (hier_near.h; garbage, 1e30, stays on the others, far from the
 *      region, which no particle reads), and G2P returns v_p = v0 + A x_p, a_p, s_p, L_p = A and
 * C_p = A on every level, even with garbage (1e30) on level 0's inactive nodes (no particle reads
 * them). Tolerance 1e-12 of the field's scale (|v0| + |A| |x|max), and for L and C of that scale
 *      divided by the level spacing (the size of the terms they sum).
 *  (8) The nodal solve: on one level mpm_hier_phase_update equals mpm_grid_phase_update bit
 *      for bit (with and without the light-node rule); on several levels the largest nodal mass
 *      is taken over all of them.
 * The cost of the composite P2G and G2P against the plain kernel is printed, not asserted. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>
#include <math.h>
#include <mpi.h>

#include "hier_fixture.h"
#include "hier_near.h"
#include "mpm_error.h"
#include "mpm_module.h"

#define MAXW (27 * MPM_HIER_MAX_LEVELS)

static const double g_v0[3] = {0.7, -1.3, 0.4}, g_a0[3] = {-0.2, 0.5, 1.1};
static const double g_A[3][3] = {{0.3, -1.1, 0.6}, {0.9, 0.2, -0.4}, {-0.5, 0.8, 1.2}};
static const double g_grav[3] = {0.3, -9.8, 0.5};

typedef struct pset {
  mpm_lidx n;
  double *x[3], *v[3], *m, *C, *vsig;
} pset;

static double *alloc0(size_t n) {
  double *a = calloc(n ? n : 1, sizeof *a);
  assert_non_null(a);
  return a;
}

static void pset_make(pset *p, const fixture *f, mpm_lidx n, uint64_t seed) {
  const int dim = f->grid->dim;
  memset(p, 0, sizeof *p);
  p->n = n;
  for (int d = 0; d < 3; ++d) p->x[d] = alloc0((size_t)n), p->v[d] = alloc0((size_t)n);
  p->m = alloc0((size_t)n), p->C = alloc0((size_t)(9 * n)), p->vsig = alloc0((size_t)(9 * n));
  uint64_t rng = seed;
  for (mpm_lidx i = 0; i < n; ++i) {
    double x[3];
    fixture_point(f, &rng, (int)i, x);
    for (int d = 0; d < dim; ++d) p->x[d][i] = x[d], p->v[d][i] = 2 * mpm_test_uniform(&rng) - 1;
    p->m[i] = 0.5 + mpm_test_uniform(&rng);
    for (int c = 0; c < dim * dim; ++c) {
      p->C[(size_t)c * n + i] = 2 * mpm_test_uniform(&rng) - 1;
      p->vsig[(size_t)c * n + i] = 1e-3 * (2 * mpm_test_uniform(&rng) - 1);
    }
  }
}

static void pset_free(pset *p) {
  for (int d = 0; d < 3; ++d) free(p->x[d]), free(p->v[d]);
  free(p->m), free(p->C), free(p->vsig);
}

static mpm_p2g_args p2g_args(const pset *p, int dim) {
  mpm_p2g_args a = {.n = p->n, .m = p->m, .C = p->C, .vsig = p->vsig};
  for (int d = 0; d < dim; ++d) a.x[d] = p->x[d], a.v[d] = p->v[d], a.gravity[d] = g_grav[d];
  return a;
}

/* ---- (3) conservation --------------------------------------------------------------------- */

/* Does any inactive node of level l hold a nonzero deposit (only level 0 when zero_only)? */
static int inactive_hold(const fixture *f, int l) {
  const mpm_grid *g = f->h->level[l].grid;
  const mpm_grid_phase *ph = &g->phase[f->phase];
  for (mpm_lidx i = 0; i < g->nnodes; ++i) {
    if (f->h->level[l].active[i]) continue;
    int any = ph->m_i[i] != 0.0;
    for (int d = 0; d < g->dim; ++d)
      any |= ph->mv_i[d][i] != 0.0 || ph->f_i[d][i] != 0.0 || ph->normal_i[d][i] != 0.0;
    if (any) return 1;
  }
  return 0;
}

/* Sums over the active nodes of all levels: mass, momentum, force, mass gradient. */
static void active_sums(const fixture *f, long double *m, long double *mv, long double *fr,
                        long double *nr) {
  const int dim = f->grid->dim;
  *m = 0;
  for (int d = 0; d < dim; ++d) mv[d] = fr[d] = nr[d] = 0;
  for (int l = 0; l < f->h->nlevels; ++l) {
    const mpm_grid *g = f->h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f->phase];
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      if (!f->h->level[l].active[i]) continue;
      *m += ph->m_i[i];
      for (int d = 0; d < dim; ++d)
        mv[d] += ph->mv_i[d][i], fr[d] += ph->f_i[d][i], nr[d] += ph->normal_i[d][i];
    }
  }
}

static void check_conservation(hier_case c) {
  fixture f;
  assert_int_equal(fixture_make(&f, c), 0);
  const int dim = f.grid->dim, n = 20000;
  pset p;
  pset_make(&p, &f, n, 4000 + (uint64_t)c);
  f.grid->phase[f.phase].normals = 1;
  mpm_hier_phase_zero(f.h, f.phase);
  const mpm_p2g_args a = p2g_args(&p, dim);
  assert_int_equal(mpm_hier_p2g(f.h, f.phase, &a), 0);
  assert_false(inactive_hold(&f, 0));
  mpm_hier_restrict(f.h, f.phase);
  for (int l = 0; l < f.h->nlevels; ++l) assert_false(inactive_hold(&f, l));
  long double M = 0, P[3] = {0}, G[3] = {0}, mscale = 0, pscale = 0, fscale = 0;
  for (mpm_lidx i = 0; i < n; ++i) {
    double x[3] = {p.x[0][i], p.x[1][i], dim == 3 ? p.x[2][i] : 0}, cn = 0, sn = 0;
    const double h = f.h->level[mpm_hier_level_of(f.h, x)].grid->dx;
    M += p.m[i], mscale += p.m[i];
    for (int k = 0; k < dim * dim; ++k)
      cn += fabs(p.C[(size_t)k * n + i]), sn += fabs(p.vsig[(size_t)k * n + i]);
    for (int d = 0; d < dim; ++d) {
      P[d] += (long double)p.m[i] * p.v[d][i], G[d] += (long double)p.m[i] * g_grav[d];
      pscale += p.m[i] * (fabs(p.v[d][i]) + cn * f.grid->dx);
      fscale += p.m[i] * fabs(g_grav[d]) + sn / h;
    }
  }
  long double m, mv[3], fr[3], nr[3];
  active_sums(&f, &m, mv, fr, nr);
  double em = fabsl(m - M) / mscale, ep = 0, ef = 0, en = 0;
  for (int d = 0; d < dim; ++d) {
    ep = fmax(ep, (double)(fabsl(mv[d] - P[d]) / pscale));
    ef = fmax(ef, (double)(fabsl(fr[d] - G[d]) / fscale));
    en = fmax(en, (double)(fabsl(nr[d]) / fscale));
  }
  printf("conservation %-13s mass %.2e, momentum %.2e, force %.2e, mass gradient %.2e\n",
         hier_case_name[c], em, ep, ef, en);
  assert_true(em <= 1e-14);
  assert_true(ep <= 1e-14);
  assert_true(ef <= 1e-13);
  assert_true(en <= 1e-13);
  pset_free(&p);
  fixture_free(&f);
}

static void test_conservation(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) check_conservation((hier_case)c);
}

/* ---- (4) P2G weights = mpm_hier_eval ------------------------------------------------------ */

/* Deposit particle i alone (unit mass, at rest) and compare every node with eval's weights. */
static void compare_one(const fixture *f, const pset *p, mpm_lidx i, double *ew, double *edw) {
  const int dim = f->grid->dim;
  const double one = 1.0, zero[3] = {0, 0, 0};
  mpm_p2g_args a = {.n = 1, .m = &one};
  double x[3] = {0, 0, 0};
  for (int d = 0; d < dim; ++d) a.x[d] = &p->x[d][i], a.v[d] = &zero[d], x[d] = p->x[d][i];
  mpm_hier_phase_zero(f->h, f->phase);
  assert_int_equal(mpm_hier_p2g(f->h, f->phase, &a), 0);
  mpm_hier_restrict(f->h, f->phase);
  mpm_hier_weight w[MAXW];
  const int n = mpm_hier_eval(f->h, x, w, MAXW);
  assert_true(n > 0);
  for (int q = 0; q < n; ++q) { /* subtract eval's weights: every node must end at zero */
    mpm_grid_phase *ph = &f->h->level[w[q].level].grid->phase[f->phase];
    ph->m_i[w[q].node] -= w[q].w;
    for (int d = 0; d < dim; ++d) ph->normal_i[d][w[q].node] -= w[q].dw[d];
  }
  for (int l = 0; l < f->h->nlevels; ++l) {
    const mpm_grid *g = f->h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f->phase];
    for (mpm_lidx k = 0; k < g->nnodes; ++k) {
      *ew = fmax(*ew, fabs(ph->m_i[k]));
      for (int d = 0; d < dim; ++d) *edw = fmax(*edw, fabs(ph->normal_i[d][k]) * g->dx);
    }
  }
}

static void test_p2g_is_eval(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) {
    fixture f;
    assert_int_equal(fixture_make(&f, (hier_case)c), 0);
    pset p;
    pset_make(&p, &f, 300, 5000 + (uint64_t)c);
    f.grid->phase[f.phase].normals = 1;
    double ew = 0, edw = 0;
    for (mpm_lidx i = 0; i < p.n; ++i) compare_one(&f, &p, i, &ew, &edw);
    printf("P2G vs eval %-13s max |m_i - w| = %.2e, max |grad m_i - grad w| h = %.2e\n",
           hier_case_name[c], ew, edw);
    assert_true(ew <= 1e-15);
    assert_true(edw <= 1e-15);
    pset_free(&p);
    fixture_free(&f);
  }
}

/* ---- (5) affine reproduction -------------------------------------------------------------- */

static double affine_v(int dim, int r, const double *x, const double *v0) {
  double v = v0[r];
  for (int c = 0; c < dim; ++c) v += g_A[r][c] * x[c];
  return v;
}

/* Nodal scalar 1 + 2x - y (+ z/2). */
static double affine_s(const double *x) {
  return 1.0 + 2.0 * x[0] - x[1] + 0.5 * x[2];
}

/* Set v, a and the scalar s[l] affine on the nodes of level l (inactive ones too when all);
 * garbage (1e30) on the others. */
static void set_affine(const fixture *f, int l, int all, double *s) {
  mpm_grid *g = f->h->level[l].grid;
  mpm_grid_phase *ph = &g->phase[f->phase];
  for (mpm_lidx i = 0; i < g->nnodes; ++i) {
    double x[3] = {0, 0, 0};
    for (int d = 0; d < g->dim; ++d) x[d] = fixture_node_x(f, l, i, d);
    const int set = all || f->h->level[l].active[i];
    for (int d = 0; d < g->dim; ++d) {
      ph->v_i[d][i] = set ? affine_v(g->dim, d, x, g_v0) : 1e30;
      ph->a_i[d][i] = set ? affine_v(g->dim, d, x, g_a0) : 1e30;
    }
    s[i] = set ? affine_s(x) : 1e30;
  }
}

/* Largest error of the prolonged field on the inactive nodes of finer levels. */
static double prolonged_error(const fixture *f, double *const *s) {
  double e = 0;
  for (int l = 1; l < f->h->nlevels; ++l) {
    const mpm_grid *g = f->h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f->phase];
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      if (!hier_node_filled(f->h, l, i)) continue;
      double x[3] = {0, 0, 0};
      for (int d = 0; d < g->dim; ++d) x[d] = fixture_node_x(f, l, i, d);
      e = fmax(e, fabs(s[l][i] - affine_s(x)));
      for (int d = 0; d < g->dim; ++d)
        e = fmax(e, fmax(fabs(ph->v_i[d][i] - affine_v(g->dim, d, x, g_v0)),
                         fabs(ph->a_i[d][i] - affine_v(g->dim, d, x, g_a0))));
    }
  }
  return e;
}

/* Affine fields on every level (level 0's inactive nodes affine when all0, else garbage). */
static void affine_fields(const fixture *f, int all0, double *const *s) {
  set_affine(f, 0, all0, s[0]);
  for (int l = 1; l < f->h->nlevels; ++l) set_affine(f, l, 0, s[l]);
  mpm_hier_prolong(f->h, f->phase);
  for (int l = 1; l < f->h->nlevels; ++l)
    mpm_hier_prolong_level(f->h, l, (const double *const *)&s[l - 1], &s[l], 1);
}

typedef struct g2p_out {
  double *v[3], *a[3], *L, *C, *s;
} g2p_out;

/* Errors of G2P against the affine field: e[0] for v, a, s; e[1] for L and C times h. */
static void g2p_errors(const fixture *f, const pset *p, const g2p_out *o, double *e) {
  const int dim = f->grid->dim;
  const size_t n = (size_t)p->n;
  for (size_t i = 0; i < n; ++i) {
    double x[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) x[d] = p->x[d][i];
    const double h = f->h->level[mpm_hier_level_of(f->h, x)].grid->dx;
    e[0] = fmax(e[0], fabs(o->s[i] - affine_s(x)));
    for (int r = 0; r < dim; ++r) {
      e[0] = fmax(e[0], fabs(o->v[r][i] - affine_v(dim, r, x, g_v0)));
      e[0] = fmax(e[0], fabs(o->a[r][i] - affine_v(dim, r, x, g_a0)));
      for (int c = 0; c < dim; ++c) {
        const size_t k = (size_t)(r * dim + c) * n + i;
        e[1] = fmax(e[1], fmax(fabs(o->L[k] - g_A[r][c]), fabs(o->C[k] - g_A[r][c])) * h);
      }
    }
  }
}

static void check_affine(hier_case c) {
  fixture f;
  assert_int_equal(fixture_make(&f, c), 0);
  const int dim = f.grid->dim, n = 5000;
  double *s[MPM_HIER_MAX_LEVELS] = {NULL};
  for (int l = 0; l < f.h->nlevels; ++l) s[l] = alloc0((size_t)f.h->level[l].grid->nnodes);
  const double scale = 5.0; /* the largest |field|: the scalar's 1 + 2x - y at x = 2, y = 0 */
  affine_fields(&f, 1, s);
  const double ep = prolonged_error(&f, s);
  affine_fields(&f, 0, s);
  pset p;
  pset_make(&p, &f, n, 6000 + (uint64_t)c);
  g2p_out o = {.L = alloc0((size_t)(9 * n)), .C = alloc0((size_t)(9 * n)), .s = alloc0(n)};
  mpm_g2p_args a = {.n = n, .L_out = o.L, .C_out = o.C, .nscalar = 1, .s_out = {o.s}};
  a.s_i[0] = s[0];
  mpm_hier_scalars hs = {{{NULL}}};
  for (int l = 0; l < f.h->nlevels; ++l) hs.s_i[l][0] = s[l];
  for (int d = 0; d < dim; ++d) {
    o.v[d] = alloc0(n), o.a[d] = alloc0(n);
    a.x[d] = p.x[d], a.v_out[d] = o.v[d], a.a_out[d] = o.a[d];
  }
  assert_int_equal(mpm_hier_g2p(f.h, f.phase, &a, &hs), 0);
  double e[2] = {0, 0};
  g2p_errors(&f, &p, &o, e);
  printf("affine %-13s prolonged nodes %.2e, G2P v/a/s %.2e, G2P L and C (times h) %.2e "
         "(scale %.0f)\n",
         hier_case_name[c], ep, e[0], e[1], scale);
  assert_true(ep <= 1e-12 * scale);
  assert_true(e[0] <= 1e-12 * scale);
  assert_true(e[1] <= 1e-12 * scale);
  assert_int_equal(mpm_hier_g2p(f.h, f.phase, &a, NULL), MPM_ERR_INTERNAL);
  /* mpm_hier_g2p_from reads the caller's velocity on every level: the affine one, moved out of
   * the phase, whose v_i then holds garbage. */
  mpm_hier_nodal vel = {{{NULL}}};
  double *moved[MPM_HIER_MAX_LEVELS][3] = {{NULL}};
  for (int l = 0; l < f.h->nlevels; ++l) {
    mpm_grid *g = f.h->level[l].grid;
    for (int d = 0; d < dim; ++d) {
      moved[l][d] = alloc0((size_t)g->nnodes);
      memcpy(moved[l][d], g->phase[f.phase].v_i[d], sizeof(double) * (size_t)g->nnodes);
      for (mpm_lidx i = 0; i < g->nnodes; ++i) g->phase[f.phase].v_i[d][i] = 1e30;
      vel.v_i[l][d] = moved[l][d];
    }
  }
  for (int d = 0; d < dim; ++d) a.v_i[d] = NULL;
  assert_int_equal(mpm_hier_g2p_from(f.h, f.phase, &a, &vel, &hs), 0);
  double ef[2] = {0, 0};
  g2p_errors(&f, &p, &o, ef);
  printf("affine %-13s G2P from the caller's velocity: v/a/s %.2e, L and C (times h) %.2e\n",
         hier_case_name[c], ef[0], ef[1]);
  assert_true(ef[0] <= 1e-12 * scale);
  assert_true(ef[1] <= 1e-12 * scale);
  for (int l = 0; l < f.h->nlevels; ++l)
    for (int d = 0; d < dim; ++d) free(moved[l][d]);
  for (int d = 0; d < dim; ++d) free(o.v[d]), free(o.a[d]);
  free(o.L), free(o.C), free(o.s);
  for (int l = 0; l < f.h->nlevels; ++l) free(s[l]);
  pset_free(&p);
  fixture_free(&f);
}

static void test_affine(void **state) {
  (void)state;
  for (int c = 0; c < HIER_NCASES; ++c) check_affine((hier_case)c);
}

/* ---- (8) nodal solve ---------------------------------------------------------------------- */

static void fill_deposit(mpm_grid *g, int phase, uint64_t seed) {
  uint64_t rng = seed;
  mpm_grid_phase *ph = &g->phase[phase];
  for (mpm_lidx i = 0; i < g->nnodes; ++i) {
    const double u = mpm_test_uniform(&rng);
    ph->m_i[i] = u < 0.3 ? 0.0 : u < 0.4 ? 1e-17 * u : u;
    for (int d = 0; d < g->dim; ++d)
      ph->mv_i[d][i] = mpm_test_uniform(&rng) - 0.5, ph->f_i[d][i] = mpm_test_uniform(&rng);
  }
}

static int same_solve(const mpm_grid *a, const mpm_grid *b, int phase) {
  const mpm_grid_phase *p = &a->phase[phase], *q = &b->phase[phase];
  const size_t bytes = (size_t)a->nnodes * sizeof(double);
  int same = p->m_max == q->m_max && p->m_empty == q->m_empty && p->m_mean == q->m_mean;
  for (int d = 0; d < a->dim; ++d)
    same &= !memcmp(p->v_i[d], q->v_i[d], bytes) && !memcmp(p->a_i[d], q->a_i[d], bytes);
  return same;
}

static void test_phase_update(void **state) {
  (void)state;
  const double lo[2] = {0, 0}, hi[2] = {2, 2};
  const int nproc[2] = {1, 1};
  for (int light = 0; light < 2; ++light) {
    mpm_grid *ga, *gb;
    int pa, pb;
    assert_int_equal(mpm_grid_new(&ga, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc),
                     0);
    assert_int_equal(mpm_grid_new(&gb, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc),
                     0);
    assert_int_equal(mpm_grid_add_phase(ga, "a", &pa), 0);
    assert_int_equal(mpm_grid_add_phase(gb, "a", &pb), 0);
    ga->phase[pa].light_fraction = gb->phase[pb].light_fraction = light ? 0.3 : 0.0;
    fill_deposit(ga, pa, 7000), fill_deposit(gb, pb, 7000);
    mpm_hier *h;
    char why[256];
    assert_int_equal(mpm_hier_new(&h, ga, 1, NULL, 0, 1, why, sizeof why), 0);
    assert_int_equal(mpm_hier_phase_update(h, pa, 1e-3), 0);
    assert_int_equal(mpm_grid_phase_update(gb, pb, 1e-3), 0);
    assert_true(same_solve(ga, gb, pa));
    double *v17 = &gb->phase[pb].v_i[0][17]; /* the comparison can fail: one ulp off */
    *v17 = nextafter(*v17, HUGE_VAL);
    assert_false(same_solve(ga, gb, pa));
    mpm_hier_destroy(&h);
    mpm_grid_destroy(&ga), mpm_grid_destroy(&gb);
  }
  /* Several levels: the largest nodal mass is taken over all of them. */
  fixture f;
  assert_int_equal(fixture_make(&f, HIER_3LEV), 0);
  for (int l = 0; l < f.h->nlevels; ++l) fill_deposit(f.h->level[l].grid, f.phase, 7100 + l);
  f.h->level[2].grid->phase[f.phase].m_i[5] = 7.0;
  assert_int_equal(mpm_hier_phase_update(f.h, f.phase, 0.0), 0);
  for (int l = 0; l < f.h->nlevels; ++l) {
    const mpm_grid_phase *ph = &f.h->level[l].grid->phase[f.phase];
    assert_true(ph->m_max == 7.0 && ph->m_empty == ph->empty_fraction * 7.0);
  }
  fixture_free(&f);
}

/* The light rule on several levels: a uniform gas puts 2^-dim l of a level-0 node's mass on a
 * level-l node, and each level compares its nodes with the mean at its own spacing, so a node
 * at 0.8 of its level's mass stays and one at 0.2 goes (light_fraction 0.3) on every level.
 * (One mean over the raw masses of all levels, the rule before, empties every node of level 1
 * and finer here: their masses are at most a quarter of level 0's.) */
static void test_light_levels(void **state) {
  (void)state;
  fixture f;
  assert_int_equal(fixture_make(&f, HIER_3LEV), 0);
  f.grid->phase[f.phase].light_fraction = 0.3; /* (the levels copy it when built) */
  for (int l = 1; l < f.h->nlevels; ++l) f.h->level[l].grid->phase[f.phase].light_fraction = 0.3;
  const int keep = 11, drop = 12;
  for (int l = 0; l < f.h->nlevels; ++l) {
    mpm_grid *g = f.h->level[l].grid;
    mpm_grid_phase *ph = &g->phase[f.phase];
    const double node = ldexp(1.0, -2 * l); /* a uniform gas's nodal mass at level l */
    for (mpm_lidx i = 0; i < g->nnodes; ++i) {
      ph->m_i[i] = i == keep ? 0.8 * node : i == drop ? 0.2 * node : node;
      for (int d = 0; d < g->dim; ++d) ph->mv_i[d][i] = ph->m_i[i], ph->f_i[d][i] = 0.0;
    }
  }
  assert_int_equal(mpm_hier_phase_update(f.h, f.phase, 0.0), 0);
  for (int l = 0; l < f.h->nlevels; ++l) {
    const mpm_grid *g = f.h->level[l].grid;
    const mpm_grid_phase *ph = &g->phase[f.phase];
    const double node = ldexp(1.0, -2 * l);
    assert_true(fabs(ph->m_mean / node - 1.0) < 0.01); /* the two odd nodes among many */
    assert_true(fabs(ph->m_empty - 0.3 * ph->m_mean) <= 1e-15 * node);
    assert_true(ph->v_i[0][keep] == 1.0 && ph->v_i[0][drop] == 0.0 && ph->v_i[0][0] == 1.0);
  }
  fixture_free(&f);
}

/* ---- cost (printed only) ------------------------------------------------------------------ */

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* Best of 3 of a P2G then a G2P: plain kernel on g (hier NULL) or composite on h. */
static void time_pair(mpm_grid *g, mpm_hier *h, int phase, const pset *p, double *t) {
  const mpm_kernels *k = mpm_kernels_get(2);
  const mpm_p2g_args a = p2g_args(p, 2);
  double *out = alloc0((size_t)(13 * p->n));
  mpm_g2p_args b = {.n = p->n, .C_out = out + 4 * p->n};
  for (int d = 0; d < 2; ++d) {
    b.x[d] = p->x[d], b.v_out[d] = out + d * p->n, b.a_out[d] = out + (2 + d) * p->n;
    b.v_i[d] = g->phase[phase].v_i[d], b.a_i[d] = g->phase[phase].a_i[d];
  }
  t[0] = t[1] = HUGE_VAL;
  for (int r = 0; r < 3; ++r) {
    double t0 = now();
    if (h)
      assert_int_equal(mpm_hier_p2g(h, phase, &a), 0);
    else
      k->p2g(g, phase, &a);
    double t1 = now();
    if (h)
      assert_int_equal(mpm_hier_g2p(h, phase, &b, NULL), 0);
    else
      k->g2p(g, &b);
    double t2 = now();
    t[0] = fmin(t[0], t1 - t0), t[1] = fmin(t[1], t2 - t1);
  }
  free(out);
}

/* Particles uniformly in [lo, hi)^2 outside (elo, ehi)^2. */
static void pset_in(pset *p, mpm_lidx n, double lo, double hi, double elo, double ehi) {
  fixture f = {0};
  mpm_grid g = {.dim = 2};
  f.grid = &g;
  pset_make(p, &f, n, 8000); /* velocities, masses, C; positions below */
  uint64_t rng = 8100;
  for (mpm_lidx i = 0; i < n; ++i) {
    double x, y;
    do {
      x = lo + (hi - lo) * mpm_test_uniform(&rng), y = lo + (hi - lo) * mpm_test_uniform(&rng);
    } while (x > elo && x < ehi && y > elo && y < ehi);
    p->x[0][i] = x, p->x[1][i] = y;
  }
}

static void test_cost(void **state) {
  (void)state;
  const double lo[2] = {0, 0}, hi[2] = {8, 8};
  const int nproc[2] = {1, 1};
  const mpm_lidx n = 200000;
  mpm_grid *g;
  int ph;
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_SELF, 2, lo, hi, 0.02, MPM_SHAPE_QUADRATIC, nproc), 0);
  assert_int_equal(mpm_grid_add_phase(g, "gas", &ph), 0);
  const mpm_hier_box box = {1, {2, 2}, {6, 6}};
  mpm_hier *h1, *h2;
  char why[256];
  assert_int_equal(mpm_hier_new(&h1, g, 1, NULL, 0, 1, why, sizeof why), 0);
  assert_int_equal(mpm_hier_new(&h2, g, 2, &box, 1, 1, why, sizeof why), 0);
  pset out, in, mixed;
  pset_in(&out, n, 0, 8, 1.9, 6.1); /* all on level 0 */
  pset_in(&in, n, 2.1, 5.9, 0, 0);  /* all on level 1 */
  pset_in(&mixed, n, 1, 7, 0, 0);   /* both levels */
  double plain[2], one[2], fast[2], lev1[2], lev1_plain[2], mix[2];
  time_pair(g, NULL, ph, &out, plain);
  time_pair(g, h1, ph, &out, one);
  time_pair(g, h2, ph, &out, fast);
  time_pair(h2->level[1].grid, NULL, ph, &in, lev1_plain);
  time_pair(g, h2, ph, &in, lev1);
  time_pair(g, h2, ph, &mixed, mix);
  printf("cost of %d particles, P2G / G2P (APIC) in ms, best of 3:\n", (int)n);
  printf("  plain kernel, level 0 grid            %7.1f / %7.1f\n", 1e3 * plain[0], 1e3 * plain[1]);
  printf("  hierarchy of 1 level                  %7.1f / %7.1f\n", 1e3 * one[0], 1e3 * one[1]);
  printf("  2 levels, all particles on level 0    %7.1f / %7.1f\n", 1e3 * fast[0], 1e3 * fast[1]);
  printf("  plain kernel, level 1 grid            %7.1f / %7.1f\n", 1e3 * lev1_plain[0],
         1e3 * lev1_plain[1]);
  printf("  2 levels, all particles on level 1    %7.1f / %7.1f\n", 1e3 * lev1[0], 1e3 * lev1[1]);
  printf("  2 levels, particles on both           %7.1f / %7.1f\n", 1e3 * mix[0], 1e3 * mix[1]);
  double tr = HUGE_VAL, tp = HUGE_VAL;
  for (int r = 0; r < 3; ++r) {
    const double t0 = now();
    mpm_hier_restrict(h2, ph);
    const double t1 = now();
    mpm_hier_prolong(h2, ph);
    tr = fmin(tr, t1 - t0), tp = fmin(tp, now() - t1);
  }
  printf("  restriction / prolongation (%d + %d nodes) %5.1f / %7.1f\n", (int)g->nnodes,
         (int)h2->level[1].grid->nnodes, 1e3 * tr, 1e3 * tp);
  pset_free(&out), pset_free(&in), pset_free(&mixed);
  mpm_hier_destroy(&h1), mpm_hier_destroy(&h2);
  mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_conservation), cmocka_unit_test(test_p2g_is_eval),
      cmocka_unit_test(test_affine),       cmocka_unit_test(test_phase_update),
      cmocka_unit_test(test_light_levels), cmocka_unit_test(test_cost),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
