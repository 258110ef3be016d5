/* P2G and G2P kernels, compiled once for 2-D and once for 3-D from mpm_kernels_dim.c.
 *
 * Everything above the kernels is dimension-agnostic and reaches them through the small
 * per-dimension table returned by mpm_kernels_get(dim). Inside a kernel the shape kind is
 * switched once per call, outside the particle loop, so the stencil code is specialised per
 * kind: no indirect call per particle.
 *
 * Particle arrays are component-major (see mpm_particles.h): component a of a vector is an
 * array of n doubles; a tensor T_ab is component a*dim + b. */
#ifndef MPM_KERNELS_H
#define MPM_KERNELS_H

#include "mpm_grid.h"

/* Optional fields are NULL when unused and then cost nothing.
 *
 * A lean deposit: with v[0] NULL the kernel deposits S m into m_i (m may be NULL too) and the
 * force -V sigma grad S of a stress given in full (vsig) or isotropic (viso: V sigma = viso I)
 * into f_i, and nothing else: C and fext must then be unset, and m too when the phase deposits
 * its normals (gravity is not read). It visits only the arrays it fills, a fraction of the full
 * deposit's work; its sums are the full deposit's of zero velocity, operation for operation.
 * With s (a scalar per unit mass; needs m, and no stress) it deposits S m s into mv_i[0] beside
 * S m into m_i: the full deposit's sums for v = (s, 0, ...) in those two arrays, operation for
 * operation, and nothing into mv_i[1..] or f_i (a two-scalar deposit, such as the grid
 * pressure's V and V p).
 *
 * A subset of the particles (the refinement hierarchy's levels): with idx set a kernel visits
 * the nidx particles idx[0 .. nidx) (distinct, each below n) of arrays that hold n entries per
 * component, in that order, and reads and writes those indices alone; NULL: every particle.
 * Each visited particle's arithmetic is that of a call on its own, so a subset's outputs and
 * sums are those of the same particles copied out and run without a list.
 * Wrapped positions (a level that stores a whole period of a periodic axis): along an axis
 * with wrap_hi[d] > wrap_lo[d] a kernel takes each position wrapped into [wrap_lo, wrap_hi)
 * (mpm_wrap_coord) for its weights; zero (the initialiser's): as given.
 *
 * G2P writes v_out[d] and a_out[d] for every d < dim whenever v_out[0] is set, s_out[j] for
 * every j < nscalar, and each of div_out, L_out, C_out and LF_out that is set. */
typedef struct mpm_p2g_args {
  mpm_lidx n;
  const mpm_lidx *idx; /* the subset visited, or NULL (above) */
  mpm_lidx nidx;
  double wrap_lo[MPM_MAX_DIM], wrap_hi[MPM_MAX_DIM]; /* (above) */
  const double *x[MPM_MAX_DIM];                      /* positions */
  const double *v[MPM_MAX_DIM]; /* velocities, or v[0] NULL: the lean deposit */
  const double *m;              /* masses */
  const double *viso;           /* the lean deposit's isotropic V sigma, or NULL */
  const double *s;    /* the lean deposit's scalar per unit mass (into mv_i[0]), or NULL */
  const double *vsig; /* V_p sigma_p, dim*dim components of n, or NULL */
  /* APIC affine velocity C_p, dim*dim components of n (entry (r, c) at C[(r*dim + c)*n + p]),
   * or NULL. When set the momentum deposited at node i is S m (v_p + C_p (x_i - x_p)). */
  const double *C;
  /* External force on each particle, N (e.g. a surface traction times its area): component
   * d is an array of n; off when fext[0] is NULL. Adds S fext_p to f_i. */
  const double *fext[MPM_MAX_DIM];
  double gravity[MPM_MAX_DIM]; /* body acceleration */
  double lp;                   /* GIMP particle half-width in cells */
} mpm_p2g_args;

#define MPM_KERNELS_MAX_SCALARS 8

/* A scalar gather: with v_out[0] NULL the kernel computes only the scalars below and div_out,
 * reading only the arrays they need; a_out, L_out, C_out and LF_out must then be NULL. Its sums
 * are the full gather's, operation for operation. */
typedef struct mpm_g2p_args {
  mpm_lidx n;
  const mpm_lidx *idx; /* the subset visited, or NULL (as for P2G) */
  mpm_lidx nidx;
  double wrap_lo[MPM_MAX_DIM], wrap_hi[MPM_MAX_DIM]; /* wrapped positions (as for P2G) */
  const double *x[MPM_MAX_DIM];
  const double *v_i[MPM_MAX_DIM]; /* nodal velocity to interpolate (and differentiate) */
  const double *a_i[MPM_MAX_DIM]; /* nodal acceleration to interpolate */
  double lp;
  double *v_out[MPM_MAX_DIM]; /* sum_i S_ip v_i, or v_out[0] NULL: the scalar gather */
  double *a_out[MPM_MAX_DIM]; /* sum_i S_ip a_i */
  double *div_out;            /* the scalar gather's sum_i v_i . grad S_ip (trace of L), or NULL */
  double *L_out;              /* sum_i v_i (x) grad S_ip, dim*dim components, or NULL */
  /* APIC affine velocity (layout of L_out), or NULL. Quadratic and cubic B-splines:
   * C_p = D^-1 sum_i S_ip v_i (x_i - x_p)^T with D = dx^2/4 and dx^2/3 (Jiang et al. 2015);
   * linear and GIMP: C_p = sum_i v_i (x) grad S_ip, the exact APIC form for multilinear
   * weights. Either way an affine nodal velocity v0 + A x gives C_p = A. */
  double *C_out;
  /* With both set: LF_out = L F, where F is a particle tensor (layout of L_out), computed
   * from L in registers (L_out may stay NULL). The rate of a deformation gradient. */
  const double *F;
  double *LF_out;
  /* nscalar <= MPM_KERNELS_MAX_SCALARS nodal scalars to interpolate in the same pass:
   * s_out[j][p] = sum_i S_ip s_i[j][i] (e.g. a nodal power for an energy balance). */
  int nscalar;
  const double *s_i[MPM_KERNELS_MAX_SCALARS];
  double *s_out[MPM_KERNELS_MAX_SCALARS];
} mpm_g2p_args;

/* x wrapped into [lo, hi) when it lies at most a period outside, as mpm_grid_wrap does (inline:
 * a hot path). */
static inline double mpm_wrap_coord(double x, double lo, double hi) {
  const double len = hi - lo;
  if (x >= hi && x < hi + len) return x - len;
  if (x < lo && x >= lo - len) return x + len < hi ? x + len : lo;
  return x;
}

typedef struct mpm_kernels {
  int dim;
  /* Add m_i, (m v)_i and f_i = sum S m g - sum V sigma grad S into phase fields, and the mass
   * gradient sum m grad S into normal_i when the phase asks for it (phase->normals). */
  void (*p2g)(mpm_grid *grid, int phase, const mpm_p2g_args *a);
  void (*g2p)(const mpm_grid *grid, const mpm_g2p_args *a);
} mpm_kernels;

const mpm_kernels *mpm_kernels_get(int dim);

#endif
