/* Dimension-specific P2G and G2P; included by mpm_kernels2.c and mpm_kernels3.c with
 * MPM_DIM set to 2 or 3 (the p4est way: one source, two compilations). Not compiled alone.
 *
 * A stencil is the tensor product of 1-D weights: S = wx[i] wy[j] (wz[k]) and
 * grad S = (dwx wy wz, wx dwy wz, wx wy dwz). Both kernels factor these products by axis
 * instead of forming every node's weight and gradient: P2G builds, per particle, the
 * contribution to each node of one x-y layer of its stencil from per-axis factors, and in
 * 3-D scales that layer by wz[k] and dwz[k]; G2P first sums each x-row of nodes with the
 * x-weights and then combines the row sums with the y (and z) weights. The sums are the
 * node-by-node ones with fewer multiplications; only the rounding differs.
 *
 * The shape kind and the optional terms (APIC) are compile-time constants inside each
 * specialised loop (the always-inline helpers are called with literals), so the stencil
 * loops are fully unrolled and an option that is off costs nothing. The lattice constants
 * are copied to locals first: the compiler must otherwise assume that every store into a
 * nodal array could change them and load them again. */
#include <assert.h>
#include <math.h>

#if MPM_DIM == 2
#define DIMFN(name) name##_2d
#else
#define DIMFN(name) name##_3d
#endif

#define MPM_INLINE static inline __attribute__((always_inline))
#define SMAX       MPM_SHAPE_MAX_SUPPORT
/* Nodes per direction of a kind: a constant expression once the kind is a literal. */
#define SUPPORT(kind) ((kind) == MPM_SHAPE_LINEAR ? 2 : (kind) == MPM_SHAPE_CUBIC ? 4 : 3)

/* The lattice as the kernels need it, read once per call. */
typedef struct {
  double lo[MPM_DIM], dx, inv_dx, lp;
  int box_lo[MPM_DIM];
  mpm_lidx sy, sz;   /* index strides of y and z in the box */
  int wrap[MPM_DIM]; /* positions wrapped along d (mpm_kernels.h) */
  double wrap_lo[MPM_DIM], wrap_hi[MPM_DIM];
} DIMFN(lattice);

static DIMFN(lattice)
    DIMFN(lattice_of)(const mpm_grid *g, double lp, const double *wrap_lo, const double *wrap_hi) {
  DIMFN(lattice) L = {.dx = g->dx, .inv_dx = 1.0 / g->dx, .lp = lp};
  for (int d = 0; d < MPM_DIM; ++d) {
    L.lo[d] = g->lo[d], L.box_lo[d] = g->box_lo[d];
    L.wrap[d] = wrap_hi[d] > wrap_lo[d], L.wrap_lo[d] = wrap_lo[d], L.wrap_hi[d] = wrap_hi[d];
  }
  L.sy = g->box_n[0];
  L.sz = (mpm_lidx)g->box_n[0] * g->box_n[1];
  return L;
}

/* The 1-D weights of one particle along each axis. */
typedef struct {
  mpm_lidx first;           /* box index of the stencil's first node */
  double w[MPM_DIM][SMAX];  /* weights */
  double dw[MPM_DIM][SMAX]; /* their derivatives, 1/m */
  double r[MPM_DIM][SMAX];  /* node minus particle position, m (only when asked) */
} DIMFN(weights);

MPM_INLINE void DIMFN(weights_eval)(const DIMFN(lattice) * L, mpm_shape_kind kind, const double *x,
                                    int with_r, DIMFN(weights) * s) {
  int gi[MPM_DIM];
  for (int d = 0; d < MPM_DIM; ++d) {
    const double xd = L->wrap[d] ? mpm_wrap_coord(x[d], L->wrap_lo[d], L->wrap_hi[d]) : x[d];
    const double xi = (xd - L->lo[d]) * L->inv_dx;
    gi[d] = mpm_shape_1d(kind, xi, L->lp, s->w[d], s->dw[d]);
    for (int k = 0; k < SUPPORT(kind); ++k) {
      s->dw[d][k] *= L->inv_dx;
      if (with_r) s->r[d][k] = (gi[d] + k - xi) * L->dx;
    }
  }
  s->first = (gi[0] - L->box_lo[0]) + L->sy * (gi[1] - L->box_lo[1]);
#if MPM_DIM == 3
  s->first += L->sz * (gi[2] - L->box_lo[2]);
#endif
}

