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

/* f[d] = G_d prod_{e != d} M_e p on one span (m[e]: axis e's matrices). The M of the axes above
 * d are shared between the components: B holds them applied, from the top axis down. */
static inline void span_force(const axis_mats *const *m, int dim, const double *p,
                              double f[][NMAX]) {
  double B[NMAX], t[2][NMAX];
  const int n = dim == 3 ? 27 : 9;
  for (int a = 0; a < n; ++a) B[a] = p[a];
  for (int d = dim - 1; d >= 0; --d) {
    const double *x = B;
    for (int e = 0; e < d; ++e) axis_apply(m[e]->M, e, dim, x, t[e & 1], 0), x = t[e & 1];
    axis_apply(m[d]->G, d, dim, x, f[d], 0);
    if (d > 0) axis_apply(m[d]->M, d, dim, B, t[0], 0), memcpy(B, t[0], sizeof(double) * n);
  }
}

/* D = sum_d prod_{e != d} M_e G_d^T v_d on one span, the transpose of span_force (Horner over
 * the axes: acc = M_d acc + prod_{e < d} M_e G_d^T v_d). */
static inline void span_divergence(const axis_mats *const *m, int dim, double v[][NMAX],
                                   double *D) {
  double t[2][NMAX];
  for (int d = 0; d < dim; ++d) {
    if (d > 0) axis_apply(m[d]->M, d, dim, D, t[1], 0), memcpy(D, t[1], sizeof(t[1]));
    const double *x = v[d];
    for (int e = 0; e < d; ++e) axis_apply(m[e]->M, e, dim, x, t[e & 1], 0), x = t[e & 1];
    axis_apply(m[d]->GT, d, dim, x, D, d > 0);
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

/* One walk over the spans of a dim-D grid: the force of p into f when p is set, the divergence
 * of v into D when v is set. dim is a constant at each call, so the axis loops unroll. */
static inline void integrate_dim(const mpm_grid *g, const mpm_span_set *s, int dim, const double *p,
                                 double *const *f, const double *const *v, double *D) {
  axis_mats kind[SPAN_KINDS];
  kinds_fill(kind, g->dx);
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int d = 0; d < dim; ++d) lo[d] = s->lo[d], hi[d] = s->hi[d];
  mpm_lidx off[NMAX];
  const int na = span_offsets(g, dim, off);
  int gi[3];
  for (gi[2] = lo[2]; gi[2] <= hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] <= hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] <= hi[0]; ++gi[0]) {
        const mpm_lidx n = mpm_grid_local_index(g, gi);
        if (s->skip && s->skip[n]) continue;
        const axis_mats *m[3];
        for (int d = 0; d < dim; ++d)
          m[d] = &kind[s->half_lo[d] && gi[d] == s->lo[d]   ? SPAN_UPPER
                       : s->half_hi[d] && gi[d] == s->hi[d] ? SPAN_LOWER
                                                            : SPAN_FULL];
        double sc[3], x[3][NMAX], y[3][NMAX];
        span_scales(m, dim, sc);
        if (p) {
          for (int a = 0; a < na; ++a) x[0][a] = p[n + off[a]];
          span_force(m, dim, x[0], y);
          for (int d = 0; d < dim; ++d)
            for (int a = 0; a < na; ++a) f[d][n + off[a]] += sc[d] * y[d][a];
        }
        if (v) {
          for (int d = 0; d < dim; ++d)
            for (int a = 0; a < na; ++a) x[d][a] = sc[d] * v[d][n + off[a]];
          span_divergence(m, dim, x, y[0]);
          for (int a = 0; a < na; ++a) D[n + off[a]] += y[0][a];
        }
      }
}

/* y[a] = A[a][0] x[0] + A[a][1] x[s] + A[a][2] x[2 s], a = 0 .. 2 (y at stride t): one line of
 * axis_apply, in its order of operations. */
static inline void line3(const double A[NA][NA], const double *x, int s, double *y, int t) {
  const double x0 = x[0], x1 = x[s], x2 = x[2 * s];
  for (int a = 0; a < NA; ++a) y[a * t] = A[a][0] * x0 + A[a][1] * x1 + A[a][2] * x2;
}

/* integrate_dim for dim = 2, its products and sums in the same order (so the same bits), with
 * the axis loops written out: the sum-factorised span in registers, the kind of each span found
 * once per row and column. The 2-D gas runs it twice a step (the grid and hybrid pressures). */
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
        /* span_divergence: D = G_x^T x0, then D = M_y D, then D += G_y^T (M_x x1). */
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
    integrate_dim(g, s, 3, p, f, v, D);
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
