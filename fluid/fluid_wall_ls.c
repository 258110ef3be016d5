/* The least-squares wall treatment (see fluid_wall_ls.h). */
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const mpm_key_spec fluid_wall_keys[] = {
    {"fluid.wall_treatment", MPM_KEY_ENUM, "ghost", 0, 0, 0, 0, "ghost|least_squares",
     "gas next to [obstacle] surfaces and, under coupling.scheme = traction, next to the "
     "solid: ghost (ghost pressure and held nodes) or least_squares (the particles within "
     "fluid.wall_band take a least-squares fit over the particles behind them, with the wall "
     "condition imposed; classic update only, and at a traction interface usl with "
     "coupling.time = monolithic; see fluid/fluid_wall_ls.h)",
     0, NULL},
    {"fluid.wall_band", MPM_KEY_REAL, "1", 0, 3, 1, 0, NULL,
     "least_squares: particles closer to an obstacle than this many cells are fitted, in "
     "(0, 3]",
     0, "dx"},
    {"fluid.wall_blend", MPM_KEY_REAL, "0", 0, 3, 0, 0, NULL,
     "least_squares: particles between fluid.wall_band and wall_band + this many cells take "
     "the fit in part, fully at the band's edge and not at all this far beyond it, and stay "
     "donors (0: none, a sharp edge). 1 keeps uniform flow along a wall slanted to the grid "
     "within 0.6 % (0: 2.5-4.2 %, on the particle rows just outside the band) and moves the "
     "Mach 2.5 wedge's shock 0.44 degrees steeper (fluid/fluid_wall_ls.h)",
     0, "dx"},
    {"fluid.wall_fit_order", MPM_KEY_INT, "0", 0, 1, 0, 0, NULL,
     "least_squares: order of the fit of the tangential velocity, e and rho: 0 (the donors' "
     "weighted mean) or 1 (linear; it extrapolates the gradients next to the wall: the "
     "wedge's wall layer ran 10-57 % over the post-shock pressure); the normal velocity is "
     "always linear and zero on the surface",
     0, "-"},
};
const int fluid_wall_nkeys = (int)(sizeof fluid_wall_keys / sizeof fluid_wall_keys[0]);

/* ---- small dense systems ------------------------------------------------------------------- */

/* Solve the symmetric positive definite system A x = b of order n <= 4 (A row-major, both
 * overwritten) by Cholesky; 1 if a pivot falls below tol times the largest diagonal entry. */
static int spd_solve(int n, double *A, double *b, double tol) {
  double dmax = 0.0;
  for (int i = 0; i < n; ++i) dmax = fmax(dmax, A[i * n + i]);
  for (int j = 0; j < n; ++j) {
    double d = A[j * n + j];
    for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > tol * dmax)) return 1;
    d = sqrt(d);
    A[j * n + j] = d;
    for (int i = j + 1; i < n; ++i) {
      double s = A[i * n + j];
      for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / d;
    }
  }
  for (int i = 0; i < n; ++i) { /* L y = b */
    for (int k = 0; k < i; ++k) b[i] -= A[i * n + k] * b[k];
    b[i] /= A[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) { /* L^T x = y */
    for (int k = i + 1; k < n; ++k) b[i] -= A[k * n + i] * b[k];
    b[i] /= A[i * n + i];
  }
  return 0;
}

/* Pivots below this fraction of the largest diagonal entry mean the donors cannot fix a
 * gradient (they lie on a line, or one holds all the weight). */
#define SINGULAR 1e-8

/* ---- the moments ---------------------------------------------------------------------------- */

/* Index layout of one node's moments, r in cells: M0, M1[dim], M2[dim (dim + 1) / 2] (a <= b),
 * then per field F0 and, for the first ng fields, F1[dim]. A linear fit needs every field's F1;
 * the constant one (fluid.wall_fit_order = 0) only the velocities' (the normal component is
 * always linear), so e and rho carry F0 alone. A node's moments are contiguous (nmom values at
 * mom + l nmom), so that a donor's deposit and a wall particle's gather read and write one run
 * of memory per node; the halo exchanges take them one array per moment (block_rows). */
typedef struct layout {
  int dim, nf, ng, m1, m2, f0, nmom;
} layout;

static int f_index(const layout *L, int f) {
  return f < L->ng ? L->f0 + f * (1 + L->dim) : L->f0 + L->ng * (1 + L->dim) + (f - L->ng);
}

static layout layout_of(int dim, int nf, int order) {
  layout L = {.dim = dim, .nf = nf, .ng = order ? nf : 2 * dim, .m1 = 1, .m2 = 1 + dim};
  L.f0 = L.m2 + dim * (dim + 1) / 2;
  L.nmom = f_index(&L, nf);
  return L;
}
static int m2_index(const layout *L, int a, int b) { /* a <= b */
  int k = L->m2;
  for (int r = 0; r < a; ++r) k += L->dim - r;
  return k + b - a;
}

