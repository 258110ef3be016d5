/* Dimension-specific P2G and G2P; included by mpm_kernels2.c and mpm_kernels3.c with
 * MPM_DIM set to 2 or 3 (the p4est way: one source, two compilations). Not compiled alone.
 *
 * A stencil is the tensor product of 1-D weights: S = w0[i] w1[j] (w2[k]) and
 * dS/dx_d = dw_d / dx times the other weights. The kind is a compile-time constant inside
 * each specialised loop (the always-inline helpers are called with a literal). */
#include <math.h>

#if MPM_DIM == 2
#define DIMFN(name) name##_2d
#else
#define DIMFN(name) name##_3d
#endif

#define MPM_INLINE static inline __attribute__((always_inline))

#if MPM_DIM == 3
#define MAX_NODES (MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT)
#else
#define MAX_NODES (MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT)
#endif

/* The nodes a particle touches: box index, weight, weight gradient and offset x_i - x_p
 * of each. */
typedef struct {
  int count;
  mpm_lidx l[MAX_NODES];
  double w[MAX_NODES];
  double grad[MAX_NODES][MPM_DIM];
  double r[MAX_NODES][MPM_DIM];
} DIMFN(stencil);

/* Expand the tensor-product stencil of a particle at x into its node list. */
MPM_INLINE void DIMFN(stencil_eval)(const mpm_grid *g, mpm_shape_kind kind, const double *x,
                                    double lp, DIMFN(stencil) * s) {
  const int S = mpm_shape_support(kind);
  const double inv_dx = 1.0 / g->dx;
  double w[MPM_DIM][MPM_SHAPE_MAX_SUPPORT], dw[MPM_DIM][MPM_SHAPE_MAX_SUPPORT];
  double r[MPM_DIM][MPM_SHAPE_MAX_SUPPORT];
  int gi[MPM_DIM];
  for (int d = 0; d < MPM_DIM; ++d) {
    const double xi = (x[d] - g->lo[d]) * inv_dx;
    gi[d] = mpm_shape_1d(kind, xi, lp, w[d], dw[d]);
    for (int k = 0; k < MPM_SHAPE_MAX_SUPPORT; ++k) {
      dw[d][k] *= inv_dx;
      r[d][k] = (gi[d] + k - xi) * g->dx;
    }
  }
  const mpm_lidx first = mpm_grid_local_index(g, gi), sy = g->box_n[0];
  int q = 0;
#if MPM_DIM == 3
  const mpm_lidx sz = (mpm_lidx)g->box_n[0] * g->box_n[1];
  for (int k = 0; k < S; ++k)
#endif
    for (int j = 0; j < S; ++j)
      for (int i = 0; i < S; ++i, ++q) {
#if MPM_DIM == 3
        const double wjk = w[1][j] * w[2][k];
        s->grad[q][0] = dw[0][i] * wjk;
        s->grad[q][1] = w[0][i] * dw[1][j] * w[2][k];
        s->grad[q][2] = w[0][i] * w[1][j] * dw[2][k];
        s->r[q][2] = r[2][k];
        s->l[q] = first + i + j * sy + k * sz;
#else
      const double wjk = w[1][j];
      s->grad[q][0] = dw[0][i] * wjk;
      s->grad[q][1] = w[0][i] * dw[1][j];
      s->l[q] = first + i + j * sy;
#endif
        s->r[q][0] = r[0][i];
        s->r[q][1] = r[1][j];
        s->w[q] = w[0][i] * wjk;
      }
  s->count = q;
}

/* apic (a literal) selects the affine momentum term at compile time. */
MPM_INLINE void DIMFN(p2g_loop)(mpm_grid *g, mpm_grid_phase *ph, const mpm_p2g_args *a,
                                mpm_shape_kind kind, int apic) {
  const size_t n = (size_t)a->n;
  for (mpm_lidx p = 0; p < a->n; ++p) {
    double x[MPM_DIM], mv[MPM_DIM], b[MPM_DIM], sig[MPM_DIM][MPM_DIM], mC[MPM_DIM][MPM_DIM];
    const double m = a->m[p];
    for (int d = 0; d < MPM_DIM; ++d) {
      x[d] = a->x[d][p], mv[d] = m * a->v[d][p];
      b[d] = m * a->gravity[d] + (a->fext[0] ? a->fext[d][p] : 0.0);
    }
    for (int r = 0; r < MPM_DIM; ++r)
      for (int c = 0; c < MPM_DIM; ++c) {
        sig[r][c] = a->vsig ? a->vsig[(size_t)(r * MPM_DIM + c) * n + p] : 0.0;
        mC[r][c] = apic ? m * a->C[(size_t)(r * MPM_DIM + c) * n + p] : 0.0;
      }
    DIMFN(stencil) s;
    DIMFN(stencil_eval)(g, kind, x, a->lp, &s);
    for (int q = 0; q < s.count; ++q) {
      const mpm_lidx l = s.l[q];
      const double w = s.w[q];
      ph->m_i[l] += w * m;
      for (int d = 0; d < MPM_DIM; ++d) {
        double f = w * b[d], mvq = mv[d];
        for (int c = 0; c < MPM_DIM; ++c) {
          f -= sig[d][c] * s.grad[q][c];
          if (apic) mvq += mC[d][c] * s.r[q][c];
        }
        ph->mv_i[d][l] += w * mvq;
        ph->f_i[d][l] += f;
      }
    }
  }
}

