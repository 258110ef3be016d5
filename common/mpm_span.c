/* Exact span integrals of quadratic B-spline fields (see mpm_span.h), by sum factorisation.
 *
 * On a span with local coordinate t = (x - x_i) / dx in [-1/2, 1/2] the three B-splines per axis
 * are N_-(t) = (1/2 - t)^2 / 2, N_0(t) = 3/4 - t^2, N_+(t) = (1/2 + t)^2 / 2 (nodes i - 1, i,
 * i + 1). A half span integrates t over [0, 1/2] or [-1/2, 0] instead.
 *
 * The basis on a span is a tensor product and the span a box, so each integral is a product of
 * 1-D integrals: with the 3 x 3 matrices of one axis
 *
 *   M[a][b] = integral of N_a N_b dx,   G[a][b] = integral of N_a' N_b dx
 *
 * the force of the span's 3^dim nodal pressures p is f_d = (M x ... x G x ... x M) p, G on axis
 * d (Kronecker product), and the divergence D = sum_d (M x ... x G^T x ... x M) v_d. Applied one
 * axis at a time that is 3 products per node and axis: about 650 products per span and field in
 * 3-D, against the (3 x 3)^3 Gauss points times basis functions of the direct sum.
 *
 * M and G are exact rationals (their closed forms), kept as integer matrices times one scale per
 * span kind: full spans M = dx / 120 [6 13 1; 13 54 13; 1 13 6], G = 1 / 24 [-3 -8 -1; 2 0 -2;
 * 1 8 3]; the upper half (t in [0, 1/2]) has its own, the lower half the upper's mirrored. The
 * integer matrices multiply without error and G's columns sum to exactly 0 (the B-splines sum to
 * 1), so a constant p gives each span's nodes forces that sum to 0 up to the rounding of the
 * products, without a bias repeated span after span: the grid pressure's momentum stays exact
 * to roundoff over long runs (Gauss-rule matrices, correct to 1e-17, drift 70x more on
 * test_refine_gas_pulse_grid). The grid's spacing is the same along every axis, so one set of
 * kinds serves all axes.
 *
 * A node plane (mpm_span_plane) cuts its spans through their nodes (t = 0), where the three
 * B-splines of the normal axis are 1/8, 3/4, 1/8: along that axis the matrix is their outer
 * product, 1/64 [1 6 1; 6 36 6; 1 6 1], and the other axes take M. */
#include "mpm_span.h"

#include <string.h>

enum { NA = 3, NMAX = 27 }; /* nodes per axis and per span */

/* One span kind's integer matrices along an axis, G's transpose for the divergence, and the
 * scales that make them the integrals (sM includes dx; G's dx and 1/dx cancel). */
typedef struct axis_mats {
  double M[NA][NA], G[NA][NA], GT[NA][NA];
  double sM, sG;
} axis_mats;

enum { SPAN_FULL, SPAN_UPPER, SPAN_LOWER, SPAN_KINDS };

/* The three kinds on a grid of spacing dx. */
static void kinds_fill(axis_mats *k, double dx) {
  static const double Mf[NA][NA] = {{6, 13, 1}, {13, 54, 13}, {1, 13, 6}};
  static const double Gf[NA][NA] = {{-3, -8, -1}, {2, 0, -2}, {1, 8, 3}};
  static const double Mu[NA][NA] = {{3, 29, 8}, {29, 432, 179}, {8, 179, 93}};
  static const double Gu[NA][NA] = {{-3, -34, -11}, {-2, -60, -34}, {5, 94, 45}};
  for (int i = 0; i < NA; ++i)
    for (int j = 0; j < NA; ++j) {
      k[SPAN_FULL].M[i][j] = Mf[i][j], k[SPAN_FULL].G[i][j] = Gf[i][j];
      k[SPAN_UPPER].M[i][j] = Mu[i][j], k[SPAN_UPPER].G[i][j] = Gu[i][j];
      k[SPAN_LOWER].M[i][j] = Mu[2 - i][2 - j], k[SPAN_LOWER].G[i][j] = -Gu[2 - i][2 - j];
    }
  k[SPAN_FULL].sM = dx / 120, k[SPAN_FULL].sG = 1.0 / 24;
  k[SPAN_UPPER].sM = k[SPAN_LOWER].sM = dx / 1920;
  k[SPAN_UPPER].sG = k[SPAN_LOWER].sG = 1.0 / 384;
  for (int n = 0; n < SPAN_KINDS; ++n)
    for (int i = 0; i < NA; ++i)
      for (int j = 0; j < NA; ++j) k[n].GT[i][j] = k[n].G[j][i];
}

