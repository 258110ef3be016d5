/* Cost of the exact span integrals (common/mpm_span.h): ns per span for the force and the
 * divergence, 2-D and 3-D, of the library's sum-factorised code against the direct Gauss-point
 * sum it replaced (kept here, and only here, as old_integrate), timed in one process, old and
 * new alternating. Also checks that the two agree: on a set with half spans on every axis and a
 * skip mask, the largest |new - old| over the largest |old| of each output.
 *
 * Usage: bench_span [2-D spans per axis] [3-D spans per axis] [trials]  (default 128 32 7)
 * Prints one line per (dim, integral): "dim what old_ns new_ns ratio" and the agreement lines.
 * Built by bench/bench_span.py (mpicc for mpi.h only; no MPI call is made): the grid is filled
 * in by hand, since only its box, dimension and spacing are read. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mpm_span.h"

/* ---- the direct sum, as it was in common/mpm_span.c before sum factorisation ---- */
enum { NQ = 3, NA = 3 };

typedef struct axis_table {
  int nq, na;
  double w[NQ], N[NQ][NA], dN[NQ][NA];
} axis_table;

static void axis_fill(axis_table *t, double a, double b, double dx) {
  static const double xi[NQ] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static const double om[NQ] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  t->nq = NQ, t->na = NA;
  for (int q = 0; q < NQ; ++q) {
    const double s = 0.5 * (a + b) + 0.5 * (b - a) * xi[q];
    t->w[q] = 0.5 * (b - a) * om[q] * dx;
    t->N[q][0] = 0.5 * (0.5 - s) * (0.5 - s);
    t->N[q][1] = 0.75 - s * s;
    t->N[q][2] = 0.5 * (0.5 + s) * (0.5 + s);
    t->dN[q][0] = -(0.5 - s) / dx;
    t->dN[q][1] = -2.0 * s / dx;
    t->dN[q][2] = (0.5 + s) / dx;
  }
}

static void axis_unit(axis_table *t) {
  t->nq = 1, t->na = 1, t->w[0] = 1.0, t->N[0][0] = 1.0, t->dN[0][0] = 0.0;
}

static void old_integrate(const mpm_grid *g, const mpm_span_set *s, const double *p,
                          double *const *f, const double *const *v, double *D) {
  const int dim = g->dim;
  axis_table full[MPM_MAX_DIM], upper[MPM_MAX_DIM], lower[MPM_MAX_DIM], unit;
  axis_unit(&unit);
  for (int d = 0; d < dim; ++d) {
    axis_fill(&full[d], -0.5, 0.5, g->dx);
    axis_fill(&upper[d], 0.0, 0.5, g->dx);
    axis_fill(&lower[d], -0.5, 0.0, g->dx);
  }
  mpm_lidx stride[3] = {1, 0, 0};
  for (int d = 1; d < dim; ++d) stride[d] = stride[d - 1] * g->box_n[d - 1];
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int d = 0; d < dim; ++d) lo[d] = s->lo[d], hi[d] = s->hi[d];
  mpm_lidx off[27];
  int na = 1;
  for (int d = 0; d < dim; ++d) na *= NA;
  for (int a = 0; a < na; ++a) {
    off[a] = 0;
    for (int d = 0, r = a; d < dim; ++d, r /= NA) off[a] += (mpm_lidx)(r % NA - 1) * stride[d];
  }
  int gi[3];
  for (gi[2] = lo[2]; gi[2] <= hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] <= hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] <= hi[0]; ++gi[0]) {
        const mpm_lidx n = mpm_grid_local_index(g, gi);
        if (s->skip && s->skip[n]) continue;
        const axis_table *t[3] = {&unit, &unit, &unit};
        for (int d = 0; d < dim; ++d)
          t[d] = s->half_lo[d] && gi[d] == s->lo[d]   ? &upper[d]
                 : s->half_hi[d] && gi[d] == s->hi[d] ? &lower[d]
                                                      : &full[d];
        for (int q2 = 0; q2 < t[2]->nq; ++q2)
          for (int q1 = 0; q1 < t[1]->nq; ++q1)
            for (int q0 = 0; q0 < t[0]->nq; ++q0) {
              const int q[3] = {q0, q1, q2};
              const double w = t[0]->w[q0] * t[1]->w[q1] * t[2]->w[q2];
              double phi[27], grad[3][27];
              for (int a = 0; a < na; ++a) {
                int ax[3] = {0, 0, 0};
                for (int d = 0, r = a; d < dim; ++d, r /= NA) ax[d] = r % NA;
                double val[3], der[3];
                for (int d = 0; d < 3; ++d)
                  val[d] = t[d]->N[q[d]][ax[d]], der[d] = t[d]->dN[q[d]][ax[d]];
                phi[a] = val[0] * val[1] * val[2];
                grad[0][a] = der[0] * val[1] * val[2];
                grad[1][a] = val[0] * der[1] * val[2];
                grad[2][a] = val[0] * val[1] * der[2];
              }
              if (p) {
                double ph = 0.0;
                for (int a = 0; a < na; ++a) ph += phi[a] * p[n + off[a]];
                ph *= w;
                for (int d = 0; d < dim; ++d)
                  for (int a = 0; a < na; ++a) f[d][n + off[a]] += ph * grad[d][a];
              }
              if (v) {
                double div = 0.0;
                for (int d = 0; d < dim; ++d)
                  for (int a = 0; a < na; ++a) div += grad[d][a] * v[d][n + off[a]];
                div *= w;
                for (int a = 0; a < na; ++a) D[n + off[a]] += div * phi[a];
              }
            }
      }
}

