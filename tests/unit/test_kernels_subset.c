/* The kernels' index list and wrap (mpm_kernels.h), for every shape in 2-D and 3-D on a one-rank
 * grid, on random particles with every optional field (stress, APIC, external force; G2P's L, C,
 * L F and a nodal scalar):
 *  (i) P2G over a shuffled subset idx of the particles deposits what the full kernel deposits
 *      for the same particles copied out in that order;
 *  (ii) G2P over the subset writes, at the subset's indices, what the full kernel gives for the
 *      copies, and leaves every other particle's outputs alone;
 *  (iii) with a wrap along every axis (an interval inside the domain), P2G and G2P of positions
 *      up to a period outside it equal the kernels without a wrap on the positions wrapped
 *      beforehand by mpm_wrap_coord (what the hierarchy did before the kernels wrapped).
 *
 * Tolerance: none, the values must be equal: the hierarchy's transfers visit each level's
 * particles through the list, and its results must be those of the former gathered copies bit
 * for bit. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <mpi.h>

#include "mpm_grid.h"
#include "mpm_kernels.h"
#include "mpm_random.h"

#define NP 1200
#define NS 500 /* the subset */

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.2, 2.0, 2.6}, g_dx = 0.1;

static double *random_array(size_t n, double lo, double hi, uint64_t *seed) {
  double *a = malloc(sizeof(double) * n);
  for (size_t k = 0; k < n; ++k) a[k] = lo + (hi - lo) * mpm_test_uniform(seed);
  return a;
}

/* Component-major copy of the particles idx[0 .. ns) of src (ncomp components of n). */
static double *pick(const double *src, int ncomp, const mpm_lidx *idx, int ns, size_t n) {
  double *out = malloc(sizeof(double) * (size_t)ncomp * (size_t)ns);
  for (int c = 0; c < ncomp; ++c)
    for (int k = 0; k < ns; ++k) out[(size_t)c * ns + k] = src[(size_t)c * n + (size_t)idx[k]];
  return out;
}

/* The particles of a test: positions, fields, and the subset. */
typedef struct scene {
  int dim;
  double *x[3], *v[3], *fext[3], *m, *vsig, *C, *F;
  mpm_lidx idx[NS];
} scene;

/* Positions 0.25 inside the domain: every stencil lies in the box. */
static void scene_make(scene *s, int dim, uint64_t seed) {
  memset(s, 0, sizeof *s);
  s->dim = dim;
  for (int d = 0; d < dim && d < 3; ++d) {
    s->x[d] = random_array(NP, g_lo[d] + 0.25, g_hi[d] - 0.25, &seed);
    s->v[d] = random_array(NP, -2.0, 2.0, &seed);
    s->fext[d] = random_array(NP, -1.0, 1.0, &seed);
  }
  s->m = random_array(NP, 0.5, 2.0, &seed);
  s->vsig = random_array((size_t)(dim * dim) * NP, -2.0, 2.0, &seed);
  s->C = random_array((size_t)(dim * dim) * NP, -1.0, 1.0, &seed);
  s->F = random_array((size_t)(dim * dim) * NP, 0.5, 1.5, &seed);
  /* A shuffled subset: every other particle from a random start, then a Fisher-Yates shuffle. */
  const int start = (int)(mpm_test_uniform(&seed) * 100.0);
  for (int k = 0; k < NS; ++k) s->idx[k] = start + 2 * k;
  for (int k = NS - 1; k > 0; --k) {
    const int j = (int)(mpm_test_uniform(&seed) * (k + 1));
    const mpm_lidx t = s->idx[k];
    s->idx[k] = s->idx[j], s->idx[j] = t;
  }
}

static void scene_free(scene *s) {
  for (int d = 0; d < 3; ++d) free(s->x[d]), free(s->v[d]), free(s->fext[d]);
  free(s->m), free(s->vsig), free(s->C), free(s->F);
}

