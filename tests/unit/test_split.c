/* Split and merge of gas particles (fluid/fluid_split.h) on random particle sets in the gas's
 * own layouts (APIC, viscosity and the limiter, lagged rate in the state or pending), 2-D and
 * 3-D, one rank:
 *  (i)   split: mass, momentum, total energy sum m (e + |v|^2 / 2), volume sum J V0, the
 *        centre of mass and sum m C are unchanged; 2^dim children per parent at +-s/4,
 *        s = (J V0)^(1/dim), each with m / 2^dim, V0 / 2^dim and the parent's other fields
 *        bit for bit (hence its density m / (J V0)); ids unique, id_next above them all;
 *  (ii)  merge of random groups of 2^dim with spread velocities: the same totals, the
 *        lowest id kept, e raised by the averaging's kinetic energy;
 *  (iii) split then merge of each parent with its children returns every field of every
 *        particle and its id; the same through the parent-slot groups (fluid_merge_groups)
 *        for gas seeded at the slots' centres;
 *  (iv)  a parent near a wall splits with shortened, symmetric offsets inside the domain;
 *  (v)   a group across a periodic face merges at its centre of mass across the face.
 * It also prints the cost of split + merge per particle and the memory the split holds at its
 * peak (no assertion on either).
 *
 * Tolerance: 1e-14 relative, each total against its own scale (M; sum m |v| per component
 * of momentum; E; the domain's extent for the centre of mass; sum m |C|). The operations are
 * exact in real arithmetic; what remains is the rounding of a few terms per particle (a few
 * ulp, about 1e-16 relative) and of the sums, taken in long double here (measured: at most
 * 4e-17 for the totals, 6e-16 for split + merge field by field). A wrong rule is far above it
 * (measured by breaking the code): without the kinetic-energy term of the merge the energy
 * error is 4e-2 (air-like e and v); x volume-weighted in the merge moves the centre of mass by
 * 4e-3; children without V0 / 2^dim change the volume by a factor 2^dim. */
#include "mpm_random.h"
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

#include "fluid_internal.h"
#include "fluid_split.h"
#include "mpm_grid.h"
#include "mpm_particles.h"

#define TOL 1e-14
#define NP  400

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.0, 1.6, 2.1}, g_dx = 0.2;

/* A gas module with only what split and merge read: grid, layout, particles. */
typedef struct gas {
  mpm_module m;
  fluid_content fc;
} gas;

/* Layout flags: APIC, viscous, limiter, lagged rate in the state. */
static void gas_make(gas *s, int dim, int apic, int viscous, int limiter, int lag) {
  memset(s, 0, sizeof *s);
  const int nproc[3] = {1, 1, 1};
  assert_int_equal(
      mpm_grid_new(&s->m.grid, MPI_COMM_WORLD, dim, g_lo, g_hi, g_dx, MPM_SHAPE_QUADRATIC, nproc),
      0);
  assert_int_equal(
      fluid_particles_new(&s->m.particles, dim, &s->fc.lay, apic, viscous, limiter, lag), 0);
  s->m.content = &s->fc;
}

static void gas_free(gas *s) {
  mpm_particles_destroy(&s->m.particles);
  mpm_grid_destroy(&s->m.grid);
}

static double *comp(const gas *s, int f, int c) {
  return mpm_particles_comp(s->m.particles, f, c);
}

/* n random particles: positions at least `margin` inside the domain, every field random
 * (positive m, V0, J, e), ids 0 .. n-1. vspread: the spread of v around (300, -200, 100) m/s (e
 * about 2e5 J/kg: air). */
