/* Small tensor helpers over component-major particle arrays: component (r, c) of particle i
 * of a dim x dim tensor field T with stride n is T[(r*dim + c)*n + i]. */
#ifndef SOLID_TENSOR_H
#define SOLID_TENSOR_H

#include "mpm_types.h"

#include <stddef.h>

/* Determinant of the dim x dim tensor of particle i. */
static inline double solid_det(int dim, const double *F, mpm_lidx n, mpm_lidx i) {
#define A(r, c) F[(size_t)((r)*dim + (c)) * (size_t)n + (size_t)i]
  if (dim == 2) return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
  return A(0, 0) * (A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1)) -
         A(0, 1) * (A(1, 0) * A(2, 2) - A(1, 2) * A(2, 0)) +
         A(0, 2) * (A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0));
#undef A
}

#endif