static mpm_grid *grid_make(int dim, mpm_shape_kind shape, int nphase) {
  mpm_grid *g = NULL;
  const int nproc[3] = {1, 1, 1};
  int phase;
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_SELF, dim, g_lo, g_hi, g_dx, shape, nproc), 0);
  static const char *const name[2] = {"a", "b"};
  for (int p = 0; p < nphase; ++p) assert_int_equal(mpm_grid_add_phase(g, name[p], &phase), 0);
  return g;
}

static long differ(const double *a, const double *b, size_t n) {
  long count = 0;
  for (size_t k = 0; k < n; ++k) count += memcmp(&a[k], &b[k], sizeof a[k]) != 0;
  return count;
}

/* Nodes of phases 0 and 1 of g that differ (mass, momentum, force) and nodes reached. */
static long phases_differ(const mpm_grid *g, long *reached) {
  const mpm_grid_phase *a = &g->phase[0], *b = &g->phase[1];
  const size_t nn = (size_t)g->nnodes;
  long diff = differ(a->m_i, b->m_i, nn);
  for (int d = 0; d < g->dim; ++d)
    diff += differ(a->mv_i[d], b->mv_i[d], nn) + differ(a->f_i[d], b->f_i[d], nn);
  *reached = 0;
  for (size_t k = 0; k < nn; ++k) *reached += b->m_i[k] != 0.0;
  return diff;
}

/* a deposited into phase 0 and b into phase 1 of g, both zeroed first: the nodes that differ
 * (phases_differ). */
static long deposit_pair(mpm_grid *g, const mpm_p2g_args *a, const mpm_p2g_args *b, long *reached) {
  mpm_grid_phase_zero(g, 0);
  mpm_grid_phase_zero(g, 1);
  mpm_kernels_get(g->dim)->p2g(g, 0, a);
  mpm_kernels_get(g->dim)->p2g(g, 1, b);
  return phases_differ(g, reached);
}

/* Random nodal velocity, acceleration and one scalar on phase 0. */
static void nodal_fields(mpm_grid *g, uint64_t seed) {
  mpm_grid_phase *ph = &g->phase[0];
  for (mpm_lidx k = 0; k < g->nnodes; ++k) {
    for (int d = 0; d < g->dim; ++d)
      ph->v_i[d][k] = -1.0 + 2.0 * mpm_test_uniform(&seed),
      ph->a_i[d][k] = -3.0 + 6.0 * mpm_test_uniform(&seed);
    ph->m_i[k] = mpm_test_uniform(&seed); /* (the scalar) */
  }
}

/* G2P arguments of phase 0 into the output block out (v, a, L, C, LF, s: 2 dim + 3 dim^2 + 1
 * components of n). */
static mpm_g2p_args g2p_args(const mpm_grid *g, double *const *x, const double *F, double *out,
                             size_t n) {
  const int D = g->dim, DD = D * D;
  const mpm_grid_phase *ph = &g->phase[0];
  mpm_g2p_args a = {.n = (mpm_lidx)n, .lp = 0.25, .F = F, .nscalar = 1, .s_i = {ph->m_i}};
  for (int d = 0; d < D; ++d) {
    a.x[d] = x[d], a.v_i[d] = ph->v_i[d], a.a_i[d] = ph->a_i[d];
    a.v_out[d] = out + (size_t)d * n, a.a_out[d] = out + (size_t)(D + d) * n;
  }
  a.L_out = out + (size_t)(2 * D) * n;
  a.C_out = out + (size_t)(2 * D + DD) * n;
  a.LF_out = out + (size_t)(2 * D + 2 * DD) * n;
  a.s_out[0] = out + (size_t)(2 * D + 3 * DD) * n;
  return a;
}

static int g2p_comps(int dim) {
  return 2 * dim + 3 * dim * dim + 1;
}