/* The weighted sums of one wall particle, gathered from the nodal moments. */
typedef struct sums {
  double S0, S1[MPM_MAX_DIM], S2[MPM_MAX_DIM][MPM_MAX_DIM];
  double G0[2 * MPM_MAX_DIM + 2], G1[2 * MPM_MAX_DIM + 2][MPM_MAX_DIM];
} sums;

/* Visit the stencil of a point at xi (cells): BODY for every box node L_, with W its weight and
 * D its offset x_i - x in cells. The node's index along each axis advances as an odometer
 * rather than by an integer division per node and axis. DIM is g->dim; deposit and gather pass
 * it as a literal (MPM_INLINE), so that the loops over the axes unroll. The deposit is compiled
 * without the vectoriser (NO_VECTORIZE): it packed each node's offsets into a pair read from the
 * stack just after writing them one at a time, a failed store forward at every node, which
 * made the donors' deposit the largest part of the treatment's cost on the wedge (profiled). */
#define MPM_INLINE   static inline __attribute__((always_inline))
#define NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#define FOR_STENCIL(g, DIM, xi, lp, BODY)                                                          \
  do {                                                                                             \
    int base_[MPM_MAX_DIM], kd_[MPM_MAX_DIM] = {0}, sup_ = mpm_shape_support((g)->shape);          \
    double w_[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT], dw_[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT];        \
    mpm_shape_eval((g)->shape, DIM, xi, lp, base_, w_, dw_);                                       \
    const int cnt_ = (DIM) == 2 ? sup_ * sup_ : sup_ * sup_ * sup_;                                \
    for (int s_ = 0; s_ < cnt_; ++s_) {                                                            \
      int gi_[MPM_MAX_DIM], in_ = 1;                                                               \
      double W = 1.0, D[MPM_MAX_DIM];                                                              \
      for (int d_ = 0; d_ < (DIM); ++d_) {                                                         \
        gi_[d_] = base_[d_] + kd_[d_];                                                             \
        in_ &= gi_[d_] >= (g)->box_lo[d_] && gi_[d_] < (g)->box_lo[d_] + (g)->box_n[d_];           \
        W *= w_[d_][kd_[d_]];                                                                      \
        D[d_] = gi_[d_] - (xi)[d_];                                                                \
      }                                                                                            \
      for (int d_ = 0; d_ < (DIM) && ++kd_[d_] == sup_; ++d_) kd_[d_] = 0;                         \
      if (!in_ || W == 0.0) continue;                                                              \
      const mpm_lidx L_ = mpm_grid_local_index(g, gi_);                                            \
      BODY                                                                                         \
    }                                                                                              \
  } while (0)

MPM_INLINE NO_VECTORIZE void deposit_dim(const int dim, double *mom, const double *need,
                                         const layout *L, const mpm_grid *g, const double *xi,
                                         double lp, double V, const double *f) {
  FOR_STENCIL(g, dim, xi, lp, {
    if (need[L_] == 0.0) continue;
    const double w = W * V;
    double *M = mom + (size_t)L_ * L->nmom;
    double r[MPM_MAX_DIM];
    for (int a = 0; a < dim; ++a) r[a] = -D[a]; /* x_q - x_i */
    M[0] += w;
    for (int a = 0; a < dim; ++a) {
      M[L->m1 + a] += w * r[a];
      for (int b = a; b < dim; ++b) M[m2_index(L, a, b)] += w * r[a] * r[b];
    }
    for (int k = 0; k < L->nf; ++k) {
      const int i0 = f_index(L, k);
      M[i0] += w * f[k];
      for (int a = 0; k < L->ng && a < dim; ++a) M[i0 + 1 + a] += w * f[k] * r[a];
    }
  });
}

MPM_INLINE void gather_dim(const int dim, sums *s, const double *mom, const layout *L,
                           const mpm_grid *g, const double *xi, double lp) {
  memset(s, 0, sizeof *s);
  FOR_STENCIL(g, dim, xi, lp, {
    const double *M = mom + (size_t)L_ * L->nmom;
    const double m0 = M[0];
    double m1[MPM_MAX_DIM];
    for (int a = 0; a < dim; ++a) m1[a] = M[L->m1 + a];
    s->S0 += W * m0;
    for (int a = 0; a < dim; ++a) {
      s->S1[a] += W * (m1[a] + D[a] * m0);
      for (int b = a; b < dim; ++b)
        s->S2[a][b] += W * (M[m2_index(L, a, b)] + m1[a] * D[b] + D[a] * m1[b] + D[a] * D[b] * m0);
    }
    for (int k = 0; k < L->nf; ++k) {
      const int i0 = f_index(L, k);
      const double f0 = M[i0];
      s->G0[k] += W * f0;
      for (int a = 0; k < L->ng && a < dim; ++a) s->G1[k][a] += W * (M[i0 + 1 + a] + D[a] * f0);
    }
  });
  for (int a = 0; a < dim; ++a)
    for (int b = 0; b < a; ++b) s->S2[a][b] = s->S2[b][a];
}