/* ---- P2G ---------------------------------------------------------------------------------- */

/* With apic (a literal) the momentum carries the affine term S m C_p (x_i - x_p); with grad (a
 * literal) the mass gradient m grad S goes to normal_i. */
MPM_INLINE void DIMFN(p2g_loop)(const DIMFN(lattice) * L, mpm_grid_phase *ph, const mpm_p2g_args *a,
                                mpm_shape_kind kind, int apic, int grad) {
  enum { D = MPM_DIM };
  const int S = SUPPORT(kind);
  const size_t n = (size_t)a->n;
  double *restrict mi = ph->m_i;
  double *restrict mvi[D], *restrict fi[D], *restrict ni[D];
  const double *restrict xp[D], *restrict vp[D], *restrict fext[D];
  const double *restrict mp = a->m, *restrict vsig = a->vsig, *restrict C = a->C;
  double grav[D];
  for (int d = 0; d < D; ++d) {
    mvi[d] = ph->mv_i[d], fi[d] = ph->f_i[d], ni[d] = ph->normal_i[d];
    xp[d] = a->x[d], vp[d] = a->v[d], fext[d] = a->fext[0] ? a->fext[d] : NULL;
    grav[d] = a->gravity[d];
  }
  const mpm_lidx *restrict idx = a->idx;
  const size_t count = idx ? (size_t)a->nidx : n;
  for (size_t it = 0; it < count; ++it) {
    const size_t p = idx ? (size_t)idx[it] : it;
    double x[D], mv[D], b[D], sig[D][D], mC[D][D];
    const double m = mp[p];
    for (int d = 0; d < D; ++d) {
      x[d] = xp[d][p], mv[d] = m * vp[d][p];
      b[d] = m * grav[d] + (fext[0] ? fext[d][p] : 0.0); /* body force S b, N per unit S */
    }
    for (int r = 0; r < D; ++r)
      for (int c = 0; c < D; ++c) {
        sig[r][c] = vsig ? vsig[(size_t)(r * D + c) * n + p] : 0.0;
        if (apic) mC[r][c] = m * C[(size_t)(r * D + c) * n + p];
      }
    DIMFN(weights) s;
    DIMFN(weights_eval)(L, kind, x, apic, &s);
    const double *wx = s.w[0], *dwx = s.dw[0], *wy = s.w[1], *dwy = s.dw[1];

    /* x factors: f_d = wy (wx b_d - sig_d0 dwx) - dwy (sig_d1 wx) [- dwz wy (sig_d2 wx)],
     * times wz in 3-D; momentum wx (m v_d + m C_d0 rx) + wx ry (m C_d1) [+ ...]. */
    double mwx[SMAX], P[D][SMAX], Q[D][SMAX], MX[D][SMAX], CY[D][SMAX];
#if MPM_DIM == 3
    double R[D][SMAX], CZ[D][SMAX];
#endif
    for (int i = 0; i < S; ++i) {
      mwx[i] = m * wx[i];
      for (int d = 0; d < D; ++d) {
        P[d][i] = wx[i] * b[d] - sig[d][0] * dwx[i];
        Q[d][i] = sig[d][1] * wx[i];
        MX[d][i] = wx[i] * (apic ? mv[d] + mC[d][0] * s.r[0][i] : mv[d]);
        if (apic) CY[d][i] = wx[i] * mC[d][1];
#if MPM_DIM == 3
        R[d][i] = sig[d][2] * wx[i];
        if (apic) CZ[d][i] = wx[i] * mC[d][2];
#endif
      }
    }
#if MPM_DIM == 2
    for (int j = 0; j < S; ++j) {
      const mpm_lidx row = s.first + j * L->sy;
      const double ry = apic ? s.r[1][j] : 0.0;
      for (int i = 0; i < S; ++i) {
        mi[row + i] += wy[j] * mwx[i];
        for (int d = 0; d < D; ++d) {
          mvi[d][row + i] += wy[j] * (apic ? MX[d][i] + ry * CY[d][i] : MX[d][i]);
          fi[d][row + i] += wy[j] * P[d][i] - dwy[j] * Q[d][i];
        }
        if (grad) {
          ni[0][row + i] += wy[j] * m * dwx[i];
          ni[1][row + i] += dwy[j] * mwx[i];
        }
      }
    }
#else
    /* One x-y layer of the stencil: mass, momentum, force and their z parts; each is used
     * for every z-layer. */
    double lm[SMAX][SMAX], lmv[D][SMAX][SMAX], lf[D][SMAX][SMAX];
    double lmvz[D][SMAX][SMAX], lfz[D][SMAX][SMAX];
    for (int j = 0; j < S; ++j)
      for (int i = 0; i < S; ++i) {
        lm[j][i] = wy[j] * mwx[i];
        for (int d = 0; d < D; ++d) {
          lmv[d][j][i] = wy[j] * (apic ? MX[d][i] + s.r[1][j] * CY[d][i] : MX[d][i]);
          lf[d][j][i] = wy[j] * P[d][i] - dwy[j] * Q[d][i];
          lfz[d][j][i] = wy[j] * R[d][i];
          if (apic) lmvz[d][j][i] = wy[j] * CZ[d][i];
        }
      }
    for (int k = 0; k < S; ++k) {
      const double wz = s.w[2][k], dwz = s.dw[2][k], rz = apic ? s.r[2][k] : 0.0;
      for (int j = 0; j < S; ++j) {
        const mpm_lidx row = s.first + j * L->sy + k * L->sz;
        for (int i = 0; i < S; ++i) {
          mi[row + i] += wz * lm[j][i];
          for (int d = 0; d < D; ++d) {
            mvi[d][row + i] += wz * (apic ? lmv[d][j][i] + rz * lmvz[d][j][i] : lmv[d][j][i]);
            fi[d][row + i] += wz * lf[d][j][i] - dwz * lfz[d][j][i];
          }
          if (grad) {
            ni[0][row + i] += wz * wy[j] * m * dwx[i];
            ni[1][row + i] += wz * dwy[j] * mwx[i];
            ni[2][row + i] += dwz * lm[j][i];
          }
        }
      }
    }
#endif
  }
}