/* (i) and (ii), with APIC on or off. */
static void check_subset(int dim, mpm_shape_kind shape, int apic) {
  if (dim < 2 || dim > 3) fail_msg("dim %d", dim); /* bounds the loops over x[3] for gcc */
  scene s;
  scene_make(&s, dim, 11u + (uint64_t)(100 * dim + 10 * shape + apic));
  const int DD = dim * dim;
  double *xs[3] = {NULL}, *vs[3] = {NULL}, *fs[3] = {NULL};
  for (int d = 0; d < dim && d < 3; ++d) {
    xs[d] = pick(s.x[d], 1, s.idx, NS, NP), vs[d] = pick(s.v[d], 1, s.idx, NS, NP);
    fs[d] = pick(s.fext[d], 1, s.idx, NS, NP);
  }
  double *ms = pick(s.m, 1, s.idx, NS, NP), *sigs = pick(s.vsig, DD, s.idx, NS, NP);
  double *Cs = pick(s.C, DD, s.idx, NS, NP), *Fs = pick(s.F, DD, s.idx, NS, NP);

  mpm_grid *g = grid_make(dim, shape, 2);
  mpm_p2g_args sub = {.n = NP,
                      .idx = s.idx,
                      .nidx = NS,
                      .m = s.m,
                      .vsig = s.vsig,
                      .C = apic ? s.C : NULL,
                      .lp = 0.25};
  mpm_p2g_args copy = {.n = NS, .m = ms, .vsig = sigs, .C = apic ? Cs : NULL, .lp = 0.25};
  for (int d = 0; d < dim && d < 3; ++d) {
    sub.x[d] = s.x[d], sub.v[d] = s.v[d], sub.fext[d] = s.fext[d];
    copy.x[d] = xs[d], copy.v[d] = vs[d], copy.fext[d] = fs[d];
    sub.gravity[d] = copy.gravity[d] = -0.5 * (d + 1);
  }
  long reached;
  const long dp = deposit_pair(g, &sub, &copy, &reached);

  nodal_fields(g, 3u + (uint64_t)shape);
  const size_t nc = (size_t)g2p_comps(dim);
  double *out = malloc(sizeof(double) * nc * NP), *outs = calloc(nc * NS, sizeof(double));
  for (size_t k = 0; k < nc * NP; ++k) out[k] = 7.0; /* untouched unless visited */
  mpm_g2p_args gsub = g2p_args(g, s.x, s.F, out, NP), gcopy = g2p_args(g, xs, Fs, outs, NS);
  gsub.idx = s.idx, gsub.nidx = NS;
  if (!apic) gsub.C_out = gcopy.C_out = NULL;
  mpm_kernels_get(dim)->g2p(g, &gsub);
  mpm_kernels_get(dim)->g2p(g, &gcopy);
  long dg = 0, touched = 0;
  unsigned char *in = calloc(NP, 1);
  for (int k = 0; k < NS; ++k) in[s.idx[k]] = 1;
  for (size_t c = 0; c < nc; ++c) {
    if (!apic && c >= (size_t)(2 * dim + DD) && c < (size_t)(2 * dim + 2 * DD)) continue;
    for (int k = 0; k < NS; ++k)
      dg += memcmp(&out[c * NP + (size_t)s.idx[k]], &outs[c * NS + (size_t)k], sizeof(double));
    for (size_t p = 0; p < NP; ++p) touched += !in[p] && out[c * NP + p] != 7.0;
  }
  printf("  %d-D %-9s APIC %s: P2G %ld nodes reached, %ld differ; G2P %ld outputs differ, "
         "%ld outside the subset touched\n",
         dim, mpm_shape_name(shape), apic ? "on " : "off", reached, dp, dg, touched);
  assert_true(reached > 100);
  assert_int_equal(dp + dg + touched, 0);
  for (int d = 0; d < dim && d < 3; ++d) free(xs[d]), free(vs[d]), free(fs[d]);
  free(ms), free(sigs), free(Cs), free(Fs), free(out), free(outs), free(in);
  mpm_grid_destroy(&g);
  scene_free(&s);
}

