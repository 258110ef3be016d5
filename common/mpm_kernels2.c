/* 2-D instantiation of the kernels, and the per-dimension table lookup. */
#include "mpm_kernels.h"

#define MPM_DIM 2
#include "mpm_kernels_dim.c"

extern const mpm_kernels mpm_kernels_3d;

const mpm_kernels *mpm_kernels_get(int dim) {
  return dim == 2 ? &mpm_kernels_2d : dim == 3 ? &mpm_kernels_3d : 0;
}