/* The lean deposit (mpm_kernels.h): S m into m_i when mass, with scalar (a literal; mass and
 * no stress) S m s into mv_i[0] as the full loop forms m v_0 and its x factors, and with stress
 * (a literal: 0 none, 1 the isotropic viso, 2 the full vsig) the force -V sigma grad S into f_i.
 * Each product is the full loop's for zero velocity (there P_d = -sig_d0 dwx, Q_d = sig_d1 wx and
 * the zero body force adds nothing; a - b = -(b - a) exactly), so the sums agree bitwise. The force
 * factors: f_d -= wy X_d + dwy Y_d [wz (...) + dwz wy Z_d in 3-D], X_d = sig_d0 dwx, Y_d = sig_d1
 * wx, Z_d = sig_d2 wx; the isotropic stress keeps only the diagonal terms. */
MPM_INLINE void DIMFN(p2g_lean_loop)(const DIMFN(lattice) * L, mpm_grid_phase *ph,
                                     const mpm_p2g_args *a, mpm_shape_kind kind, int mass,
                                     int scalar, int stress) {
  enum { D = MPM_DIM };
  const int S = SUPPORT(kind);
  const size_t n = (size_t)a->n;
  double *restrict mi = ph->m_i, *restrict si = ph->mv_i[0], *restrict fi[D];
  const double *restrict xp[D], *restrict mp = a->m, *restrict viso = a->viso;
  const double *restrict vsig = a->vsig, *restrict sp = a->s;
  for (int d = 0; d < D; ++d) fi[d] = ph->f_i[d], xp[d] = a->x[d];
  const mpm_lidx *restrict idx = a->idx;
  const size_t count = idx ? (size_t)a->nidx : n;
  for (size_t it = 0; it < count; ++it) {
    const size_t p = idx ? (size_t)idx[it] : it;
    double x[D], sig[D][D];
    for (int d = 0; d < D; ++d) x[d] = xp[d][p];
    const double m = mass ? mp[p] : 0.0, q = stress == 1 ? viso[p] : 0.0;
    const double ms = scalar ? m * sp[p] : 0.0;
    for (int r = 0; stress == 2 && r < D; ++r)
      for (int c = 0; c < D; ++c) sig[r][c] = vsig[(size_t)(r * D + c) * n + p];
    DIMFN(weights) s;
    DIMFN(weights_eval)(L, kind, x, 0, &s);
    const double *wx = s.w[0], *dwx = s.dw[0], *wy = s.w[1], *dwy = s.dw[1];
    double mwx[SMAX], swx[SMAX], X[D][SMAX], Y[D][SMAX];
#if MPM_DIM == 3
    double Z[D][SMAX];
#endif
    for (int i = 0; i < S; ++i) {
      mwx[i] = m * wx[i];
      swx[i] = wx[i] * ms;
      for (int d = 0; d < D; ++d) {
        X[d][i] = stress == 2 ? sig[d][0] * dwx[i] : q * dwx[i];
        Y[d][i] = stress == 2 ? sig[d][1] * wx[i] : q * wx[i];
#if MPM_DIM == 3
        Z[d][i] = stress == 2 ? sig[d][2] * wx[i] : q * wx[i];
#endif
      }
    }
#if MPM_DIM == 2
    for (int j = 0; j < S; ++j) {
      const mpm_lidx row = s.first + j * L->sy;
      for (int i = 0; i < S; ++i) {
        if (mass) mi[row + i] += wy[j] * mwx[i];
        if (scalar) si[row + i] += wy[j] * swx[i];
        if (stress == 1) {
          fi[0][row + i] -= wy[j] * X[0][i];
          fi[1][row + i] -= dwy[j] * Y[1][i];
        }
        for (int d = 0; stress == 2 && d < D; ++d)
          fi[d][row + i] -= wy[j] * X[d][i] + dwy[j] * Y[d][i];
      }
    }
#else
    double lm[SMAX][SMAX], ls[SMAX][SMAX], lf[D][SMAX][SMAX], lz[D][SMAX][SMAX];
    for (int j = 0; j < S; ++j)
      for (int i = 0; i < S; ++i) {
        lm[j][i] = wy[j] * mwx[i];
        ls[j][i] = wy[j] * swx[i];
        if (stress == 1) {
          lf[0][j][i] = wy[j] * X[0][i], lf[1][j][i] = dwy[j] * Y[1][i];
          lz[2][j][i] = wy[j] * Z[2][i];
        }
        for (int d = 0; stress == 2 && d < D; ++d) {
          lf[d][j][i] = wy[j] * X[d][i] + dwy[j] * Y[d][i];
          lz[d][j][i] = wy[j] * Z[d][i];
        }
      }
    for (int k = 0; k < S; ++k) {
      const double wz = s.w[2][k], dwz = s.dw[2][k];
      for (int j = 0; j < S; ++j) {
        const mpm_lidx row = s.first + j * L->sy + k * L->sz;
        for (int i = 0; i < S; ++i) {
          if (mass) mi[row + i] += wz * lm[j][i];
          if (scalar) si[row + i] += wz * ls[j][i];
          if (stress == 1) {
            fi[0][row + i] -= wz * lf[0][j][i];
            fi[1][row + i] -= wz * lf[1][j][i];
            fi[2][row + i] -= dwz * lz[2][j][i];
          }
          for (int d = 0; stress == 2 && d < D; ++d)
            fi[d][row + i] -= wz * lf[d][j][i] + dwz * lz[d][j][i];
        }
      }
    }
#endif
  }
}

