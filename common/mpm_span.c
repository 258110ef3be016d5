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
 * 3-D, against the (3 x 3)^3 Gauss points times basis functions of the direct sum. M and G come
 * from the three-point Gauss rule, exact for their degree (at most 4), so the integrals are the
 * direct sum's to roundoff. Full, upper-half and lower-half spans each have their own M and G;
 * the grid's spacing is the same along every axis, so one set serves all axes. */
#include "mpm_span.h"

#include <string.h>

enum { NQ = 3, NA = 3, NMAX = 27 }; /* Gauss points and nodes per axis, nodes per span */

/* One span kind's matrices along an axis (per unit length for G's derivative, times dx for the
 * measure), and G's transpose for the divergence. */
typedef struct axis_mats {
  double M[NA][NA], G[NA][NA], GT[NA][NA];
} axis_mats;

enum { SPAN_FULL, SPAN_UPPER, SPAN_LOWER, SPAN_KINDS };

/* The matrices of t in [a, b] by the three-point Gauss rule mapped there. */
static void mats_fill(axis_mats *m, double a, double b, double dx) {
  static const double xi[NQ] = {-0.7745966692414834, 0.0, 0.7745966692414834}; /* sqrt(3/5) */
  static const double om[NQ] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  *m = (axis_mats){0};
  for (int q = 0; q < NQ; ++q) {
    const double s = 0.5 * (a + b) + 0.5 * (b - a) * xi[q];
    const double w = 0.5 * (b - a) * om[q] * dx;
    const double N[NA] = {0.5 * (0.5 - s) * (0.5 - s), 0.75 - s * s, 0.5 * (0.5 + s) * (0.5 + s)};
    const double dN[NA] = {-(0.5 - s) / dx, -2.0 * s / dx, (0.5 + s) / dx};
    for (int i = 0; i < NA; ++i)
      for (int j = 0; j < NA; ++j) m->M[i][j] += w * N[i] * N[j], m->G[i][j] += w * dN[i] * N[j];
  }
  for (int i = 0; i < NA; ++i)
    for (int j = 0; j < NA; ++j) m->GT[i][j] = m->G[j][i];
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

/* One walk over the spans of a dim-D grid: the force of p into f when p is set, the divergence
 * of v into D when v is set. dim is a constant at each call, so the axis loops unroll. */
static inline void integrate_dim(const mpm_grid *g, const mpm_span_set *s, int dim, const double *p,
                                 double *const *f, const double *const *v, double *D) {
  axis_mats kind[SPAN_KINDS];
  mats_fill(&kind[SPAN_FULL], -0.5, 0.5, g->dx);
  mats_fill(&kind[SPAN_UPPER], 0.0, 0.5, g->dx);
  mats_fill(&kind[SPAN_LOWER], -0.5, 0.0, g->dx);
  mpm_lidx stride[3] = {1, 0, 0};
  for (int d = 1; d < dim; ++d) stride[d] = stride[d - 1] * g->box_n[d - 1];
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int d = 0; d < dim; ++d) lo[d] = s->lo[d], hi[d] = s->hi[d];
  /* The 3^dim node offsets of a span, axis 0 fastest. */
  mpm_lidx off[NMAX];
  const int na = dim == 3 ? 27 : 9;
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
        const axis_mats *m[3];
        for (int d = 0; d < dim; ++d)
          m[d] = &kind[s->half_lo[d] && gi[d] == s->lo[d]   ? SPAN_UPPER
                       : s->half_hi[d] && gi[d] == s->hi[d] ? SPAN_LOWER
                                                            : SPAN_FULL];
        double x[3][NMAX], y[3][NMAX];
        if (p) {
          for (int a = 0; a < na; ++a) x[0][a] = p[n + off[a]];
          span_force(m, dim, x[0], y);
          for (int d = 0; d < dim; ++d)
            for (int a = 0; a < na; ++a) f[d][n + off[a]] += y[d][a];
        }
        if (v) {
          for (int d = 0; d < dim; ++d)
            for (int a = 0; a < na; ++a) x[d][a] = v[d][n + off[a]];
          span_divergence(m, dim, x, y[0]);
          for (int a = 0; a < na; ++a) D[n + off[a]] += y[0][a];
        }
      }
}

static void integrate(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f,
                      const double *const *v, double *D) {
  if (g->dim == 3)
    integrate_dim(g, s, 3, p, f, v, D);
  else
    integrate_dim(g, s, 2, p, f, v, D);
}

void mpm_span_force(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f) {
  integrate(g, s, p, f, NULL, NULL);
}

void mpm_span_divergence(const mpm_grid *g, const mpm_span_set *s, const double *const *v,
                         double *D) {
  integrate(g, s, NULL, NULL, v, D);
}