/* Add a donor's moments (value f, volume V) to those of its stencil's nodes that a fitted
 * particle reads (need, mark_need): the others are never gathered. */
static NO_VECTORIZE void deposit(double *mom, const double *need, const layout *L,
                                 const mpm_grid *g, const double *xi, double lp, double V,
                                 const double *f) {
  if (L->dim == 2)
    deposit_dim(2, mom, need, L, g, xi, lp, V, f);
  else
    deposit_dim(3, mom, need, L, g, xi, lp, V, f);
}

/* Flag the nodes a fitted particle at xi gathers from: only they need the donors' moments. */
static void mark_need(double *need, const mpm_grid *g, const double *xi, double lp) {
  FOR_STENCIL(g, g->dim, xi, lp, {
    (void)D;
    need[L_] = 1.0;
  });
}

/* A wall particle's weighted sums, from its stencil's nodes. */
static void gather(sums *s, const double *mom, const layout *L, const mpm_grid *g, const double *xi,
                   double lp) {
  if (L->dim == 2)
    gather_dim(2, s, mom, L, g, xi, lp);
  else
    gather_dim(3, s, mom, L, g, xi, lp);
}

/* The unconstrained fits a + g . r of every field at r = 0 into out (nf values); 1 if singular
 * (out then holds the weighted means). */
static int fit_free(const sums *s, const layout *L, double *out) {
  const int dim = L->dim, n = dim + 1;
  double A[16];
  A[0] = s->S0;
  for (int a = 0; a < dim; ++a) {
    A[a + 1] = A[(a + 1) * n] = s->S1[a];
    for (int b = 0; b < dim; ++b) A[(a + 1) * n + b + 1] = s->S2[a][b];
  }
  /* The same matrix for every field, factored again per field (order <= 4: cheap). */
  for (int k = 0; k < L->nf; ++k) {
    double Ak[16], b[4];
    memcpy(Ak, A, sizeof Ak);
    b[0] = s->G0[k];
    for (int a = 0; a < dim; ++a) b[a + 1] = s->G1[k][a];
    if (spd_solve(n, Ak, b, SINGULAR)) {
      for (int j = 0; j < L->nf; ++j) out[j] = s->G0[j] / s->S0;
      return 1;
    }
    out[k] = b[0];
  }
  return 0;
}

/* The fit u . t - u0 ~ c . (x - x_w) of the velocity field starting at field k0 along the unit
 * vector t, with u0 the wall's velocity along t: zero relative velocity on the surface point
 * x_w = x_p - phi n (phi, n in cells). Its value u . t at x_p. */
static double fit_constrained(const sums *s, const layout *L, int k0, const double *t, double phi,
                              const double *n, double u0) {
  const int dim = L->dim;
  double A[9] = {0}, b[3] = {0};
  for (int a = 0; a < dim; ++a) {
    double ga = 0.0, g0 = 0.0;
    for (int f = 0; f < dim; ++f) ga += t[f] * s->G1[k0 + f][a], g0 += t[f] * s->G0[k0 + f];
    ga -= u0 * s->S1[a], g0 -= u0 * s->S0;
    b[a] = ga + phi * n[a] * g0;
    for (int c = 0; c < dim; ++c)
      A[a * dim + c] =
          s->S2[a][c] + phi * (s->S1[a] * n[c] + n[a] * s->S1[c]) + phi * phi * s->S0 * n[a] * n[c];
  }
  double An[9], bn[3];
  memcpy(An, A, sizeof An), memcpy(bn, b, sizeof bn);
  if (!spd_solve(dim, An, bn, SINGULAR)) {
    double cn = 0.0;
    for (int a = 0; a < dim; ++a) cn += bn[a] * n[a];
    return u0 + phi * cn;
  }
  /* Donors on a line: vary along the normal only. */
  double nAn = 0.0, nb = 0.0;
  for (int a = 0; a < dim; ++a) {
    nb += n[a] * b[a];
    for (int c = 0; c < dim; ++c) nAn += n[a] * A[a * dim + c] * n[c];
  }
  return u0 + (nAn > 0.0 ? phi * nb / nAn : 0.0);
}

/* The fitted values of one wall particle into out (see the header): the free fits, then the
 * wall condition on both velocities, relative to the wall's normal velocity vw_n (0 for a static
 * obstacle; a no_slip wall is static). */