static void gas_fill(gas *s, mpm_lidx n, double margin, double vspread, uint64_t seed) {
  mpm_particles *p = s->m.particles;
  double *data = malloc(sizeof *data * (size_t)p->ncomp * (size_t)n);
  mpm_gidx *id = malloc(sizeof *id * (size_t)n);
  uint64_t st = seed;
  for (int q = 0; q < p->ncomp; ++q)
    for (mpm_lidx i = 0; i < n; ++i) data[(size_t)q * n + i] = 2.0 * mpm_test_uniform(&st) - 1.0;
  for (mpm_lidx i = 0; i < n; ++i) {
    id[i] = i;
    for (int d = 0; d < p->dim; ++d) {
      const double u = mpm_test_uniform(&st);
      data[(size_t)d * n + i] = g_lo[d] + margin + u * (g_hi[d] - g_lo[d] - 2 * margin);
      data[(size_t)(p->offset[FLUID_V] + d) * n + i] =
          (d == 0   ? 3.0
           : d == 1 ? -2.0
                    : 1.0) +
          vspread * (2.0 * mpm_test_uniform(&st) - 1.0);
    }
    data[(size_t)p->offset[s->fc.lay.f_m] * n + i] = 0.5 + mpm_test_uniform(&st);
    data[(size_t)p->offset[s->fc.lay.f_V0] * n + i] =
        pow(0.05, p->dim) * (0.5 + mpm_test_uniform(&st));
    data[(size_t)p->offset[FLUID_J] * n + i] = 0.5 + 1.5 * mpm_test_uniform(&st);
    data[(size_t)p->offset[FLUID_E] * n + i] = 2e5 * (0.5 + mpm_test_uniform(&st));
  }
  assert_int_equal(mpm_particles_edit(p, NULL, n, id, data), 0);
  p->id_next = n;
  free(data), free(id);
}

/* Totals: mass, momentum (3), energy, volume, centre of mass (3), sum m C (9), and scales. */
typedef struct totals {
  long double M, P[3], E, V, X[3], C[9];
  long double Pscale[3], Cscale;
} totals;

static totals totals_of(const gas *s) {
  const mpm_particles *p = s->m.particles;
  const int dim = p->dim, nC = s->fc.lay.f_C >= 0 ? dim * dim : 0;
  totals t = {0};
  const double *m = comp(s, s->fc.lay.f_m, 0), *V0 = comp(s, s->fc.lay.f_V0, 0);
  const double *J = comp(s, FLUID_J, 0), *e = comp(s, FLUID_E, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    long double ke = 0;
    t.M += m[i], t.V += (long double)J[i] * V0[i];
    for (int d = 0; d < dim; ++d) {
      const double v = comp(s, FLUID_V, d)[i];
      t.P[d] += (long double)m[i] * v, t.Pscale[d] += fabsl((long double)m[i] * v);
      t.X[d] += (long double)m[i] * comp(s, FLUID_X, d)[i];
      ke += 0.5L * m[i] * v * v;
    }
    t.E += (long double)m[i] * e[i] + ke;
    for (int c = 0; c < nC; ++c) {
      const long double mc = (long double)m[i] * comp(s, s->fc.lay.f_C, c)[i];
      t.C[c] += mc, t.Cscale += fabsl(mc);
    }
  }
  for (int d = 0; d < dim; ++d) t.X[d] /= t.M;
  return t;
}

static double rel(long double a, long double b, long double scale) {
  return scale > 0 ? (double)(fabsl(a - b) / scale) : (double)fabsl(a - b);
}

/* The largest relative change of any total (printed with its name). */
static double totals_check(const char *what, const totals *a, const totals *b, int dim) {
  double err[5] = {rel(a->M, b->M, a->M), 0, rel(a->E, b->E, a->E), 0, 0};
  for (int d = 0; d < dim; ++d) {
    err[1] = fmax(err[1], rel(a->P[d], b->P[d], a->Pscale[d]));
    err[3] = fmax(err[3], rel(a->X[d], b->X[d], g_hi[d] - g_lo[d]));
  }
  for (int c = 0; c < dim * dim; ++c) err[4] = fmax(err[4], rel(a->C[c], b->C[c], a->Cscale));
  printf("%-28s %dD: mass %.2e momentum %.2e energy %.2e centre %.2e sum mC %.2e\n", what, dim,
         err[0], err[1], err[2], err[3], err[4]);
  double worst = 0;
  for (int k = 0; k < 5; ++k) worst = fmax(worst, err[k]);
  return worst;
}

/* Ids unique and below id_next. */
static void check_ids(const mpm_particles *p) {
  mpm_gidx *id = malloc(sizeof *id * (size_t)(p->n + 1));
  memcpy(id, p->id, sizeof *id * (size_t)p->n);
  for (mpm_lidx i = 1; i < p->n; ++i) { /* insertion sort: a few thousand ids */
    const mpm_gidx v = id[i];
    mpm_lidx j = i;
    for (; j > 0 && id[j - 1] > v; --j) id[j] = id[j - 1];
    id[j] = v;
  }
  for (mpm_lidx i = 0; i < p->n; ++i) {
    assert_true(id[i] >= 0 && id[i] < p->id_next);
    if (i > 0) assert_true(id[i] > id[i - 1]);
  }
  free(id);
}

