/* 3-D instantiation of the kernels. */
#include "mpm_kernels.h"

#define MPM_DIM 3
#include "mpm_kernels_dim.c"