static void fit_particle(const sums *s, const layout *L, int order, int no_slip, double phi,
                         const double *nrm, double vw_n, double vn_floor, double *out) {
  const int dim = L->dim, nf = L->nf;
  int mean = order == 0;
  if (!mean) mean = fit_free(s, L, out);
  if (mean)
    for (int k = 0; k < nf; ++k) out[k] = s->G0[k] / s->S0;
  for (int k = 2 * dim; k < nf; ++k) { /* e and rho of a linear fit */
    const double mk = s->G0[k] / s->S0;
    if (!(out[k] > 0.5 * mk && out[k] < 2.0 * mk)) out[k] = mk;
  }
  for (int k0 = 0; k0 <= dim; k0 += dim) {
    if (no_slip) {
      for (int c = 0; c < dim; ++c) {
        double t[MPM_MAX_DIM] = {0};
        t[c] = 1.0;
        out[k0 + c] = fit_constrained(s, L, k0, t, phi, nrm, 0.0);
      }
      continue;
    }
    double un = 0.0;
    for (int d = 0; d < dim; ++d) un += out[k0 + d] * nrm[d];
    double rel = fit_constrained(s, L, k0, nrm, fabs(phi), nrm, vw_n) - vw_n;
    if (phi < 0.0 && rel < 0.0) rel = 0.0;           /* inside the body: never deeper */
    if (k0 == dim && rel < vn_floor) rel = vn_floor; /* the motion: see the header */
    const double fitted = vw_n + rel;
    for (int d = 0; d < dim; ++d) out[k0 + d] += (fitted - un) * nrm[d];
  }
}

/* A wall particle with no donor near (gas expanding away from a face into near vacuum): it keeps
 * the transfer's values f, less any velocity into the body (relative to the wall's, vw_n). */
static void keep_out(const double *f, const layout *L, const double *nrm, double vw_n,
                     double *out) {
  const int dim = L->dim;
  memcpy(out, f, sizeof *out * (size_t)L->nf);
  for (int k0 = 0; k0 <= dim; k0 += dim) {
    double un = -vw_n;
    for (int d = 0; d < dim; ++d) un += out[k0 + d] * nrm[d];
    for (int d = 0; un < 0.0 && d < dim; ++d) out[k0 + d] -= un * nrm[d];
  }
}

/* ---- setup ---------------------------------------------------------------------------------- */

/* What a cell (w->reach, by its lower corner node) holds: no particle near a body, donors only,
 * or particles that may be fitted (their phi decides). */
enum { REACH_FAR = 0, REACH_DONOR = 1, REACH_MAY_FIT = 2 };

/* The nearest obstacle to x: its index, phi and outward normal (dim values). */
static int nearest(const fluid_obstacles *o, int dim, const double *x, double *phi,
                   double *normal) {
  int best = -1;
  double nb[MPM_MAX_DIM];
  *phi = HUGE_VAL;
  for (int k = 0; k < o->count; ++k) {
    const double f = mpm_sdf_eval(&o->ob[k].sdf, x, nb);
    if (f < *phi) *phi = f, best = k, memcpy(normal, nb, sizeof *nb * (size_t)dim);
  }
  return best;
}

/* The block of box nodes (lower corner blo, extent bn) within reach and two cells of the
 * physical box [lo, hi]: the same global nodes on every rank, clipped to this rank's box; along
 * a periodic axis the whole box. An empty box (lo > hi) gives an empty block. */
static void block_of(const mpm_grid *g, const double *lo, const double *hi, double reach, int *blo,
                     int *bn) {
  for (int d = 0; d < g->dim; ++d) {
    const double b0 = g->box_lo[d], b1 = g->box_lo[d] + g->box_n[d];
    double i0 = floor((lo[d] - reach - g->lo[d]) / g->dx) - 2,
           i1 = ceil((hi[d] + reach - g->lo[d]) / g->dx) + 3;
    if (g->periodic[d]) i0 = b0, i1 = b1;
    i0 = fmin(fmax(i0, b0), b1), i1 = fmin(fmax(i1, i0), b1);
    blo[d] = (int)i0, bn[d] = (int)(i1 - i0);
  }
}

/* How far from a wall a donor may lie and still reach a fitted particle's fit: a node within a
 * stencil of both, and half a cell diagonal for a cell's centre. */
static double reach_of(const fluid_wall_ls *w, const mpm_grid *g) {
  return w->band + w->blend + (mpm_shape_support(g->shape) + 0.5 * sqrt((double)g->dim)) * g->dx;
}