/* Every third particle, in a shuffled order. */
static mpm_lidx pick(mpm_lidx n, mpm_lidx *idx, uint64_t seed) {
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < n; i += 3) idx[k++] = i;
  uint64_t st = seed;
  for (mpm_lidx a = k - 1; a > 0; --a) {
    const mpm_lidx b = (mpm_lidx)(mpm_test_uniform(&st) * (a + 1));
    const mpm_lidx t = idx[a];
    idx[a] = idx[b], idx[b] = t;
  }
  return k;
}

/* The layouts: {apic, viscous, limiter, lag}; the last is the method of lines' pending copy of
 * divv, D and psi (test_layouts.c builds every layout). */
enum { NLAYOUTS = 5 };
static const int g_layouts[NLAYOUTS][4] = {
    {1, 1, 1, 1}, {1, 0, 1, 0}, {0, 1, 0, 1}, {0, 0, 0, 0}, {0, 1, 1, 0}};

/* (i) */
static void split_one(int dim, const int *lay) {
  gas s;
  gas_make(&s, dim, lay[0], lay[1], lay[2], lay[3]);
  gas_fill(&s, NP, 0.2, 50.0, 11u + (uint64_t)dim);
  mpm_particles *p = s.m.particles;
  const int nc = p->ncomp, nkid = 1 << dim;
  double *before = malloc(sizeof *before * (size_t)nc * NP);
  memcpy(before, p->data, sizeof *before * (size_t)nc * NP);
  mpm_gidx id0[NP];
  memcpy(id0, p->id, sizeof id0);
  mpm_lidx idx[NP];
  const mpm_lidx k = pick(NP, idx, 5);
  const totals t0 = totals_of(&s);
  fluid_split_report r;
  assert_int_equal(fluid_split(&s.m, idx, k, &r), 0);
  assert_int_equal(p->n, NP + (nkid - 1) * k);
  assert_int_equal(r.parents, k), assert_int_equal(r.children, (nkid - 1) * k);
  assert_int_equal(r.shrunk, 0);
  const totals t1 = totals_of(&s);
  assert_true(totals_check("split", &t0, &t1, dim) < TOL);
  assert_true(rel(t0.V, t1.V, t0.V) < TOL);
  check_ids(p);
  const int om = p->offset[s.fc.lay.f_m], oV = p->offset[s.fc.lay.f_V0];
  for (mpm_lidx a = 0; a < k; ++a) {
    const mpm_lidx i = idx[a];
    const double V = before[(size_t)p->offset[FLUID_J] * NP + i] * before[(size_t)oV * NP + i];
    const double delta = 0.25 * (dim == 3 ? cbrt(V) : sqrt(V));
    assert_true(p->id[i] == id0[i]);
    for (int j = 0; j < nkid; ++j) {
      const mpm_lidx c = j == 0 ? i : NP + a * (nkid - 1) + j - 1;
      for (int q = dim; q < p->offset[s.fc.lay.f_rho]; ++q) { /* (the output fields last) */
        const double want = before[(size_t)q * NP + i] / (q == om || q == oV ? nkid : 1);
        assert_true(p->data[(size_t)q * p->n + c] == want);
      }
      for (int d = 0; d < dim; ++d) {
        const double off = comp(&s, FLUID_X, d)[c] - before[(size_t)d * NP + i];
        assert_true(fabs(fabs(off) - delta) < 1e-12 * delta);
        assert_true((off > 0) == (j >> d & 1));
      }
    }
  }
  free(before);
  gas_free(&s);
}

static void test_split(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int l = 0; l < NLAYOUTS; ++l) split_one(dim, g_layouts[l]);
}

/* Random disjoint groups of 2^dim over particles 0 .. n-1 (a shuffle cut into groups). */
static mpm_lidx random_groups(mpm_lidx n, int size, mpm_lidx *start, mpm_lidx *member,
                              uint64_t seed) {
  for (mpm_lidx i = 0; i < n; ++i) member[i] = i;
  uint64_t st = seed;
  for (mpm_lidx a = n - 1; a > 0; --a) {
    const mpm_lidx b = (mpm_lidx)(mpm_test_uniform(&st) * (a + 1)), t = member[a];
    member[a] = member[b], member[b] = t;
  }
  mpm_lidx ng = 0;
  start[0] = 0;
  for (mpm_lidx at = 0; at + size <= n; at += size) start[++ng] = at + size;
  return ng;
}