static void DIMFN(p2g)(mpm_grid *g, int phase, const mpm_p2g_args *a) {
  mpm_grid_phase *ph = &g->phase[phase];
  const int apic = a->C != NULL;
  switch (g->shape) {
  case MPM_SHAPE_LINEAR:
    if (apic)
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_LINEAR, 1);
    else
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_LINEAR, 0);
    break;
  case MPM_SHAPE_GIMP:
    if (apic)
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_GIMP, 1);
    else
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_GIMP, 0);
    break;
  case MPM_SHAPE_QUADRATIC:
    if (apic)
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_QUADRATIC, 1);
    else
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_QUADRATIC, 0);
    break;
  default:
    if (apic)
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_CUBIC, 1);
    else
      DIMFN(p2g_loop)(g, ph, a, MPM_SHAPE_CUBIC, 0);
    break;
  }
}

/* The B-spline APIC moment: with apic_b (a literal) the loop also sums S v_i (x_i - x_p)^T,
 * which C_p = D^-1 (that sum) needs for quadratic and cubic weights. */
MPM_INLINE void DIMFN(g2p_loop)(const mpm_grid *g, const mpm_g2p_args *a, mpm_shape_kind kind,
                                int apic_b) {
  const size_t n = (size_t)a->n;
  /* D^-1 of the B-spline moment sum_i S_ip (x_i - x_p)(x_i - x_p)^T = D I. */
  const double Dinv = (kind == MPM_SHAPE_CUBIC ? 3.0 : 4.0) / (g->dx * g->dx);
  for (mpm_lidx p = 0; p < a->n; ++p) {
    double x[MPM_DIM], v[MPM_DIM] = {0}, acc[MPM_DIM] = {0}, L[MPM_DIM][MPM_DIM] = {{0}};
    double B[MPM_DIM][MPM_DIM] = {{0}};
    for (int d = 0; d < MPM_DIM; ++d) x[d] = a->x[d][p];
    DIMFN(stencil) s;
    DIMFN(stencil_eval)(g, kind, x, a->lp, &s);
    for (int q = 0; q < s.count; ++q) {
      const mpm_lidx l = s.l[q];
      const double w = s.w[q];
      for (int d = 0; d < MPM_DIM; ++d) {
        const double vi = a->v_i[d][l], wv = w * vi;
        v[d] += wv;
        acc[d] += w * a->a_i[d][l];
        for (int c = 0; c < MPM_DIM; ++c) {
          L[d][c] += vi * s.grad[q][c];
          if (apic_b) B[d][c] += wv * s.r[q][c];
        }
      }
    }
    for (int d = 0; d < MPM_DIM; ++d) {
      a->v_out[d][p] = v[d];
      a->a_out[d][p] = acc[d];
    }
    if (a->L_out)
      for (int r = 0; r < MPM_DIM; ++r)
        for (int c = 0; c < MPM_DIM; ++c) a->L_out[(size_t)(r * MPM_DIM + c) * n + p] = L[r][c];
    if (a->C_out)
      for (int r = 0; r < MPM_DIM; ++r)
        for (int c = 0; c < MPM_DIM; ++c)
          a->C_out[(size_t)(r * MPM_DIM + c) * n + p] = apic_b ? Dinv * B[r][c] : L[r][c];
  }
}

static void DIMFN(g2p)(const mpm_grid *g, const mpm_g2p_args *a) {
  const int apic_b = a->C_out != NULL;
  switch (g->shape) {
  case MPM_SHAPE_LINEAR:
    DIMFN(g2p_loop)(g, a, MPM_SHAPE_LINEAR, 0);
    break;
  case MPM_SHAPE_GIMP:
    DIMFN(g2p_loop)(g, a, MPM_SHAPE_GIMP, 0);
    break;
  case MPM_SHAPE_QUADRATIC:
    if (apic_b)
      DIMFN(g2p_loop)(g, a, MPM_SHAPE_QUADRATIC, 1);
    else
      DIMFN(g2p_loop)(g, a, MPM_SHAPE_QUADRATIC, 0);
    break;
  default:
    if (apic_b)
      DIMFN(g2p_loop)(g, a, MPM_SHAPE_CUBIC, 1);
    else
      DIMFN(g2p_loop)(g, a, MPM_SHAPE_CUBIC, 0);
    break;
  }
}

const mpm_kernels DIMFN(mpm_kernels) = {MPM_DIM, DIMFN(p2g), DIMFN(g2p)};

#undef DIMFN
#undef MPM_INLINE
#undef MAX_NODES