mpm_span_set mpm_span_owned(const mpm_grid *g, const unsigned char *skip) {
  mpm_span_set s = {.skip = skip};
  for (int d = 0; d < g->dim; ++d) {
    s.lo[d] = g->own_lo[d], s.hi[d] = g->own_hi[d] - 1;
    if (g->periodic[d]) continue;
    if (s.lo[d] <= 0) s.lo[d] = 0, s.half_lo[d] = 1;
    if (s.hi[d] >= g->ncells[d]) s.hi[d] = g->ncells[d], s.half_hi[d] = 1;
  }
  return s;
}

/* y = A x along axis d of a span's 3^dim nodal array (axis 0 fastest), or y += A x when add. */
static inline void axis_apply(const double A[NA][NA], int d, int dim, const double *x, double *y,
                              int add) {
  int s = 1, n = 1;
  for (int e = 0; e < dim; ++e) n *= NA, s *= e < d ? NA : 1;
  for (int o = 0; o < n; o += NA * s)
    for (int i = o; i < o + s; ++i) {
      const double x0 = x[i], x1 = x[i + s], x2 = x[i + 2 * s];
      for (int a = 0; a < NA; ++a) {
        const double r = A[a][0] * x0 + A[a][1] * x1 + A[a][2] * x2;
        y[i + a * s] = add ? y[i + a * s] + r : r;
      }
    }
}

/* sc[d] = sG_d prod_{e != d} sM_e: what turns the integer products of component d into the
 * integrals. */
static inline void span_scales(const axis_mats *const *m, int dim, double *sc) {
  for (int d = 0; d < dim; ++d) {
    sc[d] = m[d]->sG;
    for (int e = 0; e < dim; ++e) sc[d] *= e == d ? 1.0 : m[e]->sM;
  }
}

/* The box offsets of a span's 3^dim nodes (axis 0 fastest) and the strides of the box. */
static int span_offsets(const mpm_grid *g, int dim, mpm_lidx *off) {
  mpm_lidx stride[3] = {1, 0, 0};
  for (int d = 1; d < dim; ++d) stride[d] = stride[d - 1] * g->box_n[d - 1];
  const int na = dim == 3 ? 27 : 9;
  for (int a = 0; a < na; ++a) {
    off[a] = 0;
    for (int d = 0, r = a; d < dim; ++d, r /= NA) off[a] += (mpm_lidx)(r % NA - 1) * stride[d];
  }
  return na;
}

/* y[a] = A[a][0] x[0] + A[a][1] x[s] + A[a][2] x[2 s], a = 0 .. 2 (y at stride t): one line of
 * axis_apply, in its order of operations. The span walks below use these with every axis and
 * stride a constant, and keep the products and sums of the generic sum-factorised walk they
 * replaced in its order, so its bits (checked against it on random fields with half spans and
 * skips, 2-D and 3-D), at half its time in 2-D (bench/bench_span.c). */
static inline void line3(const double A[NA][NA], const double *x, int s, double *y, int t) {
  const double x0 = x[0], x1 = x[s], x2 = x[2 * s];
  for (int a = 0; a < NA; ++a) y[a * t] = A[a][0] * x0 + A[a][1] * x1 + A[a][2] * x2;
}

/* One walk over the spans of a 2-D grid: the force of p into f when p is set, the divergence of
 * v into D when v is set, f_d = G_d prod_{e != d} M_e p and D = sum_d prod_{e != d} M_e G_d^T v_d
 * per span (the M of the other axis applied first). The kind of each span is found once per row
 * and column. The 2-D gas runs it twice a step (the grid and hybrid pressures). */