/* (ii) */
static void merge_one(int dim, const int *lay) {
  gas s;
  gas_make(&s, dim, lay[0], lay[1], lay[2], lay[3]);
  gas_fill(&s, NP, 0.0, 200.0, 23u + (uint64_t)dim);
  mpm_particles *p = s.m.particles;
  const int nkid = 1 << dim;
  mpm_lidx start[NP + 1], member[NP];
  const mpm_lidx ng = random_groups(NP, nkid, start, member, 9);
  double e_min[NP];
  mpm_gidx id_min[NP];
  for (mpm_lidx g = 0; g < ng; ++g) {
    e_min[g] = HUGE_VAL, id_min[g] = INT64_MAX;
    for (mpm_lidx a = start[g]; a < start[g + 1]; ++a) {
      e_min[g] = fmin(e_min[g], comp(&s, FLUID_E, 0)[member[a]]);
      if (p->id[member[a]] < id_min[g]) id_min[g] = p->id[member[a]];
    }
  }
  const totals t0 = totals_of(&s);
  fluid_split_report r;
  assert_int_equal(fluid_merge(&s.m, start, member, ng, &r), 0);
  assert_int_equal(r.groups, ng), assert_int_equal(r.removed, ng * (nkid - 1));
  assert_int_equal(p->n, NP - ng * (nkid - 1));
  const totals t1 = totals_of(&s);
  assert_true(totals_check("merge", &t0, &t1, dim) < TOL);
  assert_true(rel(t0.V, t1.V, t0.V) < TOL);
  check_ids(p);
  /* Each merged particle carries its group's lowest id and an e above its coldest member's. */
  int found = 0;
  for (mpm_lidx i = 0; i < p->n; ++i)
    for (mpm_lidx g = 0; g < ng; ++g)
      if (p->id[i] == id_min[g]) found++, assert_true(comp(&s, FLUID_E, 0)[i] > e_min[g]);
  assert_int_equal(found, ng);
  gas_free(&s);
}

static void test_merge(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int l = 0; l < NLAYOUTS; ++l) merge_one(dim, g_layouts[l]);
}

/* Largest difference of the non-derived fields of a and b (n particles each, same order),
 * relative to each component's largest magnitude. */
static double fields_diff(const mpm_particles *p, const double *a, const double *b, mpm_lidx n) {
  double worst = 0;
  for (int f = 0; f < p->nfields; ++f) {
    if (p->derived >> f & 1u) continue;
    for (int c = 0; c < p->field[f].ncomp; ++c) {
      const size_t o = (size_t)(p->offset[f] + c) * n;
      double scale = 0, diff = 0;
      for (mpm_lidx i = 0; i < n; ++i)
        scale = fmax(scale, fabs(a[o + i])), diff = fmax(diff, fabs(a[o + i] - b[o + i]));
      worst = fmax(worst, scale > 0 ? diff / scale : diff);
    }
  }
  return worst;
}

/* (iii), explicit groups: each parent with its children. */
static void round_trip_one(int dim, const int *lay) {
  gas s;
  gas_make(&s, dim, lay[0], lay[1], lay[2], lay[3]);
  gas_fill(&s, NP, 0.2, 50.0, 37u + (uint64_t)dim);
  mpm_particles *p = s.m.particles;
  const int nc = p->ncomp, nkid = 1 << dim;
  double *before = malloc(sizeof *before * (size_t)nc * NP);
  memcpy(before, p->data, sizeof *before * (size_t)nc * NP);
  mpm_gidx id0[NP];
  memcpy(id0, p->id, sizeof id0);
  mpm_lidx idx[NP];
  const mpm_lidx k = pick(NP, idx, 7);
  fluid_split_report r;
  assert_int_equal(fluid_split(&s.m, idx, k, &r), 0);
  mpm_lidx *start = malloc(sizeof *start * (size_t)(k + 1));
  mpm_lidx *member = malloc(sizeof *member * (size_t)(k * nkid));
  start[0] = 0;
  for (mpm_lidx a = 0; a < k; ++a) {
    member[a * nkid] = idx[a];
    for (int j = 1; j < nkid; ++j) member[a * nkid + j] = NP + a * (nkid - 1) + j - 1;
    start[a + 1] = (a + 1) * nkid;
  }
  assert_int_equal(fluid_merge(&s.m, start, member, k, &r), 0);
  assert_int_equal(p->n, NP);
  for (mpm_lidx i = 0; i < NP; ++i) assert_true(p->id[i] == id0[i]);
  const double err = fields_diff(p, before, p->data, NP);
  printf("split + merge, every field   %dD: %.2e\n", dim, err);
  assert_true(err < TOL);
  free(before), free(start), free(member);
  gas_free(&s);
}