/* The lean deposit of one shape kind, its terms as literals. */
MPM_INLINE void DIMFN(p2g_lean)(const DIMFN(lattice) * L, mpm_grid_phase *ph, const mpm_p2g_args *a,
                                mpm_shape_kind kind) {
  const int stress = a->vsig ? 2 : a->viso ? 1 : 0;
  if (a->s)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 1, 1, 0);
  else if (a->m && stress == 1)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 1, 0, 1);
  else if (a->m && stress == 0)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 1, 0, 0);
  else if (a->m)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 1, 0, 2);
  else if (stress == 1)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 0, 0, 1);
  else if (stress == 2)
    DIMFN(p2g_lean_loop)(L, ph, a, kind, 0, 0, 2);
}

static void DIMFN(p2g)(mpm_grid *g, int phase, const mpm_p2g_args *a) {
  mpm_grid_phase *ph = &g->phase[phase];
  const DIMFN(lattice) L = DIMFN(lattice_of)(g, a->lp, a->wrap_lo, a->wrap_hi);
  if (!a->v[0]) {
    assert(!(a->vsig && a->viso) && !a->C && !a->fext[0] && !(a->m && ph->normals));
    assert(!a->s || (a->m && !a->vsig && !a->viso));
    switch (g->shape) {
    case MPM_SHAPE_LINEAR:
      DIMFN(p2g_lean)(&L, ph, a, MPM_SHAPE_LINEAR);
      break;
    case MPM_SHAPE_GIMP:
      DIMFN(p2g_lean)(&L, ph, a, MPM_SHAPE_GIMP);
      break;
    case MPM_SHAPE_QUADRATIC:
      DIMFN(p2g_lean)(&L, ph, a, MPM_SHAPE_QUADRATIC);
      break;
    default:
      DIMFN(p2g_lean)(&L, ph, a, MPM_SHAPE_CUBIC);
    }
    return;
  }
  assert(!a->viso && !a->s);
  const int apic = a->C != NULL, grad = ph->normals;
#define P2G_CASE(kind)                                                                             \
  case kind:                                                                                       \
    if (apic && grad)                                                                              \
      DIMFN(p2g_loop)(&L, ph, a, kind, 1, 1);                                                      \
    else if (apic)                                                                                 \
      DIMFN(p2g_loop)(&L, ph, a, kind, 1, 0);                                                      \
    else if (grad)                                                                                 \
      DIMFN(p2g_loop)(&L, ph, a, kind, 0, 1);                                                      \
    else                                                                                           \
      DIMFN(p2g_loop)(&L, ph, a, kind, 0, 0);                                                      \
    break;
  switch (g->shape) {
    P2G_CASE(MPM_SHAPE_LINEAR)
    P2G_CASE(MPM_SHAPE_GIMP)
    P2G_CASE(MPM_SHAPE_QUADRATIC)
  default:
    P2G_CASE(MPM_SHAPE_CUBIC)
  }
#undef P2G_CASE
}