/* ---- the bench ---- */

/* A box grid of nspan spans per axis (nodes -1 .. nspan), spacing 1/nspan, with random fields. */
typedef struct bench_case {
  mpm_grid g;
  mpm_span_set set;
  double *p, *v[3], *f[3], *D;
  unsigned char *skip;
} bench_case;

static double uniform(uint64_t *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(*s >> 11) / 9007199254740992.0 - 0.5;
}

static void case_new(bench_case *c, int dim, int nspan) {
  memset(c, 0, sizeof(*c));
  c->g.dim = dim, c->g.dx = 1.0 / nspan, c->g.nnodes = 1;
  for (int d = 0; d < dim; ++d) {
    c->g.box_lo[d] = -1, c->g.box_n[d] = nspan + 2, c->g.nnodes *= nspan + 2;
    c->set.lo[d] = 0, c->set.hi[d] = nspan - 1;
  }
  const size_t nn = (size_t)c->g.nnodes;
  uint64_t s = 11;
  c->p = malloc(nn * sizeof(double)), c->D = calloc(nn, sizeof(double));
  c->skip = calloc(nn, 1);
  for (int d = 0; d < 3; ++d)
    c->v[d] = malloc(nn * sizeof(double)), c->f[d] = calloc(nn, sizeof(double));
  for (size_t k = 0; k < nn; ++k) {
    c->p[k] = uniform(&s);
    for (int d = 0; d < 3; ++d) c->v[d][k] = uniform(&s);
    c->skip[k] = uniform(&s) < -0.4; /* a tenth of the spans, for the agreement check */
  }
}

static void case_free(bench_case *c) {
  free(c->p), free(c->D), free(c->skip);
  for (int d = 0; d < 3; ++d) free(c->v[d]), free(c->f[d]);
}

static long spans_of(const bench_case *c) {
  long n = 1;
  for (int d = 0; d < c->g.dim; ++d) n *= c->set.hi[d] - c->set.lo[d] + 1;
  return n;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One call of the chosen integral (old or new), into the case's outputs. */
static void call(bench_case *c, int old, int div) {
  const double *const *v = (const double *const *)c->v;
  if (old)
    old_integrate(&c->g, &c->set, div ? NULL : c->p, div ? NULL : c->f, div ? v : NULL,
                  div ? c->D : NULL);
  else if (div)
    mpm_span_divergence(&c->g, &c->set, v, c->D);
  else
    mpm_span_force(&c->g, &c->set, c->p, c->f);
}

/* ns per span of one call, the fastest of `reps` back-to-back calls. */
static double time_once(bench_case *c, int old, int div, int reps) {
  double best = INFINITY;
  for (int r = 0; r < reps; ++r) {
    const double t0 = now();
    call(c, old, div);
    best = fmin(best, now() - t0);
  }
  return 1e9 * best / (double)spans_of(c);
}

/* Largest |a - b| over the largest |b|, over n values. */
static double rel_diff(const double *a, const double *b, size_t n) {
  double d = 0, m = 0;
  for (size_t k = 0; k < n; ++k) d = fmax(d, fabs(a[k] - b[k])), m = fmax(m, fabs(b[k]));
  return d / m;
}

/* Old and new on half spans along every axis and a skip mask; prints their disagreement. */
static void agree(int dim, int nspan) {
  bench_case c;
  case_new(&c, dim, nspan);
  for (int d = 0; d < dim; ++d) c.set.half_lo[d] = c.set.half_hi[d] = 1;
  c.set.skip = c.skip;
  const size_t nn = (size_t)c.g.nnodes;
  double *ref[4];
  for (int k = 0; k < 4; ++k) ref[k] = calloc(nn, sizeof(double));
  old_integrate(&c.g, &c.set, c.p, ref, (const double *const *)c.v, ref[3]);
  call(&c, 0, 0), call(&c, 0, 1);
  double worst_f = 0;
  for (int d = 0; d < dim; ++d) worst_f = fmax(worst_f, rel_diff(c.f[d], ref[d], nn));
  printf("agree %d-D (half spans on every axis, %s): force %.2e, divergence %.2e\n", dim,
         "a tenth skipped", worst_f, rel_diff(c.D, ref[3], nn));
  for (int k = 0; k < 4; ++k) free(ref[k]);
  case_free(&c);
}

int main(int argc, char **argv) {
  const int n2 = argc > 1 ? atoi(argv[1]) : 128, n3 = argc > 2 ? atoi(argv[2]) : 32;
  const int trials = argc > 3 ? atoi(argv[3]) : 7;
  printf("# dim what spans old_ns new_ns old/new\n");
  for (int dim = 2; dim <= 3; ++dim) {
    bench_case c;
    case_new(&c, dim, dim == 2 ? n2 : n3);
    for (int div = 0; div <= 1; ++div) {
      double best[2] = {INFINITY, INFINITY};
      for (int t = 0; t < trials; ++t) /* old and new alternating */
        for (int old = 1; old >= 0; --old) best[old] = fmin(best[old], time_once(&c, old, div, 3));
      printf("%d %s %ld %.1f %.1f %.2f\n", dim, div ? "divergence" : "force", spans_of(&c), best[1],
             best[0], best[1] / best[0]);
    }
    case_free(&c);
  }
  agree(2, 12), agree(3, 8);
  return 0;
}