static void integrate_2d(const mpm_grid *g, const mpm_span_set *s, const double *p,
                         double *const *f, const double *const *v, double *D) {
  axis_mats kind[SPAN_KINDS];
  kinds_fill(kind, g->dx);
  const mpm_lidx sy = g->box_n[0];
  for (int gy = s->lo[1]; gy <= s->hi[1]; ++gy) {
    const axis_mats *my = &kind[s->half_lo[1] && gy == s->lo[1]   ? SPAN_UPPER
                                : s->half_hi[1] && gy == s->hi[1] ? SPAN_LOWER
                                                                  : SPAN_FULL];
    for (int gx = s->lo[0]; gx <= s->hi[0]; ++gx) {
      const mpm_lidx n = (mpm_lidx)(gy - g->box_lo[1]) * sy + (gx - g->box_lo[0]);
      if (s->skip && s->skip[n]) continue;
      const axis_mats *mx = &kind[s->half_lo[0] && gx == s->lo[0]   ? SPAN_UPPER
                                  : s->half_hi[0] && gx == s->hi[0] ? SPAN_LOWER
                                                                    : SPAN_FULL];
      const double sc0 = mx->sG * my->sM, sc1 = my->sG * mx->sM; /* span_scales */
      const mpm_lidx base = n - 1 - sy;                          /* node (-1, -1) */
      if (p) {
        double x[NMAX], t[NMAX], B[NMAX], f0[NMAX], f1[NMAX];
        for (int j = 0; j < NA; ++j)
          for (int i = 0; i < NA; ++i) x[i + NA * j] = p[base + j * sy + i];
        for (int j = 0; j < NA; ++j) line3(mx->M, x + NA * j, 1, t + NA * j, 1);
        for (int i = 0; i < NA; ++i) line3(my->G, t + i, NA, f1 + i, NA);
        for (int i = 0; i < NA; ++i) line3(my->M, x + i, NA, B + i, NA);
        for (int j = 0; j < NA; ++j) line3(mx->G, B + NA * j, 1, f0 + NA * j, 1);
        for (int j = 0; j < NA; ++j)
          for (int i = 0; i < NA; ++i) {
            f[0][base + j * sy + i] += sc0 * f0[i + NA * j];
            f[1][base + j * sy + i] += sc1 * f1[i + NA * j];
          }
      }
      if (v) {
        double x0[NMAX], x1[NMAX], y[NMAX], t[NMAX], u[NMAX];
        for (int j = 0; j < NA; ++j)
          for (int i = 0; i < NA; ++i) {
            x0[i + NA * j] = sc0 * v[0][base + j * sy + i];
            x1[i + NA * j] = sc1 * v[1][base + j * sy + i];
          }
        /* D = M_y G_x^T x0 + G_y^T M_x x1 (Horner over the axes). */
        for (int j = 0; j < NA; ++j) line3(mx->GT, x0 + NA * j, 1, y + NA * j, 1);
        for (int i = 0; i < NA; ++i) line3(my->M, y + i, NA, t + i, NA);
        for (int j = 0; j < NA; ++j) line3(mx->M, x1 + NA * j, 1, u + NA * j, 1);
        for (int i = 0; i < NA; ++i) {
          const double u0 = u[i], u1 = u[i + NA], u2 = u[i + 2 * NA];
          for (int a = 0; a < NA; ++a)
            t[i + NA * a] =
                t[i + NA * a] + (my->GT[a][0] * u0 + my->GT[a][1] * u1 + my->GT[a][2] * u2);
        }
        for (int j = 0; j < NA; ++j)
          for (int i = 0; i < NA; ++i) D[base + j * sy + i] += t[i + NA * j];
      }
    }
  }
}

/* axis_apply on a 3-D span's 27 values along axis d (a literal). */
static inline __attribute__((always_inline)) void apply27(const double A[NA][NA], int d,
                                                          const double *x, double *y, int add) {
  const int s = d == 0 ? 1 : d == 1 ? NA : NA * NA;
  for (int o = 0; o < 27; o += NA * s)
    for (int i = o; i < o + s; ++i) {
      const double x0 = x[i], x1 = x[i + s], x2 = x[i + 2 * s];
      for (int a = 0; a < NA; ++a) {
        const double r = A[a][0] * x0 + A[a][1] * x1 + A[a][2] * x2;
        y[i + a * s] = add ? y[i + a * s] + r : r;
      }
    }
}

/* The same walk in 3-D. Force: f_z from M_x then M_y, then B = M_z p shared by f_y (M_x) and,
 * after M_y, by f_x. Divergence by Horner over the axes: D = M_z (M_y G_x^T v_x + G_y^T M_x v_y)
 * + G_z^T M_y M_x v_z. */
