/* Shape functions on a uniform lattice: linear, GIMP, quadratic and cubic B-spline.
 *
 * Everything here is in grid units: xi = (x - origin) / dx is the particle position
 * measured in cells, node i sits at xi = i. A 1-D evaluation returns the first node of
 * the stencil (`base`) and, for k = 0 .. support-1, the weight w[k] of node base+k and its
 * derivative dw[k] = dS/dxi (divide by dx for a physical gradient). Unused stencil slots
 * are set to zero, so a fixed-size stencil loop is always correct.
 *
 * The functions are static inline so that a kernel written as
 *   switch (kind) { case MPM_SHAPE_QUADRATIC: loop(MPM_SHAPE_QUADRATIC); ... }
 * is specialised by the compiler for each kind: no indirect call per particle. */
#ifndef MPM_SHAPE_H
#define MPM_SHAPE_H

#include <math.h>

typedef enum {
  MPM_SHAPE_LINEAR,
  MPM_SHAPE_GIMP,
  MPM_SHAPE_QUADRATIC,
  MPM_SHAPE_CUBIC,
  MPM_SHAPE_COUNT
} mpm_shape_kind;

#define MPM_SHAPE_MAX_SUPPORT 4

/* "linear", "gimp", "quadratic", "cubic"; -1 if unknown. */
int mpm_shape_parse(const char *name);
const char *mpm_shape_name(mpm_shape_kind kind);

/* Nodes per direction in a stencil. */
static inline int mpm_shape_support(mpm_shape_kind kind) {
  static const int s[MPM_SHAPE_COUNT] = {2, 3, 3, 4};
  return s[kind];
}

/* Ghost layers a box needs on each side. The stencil of a particle in cell c spans nodes
 * c-1 .. c+2 at most; one more layer lets a particle drift up to one cell past its rank's
 * cells during a step (the CFL limit keeps a step under one cell) before migration moves it
 * between steps. The driver checks the drift and rejects a step that goes further. */
static inline int mpm_shape_ghost_width(mpm_shape_kind kind) {
  return kind == MPM_SHAPE_LINEAR ? 2 : 3;
}

/* GIMP with a particle half-width lp (grid units, 0 < lp <= 0.5). */
static inline void mpm_shape_gimp_node(double r, double lp, double *w, double *dw) {
  const double a = fabs(r), s = r < 0 ? -1.0 : 1.0;
  if (a < lp) {
    *w = 1.0 - (r * r + lp * lp) / (2.0 * lp);
    *dw = -r / lp;
  } else if (a < 1.0 - lp) {
    *w = 1.0 - a;
    *dw = -s;
  } else if (a < 1.0 + lp) {
    const double q = 1.0 + lp - a;
    *w = q * q / (4.0 * lp);
    *dw = -s * q / (2.0 * lp);
  } else {
    *w = 0.0;
    *dw = 0.0;
  }
}

/* floor(y) as an int for |y| < 2^31: truncation, less one below a negative non-integer.
 * The same value as (int)floor(y), without the general path the compiler emits for floor
 * on targets without a rounding instruction. */
static inline int mpm_shape_floor(double y) {
  const int i = (int)y;
  return i - (y < (double)i);
}

static inline int mpm_shape_1d(mpm_shape_kind kind, double xi, double lp,
                               double w[MPM_SHAPE_MAX_SUPPORT], double dw[MPM_SHAPE_MAX_SUPPORT]) {
  int base;
  w[3] = dw[3] = 0.0;
  switch (kind) {
  case MPM_SHAPE_LINEAR: {
    base = mpm_shape_floor(xi);
    const double f = xi - base;
    w[0] = 1.0 - f, dw[0] = -1.0;
    w[1] = f, dw[1] = 1.0;
    w[2] = dw[2] = 0.0;
    break;
  }
  case MPM_SHAPE_GIMP: {
    base = mpm_shape_floor(xi + 0.5) - 1;
    for (int k = 0; k < 3; ++k) mpm_shape_gimp_node(xi - (base + k), lp, &w[k], &dw[k]);
    break;
  }
  case MPM_SHAPE_QUADRATIC: {
    base = mpm_shape_floor(xi - 0.5);
    const double f = xi - base; /* in [0.5, 1.5) */
    const double a = 1.5 - f, c = f - 0.5, b = f - 1.0;
    w[0] = 0.5 * a * a, dw[0] = -a;
    w[1] = 0.75 - b * b, dw[1] = -2.0 * b;
    w[2] = 0.5 * c * c, dw[2] = c;
    break;
  }
  case MPM_SHAPE_CUBIC:
  default: {
    base = mpm_shape_floor(xi) - 1;
    const double f = xi - base; /* in [1, 2) */
    for (int k = 0; k < 4; ++k) {
      const double r = f - k, a = fabs(r), s = r < 0 ? -1.0 : 1.0;
      if (a < 1.0) {
        w[k] = (0.5 * a - 1.0) * a * a + 2.0 / 3.0;
        dw[k] = s * (1.5 * a - 2.0) * a;
      } else if (a < 2.0) {
        const double q = 2.0 - a;
        w[k] = q * q * q / 6.0;
        dw[k] = -s * 0.5 * q * q;
      } else {
        w[k] = dw[k] = 0.0;
      }
    }
    break;
  }
  }
  return base;
}

/* Weights and derivatives per direction for a particle at xi[0..dim-1]. */
static inline void mpm_shape_eval(mpm_shape_kind kind, int dim, const double *xi, double lp,
                                  int base[3], double w[3][MPM_SHAPE_MAX_SUPPORT],
                                  double dw[3][MPM_SHAPE_MAX_SUPPORT]) {
  for (int d = 0; d < dim; ++d) base[d] = mpm_shape_1d(kind, xi[d], lp, w[d], dw[d]);
}

#endif
