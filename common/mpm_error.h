/* Error codes, the CALL macros and user-facing failure messages.
 *
 * Every fallible function returns an int: 0 on success, an mpm error code otherwise.
 * MPM_CALL(expr) propagates a failure and logs one traceback frame (file:line:function)
 * at debug level, so `run.log_level = debug` shows the whole chain while a user sees only
 * the one-line message written where the failure was detected (MPM_FAIL). MPI, HDF5 and
 * SUNDIALS return codes go through their own CALL variants.
 *
 * MPM_ERR_OUTPUT is a failed write of one of the run's files that every rank has agreed on
 * (and explained once): the run can end cleanly on every rank, as for bad input. */
#ifndef MPM_ERROR_H
#define MPM_ERROR_H

#define MPM_ERROR_LIST(X)                                                                          \
  X(MPM_SUCCESS, "success")                                                                        \
  X(MPM_ERR_MEMORY, "out of memory")                                                               \
  X(MPM_ERR_INPUT, "invalid input")                                                                \
  X(MPM_ERR_FILE, "file could not be read or written")                                             \
  X(MPM_ERR_MPI, "MPI call failed")                                                                \
  X(MPM_ERR_HDF5, "HDF5 call failed")                                                              \
  X(MPM_ERR_SUNDIALS, "SUNDIALS call failed")                                                      \
  X(MPM_ERR_UNPHYSICAL, "unphysical state")                                                        \
  X(MPM_ERR_INTERRUPTED, "stopped by a signal")                                                    \
  X(MPM_ERR_OUTPUT, "an output file could not be written")                                         \
  X(MPM_ERR_INTERNAL, "internal error")

typedef enum {
#define MPM_X_ENUM(code, msg) code,
  MPM_ERROR_LIST(MPM_X_ENUM)
#undef MPM_X_ENUM
      MPM_ERR_COUNT
} mpm_error;

const char *mpm_error_string(int code);

/* Log one traceback frame; returns code so it can sit in an expression. */
int mpm_trace(const char *file, int line, const char *func, int code);

#define MPM_CALL(expr)                                                                             \
  do {                                                                                             \
    int mpm_rc_ = (expr);                                                                          \
    if (mpm_rc_ != 0) return mpm_trace(__FILE__, __LINE__, __func__, mpm_rc_);                     \
  } while (0)

/* Log a message at error level on this rank and return code. */
#define MPM_FAIL(code, ...)                                                                        \
  do {                                                                                             \
    mpm_log_all(MPM_LOG_ERROR, __VA_ARGS__);                                                       \
    return mpm_trace(__FILE__, __LINE__, __func__, (code));                                        \
  } while (0)

#define MPM_CALL_MPI(expr)                                                                         \
  do {                                                                                             \
    int mpm_rc_ = (expr);                                                                          \
    if (mpm_rc_ != MPI_SUCCESS)                                                                    \
      MPM_FAIL(MPM_ERR_MPI, "%s failed with MPI error %d", #expr, mpm_rc_);                        \
  } while (0)

/* HDF5 calls return a negative value on failure. */
#define MPM_CALL_H5(expr)                                                                          \
  do {                                                                                             \
    if ((expr) < 0) MPM_FAIL(MPM_ERR_HDF5, "%s failed", #expr);                                    \
  } while (0)

/* SUNDIALS calls return a negative flag on failure. */
#define MPM_CALL_SUN(expr)                                                                         \
  do {                                                                                             \
    int mpm_rc_ = (expr);                                                                          \
    if (mpm_rc_ < 0) MPM_FAIL(MPM_ERR_SUNDIALS, "%s failed with flag %d", #expr, mpm_rc_);         \
  } while (0)

/* What a user is told when memory runs out (the code location is in the debug traceback). */
#define MPM_OOM_MESSAGE                                                                            \
  "out of memory: %.4g MB more could not be allocated on this rank; the case needs more "          \
  "memory than each rank has: coarsen grid.dx, use fewer particles per cell, or run on more "      \
  "ranks or nodes"

/* Fail with MPM_ERR_MEMORY and the message above, for an allocation of `bytes`. */
#define MPM_FAIL_OOM(bytes) MPM_FAIL(MPM_ERR_MEMORY, MPM_OOM_MESSAGE, (double)(bytes) / 1e6)

/* Allocation that fails with MPM_ERR_MEMORY. */
#define MPM_ALLOC(ptr, count)                                                                      \
  do {                                                                                             \
    size_t mpm_n_ = (size_t)(count);                                                               \
    (ptr) = calloc(mpm_n_ ? mpm_n_ : 1, sizeof(*(ptr)));                                           \
    if (!(ptr)) MPM_FAIL(MPM_ERR_MEMORY, MPM_OOM_MESSAGE, (double)mpm_n_ * sizeof(*(ptr)) / 1e6);  \
  } while (0)

#include "mpm_log.h"

#endif
