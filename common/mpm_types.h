/* Basic types shared by every module.
 *
 * Indices are typed as in p4est: a 32-bit local index (particles or nodes on one rank) and
 * a 64-bit global index (particle ids, global node numbers), each with its MPI datatype. */
#ifndef MPM_TYPES_H
#define MPM_TYPES_H

#include <stdint.h>
#include <mpi.h>

#define MPM_MAX_DIM 3

typedef int32_t mpm_lidx;
typedef int64_t mpm_gidx;
#define MPM_MPI_LIDX MPI_INT32_T
#define MPM_MPI_GIDX MPI_INT64_T

#define MPM_MIN(a, b) ((a) < (b) ? (a) : (b))
#define MPM_MAX(a, b) ((a) > (b) ? (a) : (b))

#endif