int fluid_wall_ls_init(mpm_module *m, const mpm_config *cfg, int classic) {
  fluid_content *fc = m->content;
  fluid_wall_ls *w = &fc->wall;
  const mpm_grid *g = m->grid;
  const char *kind;
  memset(w, 0, sizeof *w);
  MPM_CALL(mpm_config_get_string(cfg, "fluid.wall_treatment", &kind));
  if (strcmp(kind, "least_squares") != 0) return 0;
  if (!classic)
    return mpm_config_fail(cfg, "fluid.wall_treatment",
                           "least_squares needs the classic update (time.method = usl or musl): "
                           "its fit is not part of an adaptive pair's error control");
  double band, blend;
  MPM_CALL(mpm_config_get_real(cfg, "fluid.wall_band", &band));
  MPM_CALL(mpm_config_get_real(cfg, "fluid.wall_blend", &blend));
  w->on = 1, w->band = band * g->dx, w->blend = blend * g->dx;
  MPM_CALL(mpm_config_get_int(cfg, "fluid.wall_fit_order", &w->order));
  if (fc->obs.count > 0) fluid_obstacles_book_heat(&fc->obs, g);
  const int dim = g->dim;
  w->nf = 2 * dim + 2;
  const layout L = layout_of(dim, w->nf, w->order);
  w->nmom = L.nmom;
  MPM_ALLOC(w->mom, (size_t)w->nmom * g->nnodes);
  MPM_ALLOC(w->halo, (size_t)w->nmom * g->nnodes);
  MPM_ALLOC(w->need, g->nnodes);
  MPM_ALLOC(w->halo_ptr, w->nmom);
  for (int k = 0; k < w->nmom; ++k) w->halo_ptr[k] = w->halo + (size_t)k * g->nnodes;
  /* A donor reaches a fitted particle's fit if a node is within a stencil of both: donors lie
   * within band + blend + 2 stencil radii of a body; a cell is near if its centre is within
   * that and half a cell diagonal. */
  const double reach = reach_of(w, g);
  for (int d = 0; d < dim; ++d)
    w->exchange |= g->nbr[d][0] != MPI_PROC_NULL || g->nbr[d][1] != MPI_PROC_NULL;
  if (fc->obs.count == 0) return 0; /* a moving wall may come (fluid_wall_ls_attach) */
  MPM_ALLOC(w->reach, g->nnodes);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[MPM_MAX_DIM];
    double xc[MPM_MAX_DIM], phi, nrm[MPM_MAX_DIM];
    mpm_grid_node_global(g, l, gi);
    for (int d = 0; d < dim; ++d) xc[d] = g->lo[d] + (gi[d] + 0.5) * g->dx;
    nearest(&fc->obs, dim, xc, &phi, nrm);
    w->reach[l] = phi < reach ? REACH_MAY_FIT : REACH_FAR;
    /* Every point of the cell lies within half a diagonal of its centre, and phi is a distance
     * (1-Lipschitz): a cell whose centre is that much beyond the fitted particles, and a hair
     * more for the roundoff of phi, holds donors only, and its particles need no phi. */
    if (phi < reach && phi - 0.5 * sqrt((double)dim) * g->dx > w->band + w->blend + 1e-9 * g->dx)
      w->reach[l] = REACH_DONOR;
  }
  fluid_obstacles_list_cells(&fc->obs, g, w->reach);
  /* The moments live on the nodes within a stencil of a reach cell, all inside the bodies'
   * bounding box grown by reach and two cells: only that block of the box is cleared at each
   * step. The block is a global one (the same nodes on every rank), so no ghost node outside it
   * ever holds a moment for the halo exchanges to carry; along a periodic axis it is the whole
   * box. */
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) {
    lo[d] = HUGE_VAL, hi[d] = -HUGE_VAL;
    for (int k = 0; k < fc->obs.count; ++k)
      lo[d] = fmin(lo[d], fc->obs.ob[k].sdf.lo[d]), hi[d] = fmax(hi[d], fc->obs.ob[k].sdf.hi[d]);
  }
  block_of(g, lo, hi, reach, w->obs_lo, w->obs_n);
  memcpy(w->clear_lo, w->obs_lo, sizeof w->clear_lo);
  memcpy(w->clear_n, w->obs_n, sizeof w->clear_n);
  return 0;
}

int fluid_wall_ls_attach(mpm_module *m, const mpm_config *cfg, const mpm_wall_source *src,
                         int *taken) {
  fluid_content *fc = m->content;
  fluid_wall_ls *w = &fc->wall;
  const mpm_grid *g = m->grid;
  *taken = 0;
  if (!w->on) return 0;
  if (!src) {
    if (fc->obs.count == 0 && !w->src)
      return mpm_config_fail(cfg, "fluid.wall_treatment",
                             "least_squares acts on [obstacle.NAME] surfaces and on a solid's "
                             "surface under coupling.scheme = traction, and this scene has "
                             "neither (domain walls keep their mirror rules): remove the key, "
                             "or add an obstacle or a traction interface");
    return 0;
  }
  w->src = src, *taken = 1;
  MPM_ALLOC(w->near_src, g->nnodes);
  return 0;
}

/* What to do with each row of the block of nodes the moments reach (see fluid_wall_ls_init). */
enum { BLOCK_CLEAR, BLOCK_TO_HALO, BLOCK_FROM_HALO };

/* Over the block, row by row (x fastest): clear the moments, or copy them to the halo
 * exchange's arrays (one per moment) or back. */