/* ---- G2P ---------------------------------------------------------------------------------- */

/* With apic_b (a literal) the loop also sums S v_i (x_i - x_p)^T, the B-spline APIC moment:
 * C_p = D^-1 times that sum, from sum_i S (x_i - x_p)(x_i - x_p)^T = D I. nsc is the number
 * of extra scalars when it is a literal (0, 1 or 2, the common cases: the sums then stay in
 * registers), or -1 to read it from a. vel (a literal) is 0 in the scalar gather, which then
 * forms only the diagonal of L, and that only when div (a literal) asks for its trace; the
 * diagonal's sums are the full gather's. */
MPM_INLINE void DIMFN(g2p_loop)(const DIMFN(lattice) * L, const mpm_g2p_args *a,
                                mpm_shape_kind kind, int apic_b, int nsc, int vel, int div) {
  enum { D = MPM_DIM };
  const int S = SUPPORT(kind);
  const size_t n = (size_t)a->n;
  const int nscalar = nsc >= 0 ? nsc : a->nscalar;
  const int grad = vel || div; /* L, or its diagonal, is formed */
  const double *restrict s_i[MPM_KERNELS_MAX_SCALARS] = {NULL};
  for (int q = 0; q < nscalar; ++q) s_i[q] = a->s_i[q];
  const double Dinv = (kind == MPM_SHAPE_CUBIC ? 3.0 : 4.0) * L->inv_dx * L->inv_dx;
  const double *restrict xp[D], *restrict vi[D], *restrict ai[D];
  double *restrict vout[D], *restrict aout[D], *restrict divout = div ? a->div_out : NULL;
  const double *restrict F = a->LF_out ? a->F : NULL;
  double *restrict Lout = a->L_out, *restrict Cout = a->C_out, *restrict LF = a->LF_out;
  for (int d = 0; d < D; ++d) {
    xp[d] = a->x[d], vi[d] = a->v_i[d], ai[d] = a->a_i[d];
    vout[d] = a->v_out[d], aout[d] = a->a_out[d];
  }
  const mpm_lidx *restrict idx = a->idx;
  const size_t count = idx ? (size_t)a->nidx : n;
  for (size_t it = 0; it < count; ++it) {
    const size_t p = idx ? (size_t)idx[it] : it;
    double x[D], v[D] = {0}, acc[D] = {0}, Lg[D][D] = {{0}}, B[D][D] = {{0}};
    double sc[MPM_KERNELS_MAX_SCALARS] = {0};
    for (int d = 0; d < D; ++d) x[d] = xp[d][p];
    DIMFN(weights) s;
    DIMFN(weights_eval)(L, kind, x, apic_b, &s);
    const double *wx = s.w[0], *dwx = s.dw[0], *wy = s.w[1], *dwy = s.dw[1];
    double wrx[SMAX];
    if (apic_b)
      for (int i = 0; i < S; ++i) wrx[i] = wx[i] * s.r[0][i];
#if MPM_DIM == 3
    for (int k = 0; k < S; ++k) {
      const double wz = s.w[2][k], dwz = s.dw[2][k];
#else
    {
      const double wz = 1.0;
#endif
      for (int j = 0; j < S; ++j) {
#if MPM_DIM == 3
        const mpm_lidx row = s.first + j * L->sy + k * L->sz;
#else
        const mpm_lidx row = s.first + j * L->sy;
#endif
        /* Row sums with the x weights: S wx v, S dwx v, S wx a (and S wx rx v); the diagonal
         * of L needs S dwx v_0 and S wx v_d for d > 0. */
        double sv[D] = {0}, sd[D] = {0}, sa[D] = {0}, sr[D] = {0};
        for (int i = 0; grad && i < S; ++i)
          for (int d = 0; d < D; ++d) {
            const double vn = vi[d][row + i];
            if (vel || d > 0) sv[d] += wx[i] * vn;
            if (vel || d == 0) sd[d] += dwx[i] * vn;
            if (vel) sa[d] += wx[i] * ai[d][row + i];
            if (apic_b) sr[d] += wrx[i] * vn;
          }
        const double wyz = wy[j] * wz, dwyz = dwy[j] * wz;
        for (int q = 0; q < nscalar; ++q) { /* extra nodal scalars */
          double ss = 0.0;
          for (int i = 0; i < S; ++i) ss += wx[i] * s_i[q][row + i];
          sc[q] += wyz * ss;
        }
        for (int d = 0; grad && d < D; ++d) {
          if (vel) v[d] += wyz * sv[d];
          if (vel) acc[d] += wyz * sa[d];
          if (vel || d == 0) Lg[d][0] += wyz * sd[d];
          if (vel || d == 1) Lg[d][1] += dwyz * sv[d];
#if MPM_DIM == 3
          if (vel || d == 2) Lg[d][2] += wy[j] * dwz * sv[d];
#endif
          if (apic_b) {
            B[d][0] += wyz * sr[d];
            B[d][1] += wyz * s.r[1][j] * sv[d];
#if MPM_DIM == 3
            B[d][2] += wyz * s.r[2][k] * sv[d];
#endif
          }
        }
      }
    }
    if (div) {
      double tr = Lg[0][0];
      for (int d = 1; d < D; ++d) tr += Lg[d][d];
      divout[p] = tr;
    }
    if (!vel) {
      for (int q = 0; q < nscalar; ++q) a->s_out[q][p] = sc[q];
      continue;
    }
    for (int d = 0; d < D; ++d) vout[d][p] = v[d], aout[d][p] = acc[d];
    for (int q = 0; q < nscalar; ++q) a->s_out[q][p] = sc[q];
    if (Lout)
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) Lout[(size_t)(r * D + c) * n + p] = Lg[r][c];
    if (Cout)
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c)
          Cout[(size_t)(r * D + c) * n + p] = apic_b ? Dinv * B[r][c] : Lg[r][c];
    if (LF) {
      double f[D][D];
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) f[r][c] = F[(size_t)(r * D + c) * n + p];
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) {
          double sum = 0.0;
          for (int k = 0; k < D; ++k) sum += Lg[r][k] * f[k][c];
          LF[(size_t)(r * D + c) * n + p] = sum;
        }
    }
  }
}

