/* Exact span integrals of quadratic B-spline fields (see mpm_span.h).
 *
 * On a span with local coordinate t = (x - x_i) / dx in [-1/2, 1/2] the three B-splines per axis
 * are N_-(t) = (1/2 - t)^2 / 2, N_0(t) = 3/4 - t^2, N_+(t) = (1/2 + t)^2 / 2 (nodes i - 1, i,
 * i + 1). A half span integrates t over [0, 1/2] or [-1/2, 0] with the same rule mapped there.
 * Axes beyond the grid's dimension take one point of weight 1 and one "node" of value 1, so one
 * loop serves 2-D and 3-D. */
#include "mpm_span.h"

enum { NQ = 3, NA = 3 }; /* Gauss points and nodes per axis */

/* Per-axis tables of one span: the points' weights (times dx), and at each point the three
 * B-splines and their derivatives (per unit length). */
typedef struct axis_table {
  int nq, na;
  double w[NQ], N[NQ][NA], dN[NQ][NA];
} axis_table;

static void axis_fill(axis_table *t, double a, double b, double dx) {
  static const double xi[NQ] = {-0.7745966692414834, 0.0, 0.7745966692414834}; /* sqrt(3/5) */
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

/* One walk over the spans: the force of p into f when p is set, the divergence of v into D
 * when v is set. */
static void integrate(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f,
                      const double *const *v, double *D) {
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
  /* The (up to) 27 node offsets of a span, axis 0 fastest. */
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

void mpm_span_force(const mpm_grid *g, const mpm_span_set *s, const double *p, double *const *f) {
  integrate(g, s, p, f, NULL, NULL);
}

void mpm_span_divergence(const mpm_grid *g, const mpm_span_set *s, const double *const *v,
                         double *D) {
  integrate(g, s, NULL, NULL, v, D);
}