static void integrate_3d(const mpm_grid *g, const mpm_span_set *s, const double *p,
                         double *const *f, const double *const *v, double *D) {
  axis_mats kind[SPAN_KINDS];
  kinds_fill(kind, g->dx);
  mpm_lidx off[NMAX];
  span_offsets(g, 3, off);
  int gi[3];
  for (gi[2] = s->lo[2]; gi[2] <= s->hi[2]; ++gi[2])
    for (gi[1] = s->lo[1]; gi[1] <= s->hi[1]; ++gi[1])
      for (gi[0] = s->lo[0]; gi[0] <= s->hi[0]; ++gi[0]) {
        const mpm_lidx n = mpm_grid_local_index(g, gi);
        if (s->skip && s->skip[n]) continue;
        const axis_mats *m[3];
        for (int d = 0; d < 3; ++d)
          m[d] = &kind[s->half_lo[d] && gi[d] == s->lo[d]   ? SPAN_UPPER
                       : s->half_hi[d] && gi[d] == s->hi[d] ? SPAN_LOWER
                                                            : SPAN_FULL];
        double sc[3];
        span_scales(m, 3, sc);
        if (p) {
          double B[NMAX], t0[NMAX], t1[NMAX], y[3][NMAX];
          for (int a = 0; a < 27; ++a) B[a] = p[n + off[a]];
          apply27(m[0]->M, 0, B, t0, 0);
          apply27(m[1]->M, 1, t0, t1, 0);
          apply27(m[2]->G, 2, t1, y[2], 0);
          apply27(m[2]->M, 2, B, t0, 0);
          apply27(m[0]->M, 0, t0, t1, 0);
          apply27(m[1]->G, 1, t1, y[1], 0);
          apply27(m[1]->M, 1, t0, B, 0);
          apply27(m[0]->G, 0, B, y[0], 0);
          for (int d = 0; d < 3; ++d)
            for (int a = 0; a < 27; ++a) f[d][n + off[a]] += sc[d] * y[d][a];
        }
        if (v) {
          double x[3][NMAX], Dl[NMAX], t0[NMAX], t1[NMAX];
          for (int d = 0; d < 3; ++d)
            for (int a = 0; a < 27; ++a) x[d][a] = sc[d] * v[d][n + off[a]];
          apply27(m[0]->GT, 0, x[0], Dl, 0);
          apply27(m[1]->M, 1, Dl, t1, 0);
          apply27(m[0]->M, 0, x[1], t0, 0);
          apply27(m[1]->GT, 1, t0, t1, 1);
          apply27(m[2]->M, 2, t1, Dl, 0);
          apply27(m[0]->M, 0, x[2], t0, 0);
          apply27(m[1]->M, 1, t0, t1, 0);
          apply27(m[2]->GT, 2, t1, Dl, 1);
          for (int a = 0; a < 27; ++a) D[n + off[a]] += Dl[a];
        }
      }
}

void mpm_span_plane(const mpm_grid *g, const mpm_span_set *s, int axis, const double *q,
                    double *f) {
  static const double E[NA][NA] = {{1, 6, 1}, {6, 36, 6}, {1, 6, 1}};
  const int dim = g->dim;
  axis_mats kind[SPAN_KINDS];
  kinds_fill(kind, g->dx);
  mpm_lidx off[NMAX];
  const int na = span_offsets(g, dim, off);
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, gi[3];
  for (int d = 0; d < dim; ++d) lo[d] = s->lo[d], hi[d] = s->hi[d];
  for (gi[2] = lo[2]; gi[2] <= hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] <= hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] <= hi[0]; ++gi[0]) {
        const mpm_lidx n = mpm_grid_local_index(g, gi);
        if (s->skip && s->skip[n]) continue;
        double x[2][NMAX], scale = 1.0 / 64;
        for (int a = 0; a < na; ++a) x[0][a] = q[n + off[a]];
        for (int d = 0; d < dim; ++d) {
          const axis_mats *m = &kind[s->half_lo[d] && gi[d] == s->lo[d]   ? SPAN_UPPER
                                     : s->half_hi[d] && gi[d] == s->hi[d] ? SPAN_LOWER
                                                                          : SPAN_FULL];
          axis_apply(d == axis ? E : m->M, d, dim, x[d & 1], x[(d + 1) & 1], 0);
          if (d != axis) scale *= m->sM;
        }
        for (int a = 0; a < na; ++a) f[n + off[a]] += scale * x[dim & 1][a];
      }
}

static void integrate(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f,
                      const double *const *v, double *D) {
  if (g->dim == 3)
    integrate_3d(g, s, p, f, v, D);
  else
    integrate_2d(g, s, p, f, v, D);
}

void mpm_span_force(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f) {
  integrate(g, s, p, f, NULL, NULL);
}

void mpm_span_divergence(const mpm_grid *g, const mpm_span_set *s, const double *const *v,
                         double *D) {
  integrate(g, s, NULL, NULL, v, D);
}