/* (iii), groups by parent slot: gas on the slot lattice of spacing H, each parent's volume
 * H^dim. */
static void round_trip_slots(int dim) {
  gas s;
  gas_make(&s, dim, 1, 1, 1, 1);
  mpm_particles *p = s.m.particles;
  const double H = g_dx / 2;
  int ns[3] = {1, 1, 1};
  mpm_lidx n = 1;
  for (int d = 0; d < dim; ++d) ns[d] = (int)lround((g_hi[d] - g_lo[d]) / H), n *= ns[d];
  gas_fill(&s, n, 0.0, 50.0, 41u);
  for (mpm_lidx i = 0; i < n; ++i) {
    mpm_lidx r = i;
    for (int d = 0; d < dim; ++d)
      comp(&s, FLUID_X, d)[i] = g_lo[d] + ((double)(r % ns[d]) + 0.5) * H, r /= ns[d];
    comp(&s, FLUID_J, 0)[i] = 1.0, comp(&s, s.fc.lay.f_V0, 0)[i] = pow(H, dim);
  }
  const int nc = p->ncomp;
  double *before = malloc(sizeof *before * (size_t)nc * (size_t)n);
  memcpy(before, p->data, sizeof *before * (size_t)nc * (size_t)n);
  mpm_lidx *idx = malloc(sizeof *idx * ((size_t)n << dim));
  for (mpm_lidx i = 0; i < n; ++i) idx[i] = i;
  fluid_split_report r;
  assert_int_equal(fluid_split(&s.m, idx, n, &r), 0);
  for (mpm_lidx i = 0; i < p->n; ++i) idx[i] = p->n - 1 - i; /* any order */
  mpm_lidx *start, *member, ng;
  assert_int_equal(fluid_merge_groups(&s.m, idx, p->n, H, 0.0, 0, &start, &member, &ng), 0);
  assert_int_equal(ng, n);
  assert_int_equal(fluid_merge(&s.m, start, member, ng, &r), 0);
  assert_int_equal(p->n, n);
  for (mpm_lidx i = 0; i < n; ++i) assert_true(p->id[i] == i);
  const double err = fields_diff(p, before, p->data, n);
  printf("split + merge by slot        %dD: %.2e (%d parents)\n", dim, err, (int)n);
  assert_true(err < TOL);
  free(before), free(idx), free(start), free(member);
  gas_free(&s);
}

static void test_round_trip(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim) {
    for (int l = 0; l < NLAYOUTS; ++l) round_trip_one(dim, g_layouts[l]);
    round_trip_slots(dim);
  }
}

/* (iv) a parent 0.01 from the lower x wall, s = 0.1: offsets 0.005 along x, 0.025 elsewhere. */
static void test_wall(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim) {
    gas s;
    gas_make(&s, dim, 1, 0, 0, 1);
    gas_fill(&s, 1, 0.3, 50.0, 3u);
    comp(&s, FLUID_X, 0)[0] = g_lo[0] + 0.01;
    comp(&s, FLUID_J, 0)[0] = 1.0, comp(&s, s.fc.lay.f_V0, 0)[0] = pow(0.1, dim);
    const totals t0 = totals_of(&s);
    const mpm_lidx idx[1] = {0};
    fluid_split_report r;
    assert_int_equal(fluid_split(&s.m, idx, 1, &r), 0);
    assert_int_equal(r.shrunk, 1);
    const totals t1 = totals_of(&s);
    assert_true(totals_check("split at a wall", &t0, &t1, dim) < TOL);
    for (mpm_lidx i = 0; i < s.m.particles->n; ++i) {
      const double x = comp(&s, FLUID_X, 0)[i] - g_lo[0];
      assert_true(fabs(x - 0.01) > 0.005 - 1e-15 && fabs(x - 0.01) < 0.005 + 1e-15);
    }
    gas_free(&s);
  }
}

