/* SUNDIALS version differences in one place: 6.x takes a pointer to the communicator in
 * SUNContext_Create, 7.x takes the communicator itself. */
#ifndef MPM_SUNDIALS_H
#define MPM_SUNDIALS_H

#include <mpi.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>

static inline int mpm_sun_context_create(MPI_Comm *comm, SUNContext *ctx) {
#if SUNDIALS_VERSION_MAJOR >= 7
  return SUNContext_Create(*comm, ctx);
#else
  return SUNContext_Create((void *)comm, ctx);
#endif
}

#if SUNDIALS_VERSION_MAJOR >= 7
typedef sunrealtype mpm_sunreal;
#else
typedef realtype mpm_sunreal;
#endif

#endif