/* (iii): the wrap interval lies 0.1 inside the domain along every axis and holds every
 * position; two thirds of the coordinates are moved a period up or down, out of it (the kernel
 * evaluates its weights at the wrapped coordinate alone, so no stencil leaves the box). */
static void check_wrap(int dim, mpm_shape_kind shape) {
  if (dim < 2 || dim > 3) fail_msg("dim %d", dim);
  scene s;
  scene_make(&s, dim, 29u + (uint64_t)(100 * dim + 10 * shape));
  double wlo[3] = {0}, whi[3] = {0}, *xw[3] = {NULL}, *xpre[3] = {NULL};
  uint64_t seed = 41u + (uint64_t)shape;
  long moved = 0;
  for (int d = 0; d < dim && d < 3; ++d) {
    wlo[d] = g_lo[d] + 0.1, whi[d] = g_hi[d] - 0.1;
    const double len = whi[d] - wlo[d];
    xw[d] = malloc(sizeof(double) * NP), xpre[d] = malloc(sizeof(double) * NP);
    for (size_t p = 0; p < NP; ++p) {
      const double u = mpm_test_uniform(&seed), x = s.x[d][p];
      const double y = u < 1.0 / 3.0 ? x + len : u > 2.0 / 3.0 ? x - len : x;
      moved += y != x;
      xw[d][p] = y, xpre[d][p] = mpm_wrap_coord(y, wlo[d], whi[d]);
    }
  }
  mpm_grid *g = grid_make(dim, shape, 2);
  mpm_p2g_args a = {.n = NP, .m = s.m, .vsig = s.vsig, .C = s.C, .lp = 0.25};
  mpm_p2g_args b = a;
  for (int d = 0; d < dim && d < 3; ++d) {
    a.x[d] = xw[d], b.x[d] = xpre[d], a.v[d] = b.v[d] = s.v[d];
    a.wrap_lo[d] = wlo[d], a.wrap_hi[d] = whi[d];
  }
  long reached;
  const long dp = deposit_pair(g, &a, &b, &reached);
  nodal_fields(g, 5u + (uint64_t)shape);
  const size_t nc = (size_t)g2p_comps(dim);
  double *oa = calloc(nc * NP, sizeof(double)), *ob = calloc(nc * NP, sizeof(double));
  mpm_g2p_args ga = g2p_args(g, xw, s.F, oa, NP), gb = g2p_args(g, xpre, s.F, ob, NP);
  for (int d = 0; d < dim && d < 3; ++d) ga.wrap_lo[d] = wlo[d], ga.wrap_hi[d] = whi[d];
  mpm_kernels_get(dim)->g2p(g, &ga);
  mpm_kernels_get(dim)->g2p(g, &gb);
  const long dg = differ(oa, ob, nc * NP);
  printf("  %d-D %-9s wrap: %ld coordinates a period out; P2G %ld nodes reached, %ld differ; "
         "G2P %ld outputs differ\n",
         dim, mpm_shape_name(shape), moved, reached, dp, dg);
  assert_true(moved > NP && reached > 100); /* (dim axes of NP coordinates) */
  assert_int_equal(dp + dg, 0);
  for (int d = 0; d < dim && d < 3; ++d) free(xw[d]), free(xpre[d]);
  free(oa), free(ob);
  mpm_grid_destroy(&g);
  scene_free(&s);
}

static const mpm_shape_kind g_shapes[] = {MPM_SHAPE_LINEAR, MPM_SHAPE_GIMP, MPM_SHAPE_QUADRATIC,
                                          MPM_SHAPE_CUBIC};

static void test_subset(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (size_t k = 0; k < sizeof g_shapes / sizeof g_shapes[0]; ++k)
      for (int apic = 0; apic <= 1; ++apic) check_subset(dim, g_shapes[k], apic);
}

static void test_wrap(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (size_t k = 0; k < sizeof g_shapes / sizeof g_shapes[0]; ++k) check_wrap(dim, g_shapes[k]);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_subset), cmocka_unit_test(test_wrap)};
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