/* (v) a group across the periodic x faces merges at its centre of mass across them, not in the
 * middle of the domain: members 0.01 and 0.03 inside the two faces, equal masses, at the face. */
static void test_periodic(void **state) {
  (void)state;
  gas s;
  const int nproc[3] = {1, 1, 1}, periodic[3] = {1, 0, 0};
  memset(&s, 0, sizeof s);
  assert_int_equal(mpm_grid_new_periodic(&s.m.grid, MPI_COMM_WORLD, 2, g_lo, g_hi, g_dx,
                                         MPM_SHAPE_QUADRATIC, nproc, periodic),
                   0);
  assert_int_equal(fluid_particles_new(&s.m.particles, 2, &s.fc.lay, 1, 0, 0, 1), 0);
  s.m.content = &s.fc;
  gas_fill(&s, 2, 0.3, 50.0, 5u);
  comp(&s, FLUID_X, 0)[0] = g_lo[0] + 0.01, comp(&s, FLUID_X, 0)[1] = g_hi[0] - 0.03;
  comp(&s, s.fc.lay.f_m, 0)[0] = comp(&s, s.fc.lay.f_m, 0)[1] = 1.0;
  const mpm_lidx start[2] = {0, 2}, member[2] = {0, 1};
  fluid_split_report r;
  assert_int_equal(fluid_merge(&s.m, start, member, 1, &r), 0);
  assert_int_equal(s.m.particles->n, 1);
  const double x = comp(&s, FLUID_X, 0)[0], want = g_hi[0] - 0.01;
  printf("periodic merge: x = %.17g (want %.17g)\n", x, want);
  assert_true(fabs(x - want) < 1e-14);
  gas_free(&s);
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Cost of splitting every particle and merging the children back, and the split's peak. */
static void test_cost(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim) {
    const mpm_lidx n = 100000;
    gas s;
    gas_make(&s, dim, 1, 1, 1, 1);
    gas_fill(&s, n, 0.2, 50.0, 51u);
    mpm_particles *p = s.m.particles;
    const int nkid = 1 << dim;
    mpm_lidx *idx = malloc(sizeof *idx * (size_t)n * (nkid + 1));
    mpm_lidx *start = malloc(sizeof *start * (size_t)(n + 1));
    for (mpm_lidx i = 0; i < n; ++i) idx[i] = i;
    start[0] = 0;
    for (mpm_lidx a = 0; a < n; ++a) {
      idx[n + a * nkid] = a;
      for (int j = 1; j < nkid; ++j) idx[n + a * nkid + j] = n + a * (nkid - 1) + j - 1;
      start[a + 1] = (a + 1) * nkid;
    }
    fluid_split_report r;
    double t[3][2] = {{0}}; /* split, merge; cold (first) and warm (second) round */
    for (int round = 0; round < 2; ++round) {
      const double t0 = now();
      assert_int_equal(fluid_split(&s.m, idx, n, &r), 0);
      const double t1 = now();
      assert_int_equal(fluid_merge(&s.m, start, idx + n, n, &r), 0);
      t[0][round] = t1 - t0, t[1][round] = now() - t1;
    }
    printf("cost %dD, %d components: split %.0f ns per parent, merge %.0f ns per parent "
           "(%d parents; first round, with the page faults of the grown set: %.0f, %.0f)\n",
           dim, p->ncomp, 1e9 * t[0][1] / n, 1e9 * t[1][1] / n, (int)n, 1e9 * t[0][0] / n,
           1e9 * t[1][0] / n);
    const double row = (double)p->ncomp * sizeof(double) + sizeof(mpm_gidx);
    printf("split peak %dD: old block %.1f MB + new block %.1f MB + children's ids %.1f MB\n", dim,
           row * n / 1e6, row * n * nkid / 1e6, 8.0 * n * (nkid - 1) / 1e6);
    free(idx), free(start);
    gas_free(&s);
  }
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_split),      cmocka_unit_test(test_merge),
      cmocka_unit_test(test_round_trip), cmocka_unit_test(test_wall),
      cmocka_unit_test(test_periodic),   cmocka_unit_test(test_cost),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