static void block_rows(fluid_wall_ls *w, const mpm_grid *g, int what) {
  const int dim = g->dim, nx = w->clear_n[0], nm = w->nmom;
  mpm_lidx rows = 1;
  for (int d = 1; d < dim; ++d) rows *= w->clear_n[d];
  if (rows == 0 || nx == 0) return;
  for (mpm_lidx r = 0; r < rows; ++r) {
    int gi[MPM_MAX_DIM] = {w->clear_lo[0]};
    for (int d = 1, q = (int)r; d < dim; q /= w->clear_n[d], ++d)
      gi[d] = w->clear_lo[d] + q % w->clear_n[d];
    const mpm_lidx l0 = mpm_grid_local_index(g, gi);
    double *M = w->mom + (size_t)l0 * nm;
    if (what == BLOCK_CLEAR) {
      memset(M, 0, sizeof *M * (size_t)nx * nm);
      memset(w->need + l0, 0, sizeof *w->need * (size_t)nx);
      continue;
    }
    for (int k = 0; k < nm; ++k)
      for (int i = 0; i < nx; ++i) {
        if (what == BLOCK_TO_HALO)
          w->halo_ptr[k][l0 + i] = M[(size_t)i * nm + k];
        else
          M[(size_t)i * nm + k] = w->halo_ptr[k][l0 + i];
      }
  }
}

static int ensure(fluid_wall_ls *w, mpm_lidx n, int dim) {
  if (n <= w->cap) return 0;
  const mpm_lidx cap = n + n / 4 + 16;
  free(w->kind), free(w->ob), free(w->geo), free(w->val);
  w->kind = malloc((size_t)cap);
  w->ob = malloc(sizeof *w->ob * (size_t)cap);
  w->geo = malloc(sizeof *w->geo * (size_t)(1 + 2 * dim) * cap);
  w->val = malloc(sizeof *w->val * (size_t)w->nf * cap);
  w->cap = cap;
  if (!(w->kind && w->ob && w->geo && w->val)) {
    w->cap = 0;
    MPM_FAIL(MPM_ERR_MEMORY, "cannot allocate the least-squares wall scratch for %ld particles",
             (long)n);
  }
  return 0;
}

/* ---- the step ------------------------------------------------------------------------------- */

/* A moving wall: flag its cells for this step and make the block of the moments the union of
 * the obstacles' and the wall's. Where the block moved, every moment, flag and halo value is
 * cleared once (outside the block nothing else clears them: stale values there would circulate
 * through the halo exchanges). Collective. */
static int moving_block(fluid_wall_ls *w, const mpm_grid *g, double h) {
  const int dim = g->dim;
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
  int blo[MPM_MAX_DIM], bn[MPM_MAX_DIM], changed = 0;
  memset(w->near_src, 0, (size_t)g->nnodes);
  MPM_CALL(
      w->src->prepare(w->src->ctx, h, reach_of(w, g), w->band + w->blend, w->near_src, lo, hi));
  block_of(g, lo, hi, reach_of(w, g), blo, bn);
  for (int d = 0; d < dim; ++d) {
    if (w->obs_n[d] > 0 && bn[d] > 0) {
      const int e0 = MPM_MIN(blo[d], w->obs_lo[d]);
      const int e1 = MPM_MAX(blo[d] + bn[d], w->obs_lo[d] + w->obs_n[d]);
      blo[d] = e0, bn[d] = e1 - e0;
    } else if (w->obs_n[d] > 0) {
      blo[d] = w->obs_lo[d], bn[d] = w->obs_n[d];
    }
  }
  for (int d = 0; d < dim; ++d) changed |= blo[d] != w->clear_lo[d] || bn[d] != w->clear_n[d];
  if (!changed) return 0;
  memset(w->mom, 0, sizeof *w->mom * (size_t)w->nmom * g->nnodes);
  memset(w->halo, 0, sizeof *w->halo * (size_t)w->nmom * g->nnodes);
  memset(w->need, 0, sizeof *w->need * (size_t)g->nnodes);
  memcpy(w->clear_lo, blo, sizeof blo);
  memcpy(w->clear_n, bn, sizeof bn);
  return 0;
}