/* The scalar gather of one shape kind: the quadratic B-spline's common cases as literals (the
 * grid pressure's corrections read one or two scalars, or the divergence alone). */
MPM_INLINE void DIMFN(g2p_scalar)(const DIMFN(lattice) * L, const mpm_g2p_args *a,
                                  mpm_shape_kind kind) {
  const int div = a->div_out != NULL;
  if (kind == MPM_SHAPE_QUADRATIC && div && a->nscalar == 0)
    DIMFN(g2p_loop)(L, a, kind, 0, 0, 0, 1);
  else if (kind == MPM_SHAPE_QUADRATIC && !div && a->nscalar == 1)
    DIMFN(g2p_loop)(L, a, kind, 0, 1, 0, 0);
  else if (kind == MPM_SHAPE_QUADRATIC && !div && a->nscalar == 2)
    DIMFN(g2p_loop)(L, a, kind, 0, 2, 0, 0);
  else if (div)
    DIMFN(g2p_loop)(L, a, kind, 0, -1, 0, 1);
  else
    DIMFN(g2p_loop)(L, a, kind, 0, -1, 0, 0);
}

static void DIMFN(g2p)(const mpm_grid *g, const mpm_g2p_args *a) {
  const DIMFN(lattice) L = DIMFN(lattice_of)(g, a->lp, a->wrap_lo, a->wrap_hi);
  if (!a->v_out[0]) {
    assert(!a->a_out[0] && !a->L_out && !a->C_out && !a->LF_out);
    switch (g->shape) {
    case MPM_SHAPE_LINEAR:
      DIMFN(g2p_scalar)(&L, a, MPM_SHAPE_LINEAR);
      break;
    case MPM_SHAPE_GIMP:
      DIMFN(g2p_scalar)(&L, a, MPM_SHAPE_GIMP);
      break;
    case MPM_SHAPE_QUADRATIC:
      DIMFN(g2p_scalar)(&L, a, MPM_SHAPE_QUADRATIC);
      break;
    default:
      DIMFN(g2p_scalar)(&L, a, MPM_SHAPE_CUBIC);
    }
    return;
  }
  assert(!a->div_out);
  const int apic_b = a->C_out != NULL;
  switch (g->shape) {
  case MPM_SHAPE_LINEAR:
    DIMFN(g2p_loop)(&L, a, MPM_SHAPE_LINEAR, 0, -1, 1, 0);
    break;
  case MPM_SHAPE_GIMP:
    DIMFN(g2p_loop)(&L, a, MPM_SHAPE_GIMP, 0, -1, 1, 0);
    break;
  case MPM_SHAPE_QUADRATIC: /* the gas's FLIP update reads one scalar, two with the grid
                               pressure, five with its relaxation (fluid_transfer.c; a
                               run-time count) */
    if (apic_b)
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_QUADRATIC, 1, -1, 1, 0);
    else if (a->nscalar == 2)
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_QUADRATIC, 0, 2, 1, 0);
    else if (a->nscalar == 1)
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_QUADRATIC, 0, 1, 1, 0);
    else if (a->nscalar == 0)
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_QUADRATIC, 0, 0, 1, 0);
    else
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_QUADRATIC, 0, -1, 1, 0);
    break;
  default:
    if (apic_b)
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_CUBIC, 1, -1, 1, 0);
    else
      DIMFN(g2p_loop)(&L, a, MPM_SHAPE_CUBIC, 0, -1, 1, 0);
    break;
  }
}

const mpm_kernels DIMFN(mpm_kernels) = {MPM_DIM, DIMFN(p2g), DIMFN(g2p)};

#undef DIMFN
#undef MPM_INLINE
#undef SMAX
#undef SUPPORT