int fluid_wall_ls_apply(mpm_module *m, const double *y, double *ydot, double h) {
  fluid_content *fc = m->content;
  fluid_wall_ls *w = &fc->wall;
  if (!w->on) return 0;
  const mpm_particles *p = m->particles;
  mpm_grid *g = m->grid;
  const int dim = g->dim, nf = w->nf;
  const mpm_lidx n = p->n;
  const layout L = layout_of(dim, nf, w->order);
  MPM_CALL(ensure(w, n, dim));
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  const size_t ox = (size_t)p->offset[FLUID_X] * n, ov = (size_t)p->offset[FLUID_V] * n;
  const size_t oJ = (size_t)p->offset[FLUID_J] * n, oe = (size_t)p->offset[FLUID_E] * n;
  const int gs = 1 + 2 * dim; /* geo per particle */
  if (w->src) MPM_CALL(moving_block(w, g, h));
  block_rows(w, g, BLOCK_CLEAR);

  /* Classify the particles near a body that the obstacles' deposit listed in this RHS (every
   * one if there is no list) and flag the nodes the fitted ones read; then deposit the donors'
   * new values on those nodes. */
  mpm_lidx nl = n;
  const mpm_lidx *cells, *list = fluid_obstacles_listed(&fc->obs, y + ox, n, &nl, &cells);
  if (w->src) list = NULL, nl = n; /* the list knows the obstacles only */
  if (list) memset(w->kind, -1, (size_t)n);
  for (mpm_lidx k = 0; k < nl; ++k) {
    const mpm_lidx i = list ? list[k] : k;
    double x[MPM_MAX_DIM], xi[MPM_MAX_DIM];
    int gi[MPM_MAX_DIM], in = 1;
    for (int d = 0; d < dim; ++d) {
      x[d] = y[ox + (size_t)d * n + i];
      xi[d] = (x[d] - g->lo[d]) / g->dx;
      gi[d] = mpm_shape_floor(xi[d]);
      in &= gi[d] >= g->box_lo[d] && gi[d] < g->box_lo[d] + g->box_n[d];
    }
    w->kind[i] = -1;
    const mpm_lidx cell = in ? mpm_grid_local_index(g, gi) : 0;
    const int r = in && w->reach ? w->reach[cell] : REACH_FAR;
    const int moving = in && w->src ? w->near_src[cell] : 0;
    if (r == REACH_FAR && !moving) continue;
    double *geo = w->geo + (size_t)gs * i, *f = w->val + (size_t)nf * i;
    geo[0] = HUGE_VAL;
    if (r == REACH_MAY_FIT) w->ob[i] = nearest(&fc->obs, dim, x, &geo[0], geo + 1);
    for (int d = 0; d < dim; ++d) geo[1 + dim + d] = 0.0; /* a static wall */
    double phi, nrm[MPM_MAX_DIM], vw[MPM_MAX_DIM];
    if (moving == 2 && w->src->at(w->src->ctx, x, w->band + w->blend, &phi, nrm, vw) &&
        phi < geo[0]) {
      w->ob[i] = -1, geo[0] = phi;
      memcpy(geo + 1, nrm, sizeof *nrm * (size_t)dim);
      memcpy(geo + 1 + dim, vw, sizeof *vw * (size_t)dim);
    }
    const double J1 = y[oJ + i] + h * ydot[oJ + i], V = V0[i] * J1;
    for (int d = 0; d < dim; ++d) {
      f[d] = y[ov + (size_t)d * n + i] + h * ydot[ov + (size_t)d * n + i];
      f[dim + d] = ydot[ox + (size_t)d * n + i];
    }
    f[2 * dim] = y[oe + i] + h * ydot[oe + i];
    f[2 * dim + 1] = mass[i] / V;
    w->kind[i] = geo[0] < w->band ? 1 : geo[0] < w->band + w->blend ? 2 : 0;
    if (w->kind[i] > 0) mark_need(w->need, g, xi, fc->lp);
  }
  if (w->exchange) { /* a node one rank's fitted particle reads takes every rank's donors */
    MPM_CALL(mpm_grid_halo_reverse(g, &w->need, 1));
    MPM_CALL(mpm_grid_halo_forward(g, &w->need, 1));
  }
  for (mpm_lidx k = 0; k < nl; ++k) {
    const mpm_lidx i = list ? list[k] : k;
    if (w->kind[i] != 0 && w->kind[i] != 2) continue;
    double xi[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) xi[d] = (y[ox + (size_t)d * n + i] - g->lo[d]) / g->dx;
    const double V = V0[i] * (y[oJ + i] + h * ydot[oJ + i]);
    deposit(w->mom, w->need, &L, g, xi, fc->lp, V, w->val + (size_t)nf * i);
  }
  /* The halo exchanges take one array per moment: the block goes through them. The arrays are
   * zero outside the block (calloc), which no rank ever writes. A box with no neighbour (one
   * rank, no periodic axis) has nothing to exchange. */
  if (w->exchange) {
    block_rows(w, g, BLOCK_TO_HALO);
    MPM_CALL(mpm_grid_halo_reverse(g, w->halo_ptr, w->nmom));
    MPM_CALL(mpm_grid_halo_forward(g, w->halo_ptr, w->nmom));
    block_rows(w, g, BLOCK_FROM_HALO);
  }

  /* Fit the wall particles; book the momentum; sum the energy change. */
  double *force = fc->obs.f[fc->obs.rec.latest];
  double bal[2] = {0.0, 0.0}; /* the fit's energy change, and the gas's sum m e */
  for (mpm_lidx k = 0; k < nl; ++k) {
    const mpm_lidx i = list ? list[k] : k;
    if (w->kind[i] < 1) continue;
    double xi[MPM_MAX_DIM], out[2 * MPM_MAX_DIM + 2];
    for (int d = 0; d < dim; ++d) xi[d] = (y[ox + (size_t)d * n + i] - g->lo[d]) / g->dx;
    sums s;
    gather(&s, w->mom, &L, g, xi, fc->lp);
    double *f = w->val + (size_t)nf * i;
    const double *geo = w->geo + (size_t)gs * i, *nrm = geo + 1, *vw = geo + 1 + dim;
    const double phi = geo[0] / g->dx;
    double vw_n = 0.0;
    for (int d = 0; d < dim; ++d) vw_n += vw[d] * nrm[d];
    const int no_slip = w->ob[i] >= 0 && fc->obs.ob[w->ob[i]].no_slip;
    if (s.S0 > 0.0)
      fit_particle(&s, &L, w->order, no_slip, phi, nrm, vw_n, -0.5 * fmax(phi, 0.0) * g->dx / h,
                   out);
    else
      keep_out(f, &L, nrm, vw_n, out);
    if (w->ob[i] < 0) { /* a moving wall: the new velocity keeps its own normal component */
      double fitted = 0.0, own = 0.0;
      for (int d = 0; d < dim; ++d) fitted += out[d] * nrm[d], own += f[d] * nrm[d];
      for (int d = 0; d < dim; ++d) out[d] += (own - fitted) * nrm[d];
    }
    if (w->kind[i] == 2) { /* the blend: part fit, part its own */
      const double b = (w->band + w->blend - phi * g->dx) / w->blend;
      for (int k = 0; k < nf; ++k) out[k] = b * out[k] + (1.0 - b) * f[k];
    }
    /* Momentum to the obstacle or the moving wall, energy to the balance: a moving wall's work
     * J . v_w stays with the gas, the rest is given back as heat. */
    double dke = 0.0, J[MPM_MAX_DIM], work = 0.0;
    for (int d = 0; d < dim; ++d) {
      const double v0 = y[ov + (size_t)d * n + i];
      J[d] = mass[i] * (out[d] - f[d]);
      dke += 0.5 * (out[d] * out[d] - f[d] * f[d]);
      ydot[ov + (size_t)d * n + i] = (out[d] - v0) / h;
      ydot[ox + (size_t)d * n + i] = out[dim + d];
    }
    if (w->ob[i] >= 0)
      for (int d = 0; d < dim; ++d) force[(size_t)dim * w->ob[i] + d] -= J[d] / h;
    else {
      double x[MPM_MAX_DIM];
      for (int d = 0; d < dim; ++d) x[d] = y[ox + (size_t)d * n + i];
      work = w->src->impulse(w->src->ctx, x, J);
    }
    bal[0] += mass[i] * (dke + out[2 * dim] - f[2 * dim]) - work;
    bal[1] += mass[i] * out[2 * dim];
    f[2 * dim] = out[2 * dim], f[2 * dim + 1] = out[2 * dim + 1];
  }
  if (w->src) MPM_CALL(w->src->finish(w->src->ctx));
  double me = bal[1];              /* a register, not the array that MPI takes */
  for (mpm_lidx i = 0; i < n; ++i) /* every particle pays (see the header) */
    if (w->kind[i] < 1) me += mass[i] * (y[oe + i] + h * ydot[oe + i]);
  bal[1] = me;
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, bal, 2, MPI_DOUBLE, MPI_SUM, g->comm));
  const double scale = bal[1] > 0.0 ? 1.0 - bal[0] / bal[1] : 1.0;
  if (!(scale > 0.0))
    MPM_FAIL(MPM_ERR_UNPHYSICAL,
             "the least-squares wall fit changed the total energy of the gas by %.3g J, more "
             "than all its internal energy (%.3g J): the flow next to the obstacles is not "
             "resolved; refine grid.dx or use fluid.wall_treatment = ghost",
             bal[0], bal[1]);
  for (mpm_lidx i = 0; i < n; ++i) {
    if (w->kind[i] < 1) { /* e + h e' scaled; exactly as it was when the fit is neutral */
      ydot[oe + i] += (scale - 1.0) * (y[oe + i] / h + ydot[oe + i]);
      continue;
    }
    const double *f = w->val + (size_t)nf * i;
    ydot[oe + i] = (scale * f[2 * dim] - y[oe + i]) / h;
    ydot[oJ + i] = (mass[i] / (f[2 * dim + 1] * V0[i]) - y[oJ + i]) / h;
  }
  return 0;
}

void fluid_wall_ls_free(fluid_wall_ls *w) {
  free(w->reach), free(w->mom), free(w->halo), free(w->halo_ptr), free(w->need), free(w->near_src);
  free(w->kind), free(w->ob), free(w->geo), free(w->val);
  memset(w, 0, sizeof *w);
}
