/* Logging: rank 0 by default, every rank with a [rank] prefix when asked. */
#ifndef MPM_LOG_H
#define MPM_LOG_H

#include <mpi.h>

typedef enum {
  MPM_LOG_ERROR,
  MPM_LOG_WARN,
  MPM_LOG_INFO,
  MPM_LOG_DEBUG,
  MPM_LOG_TRACE
} mpm_log_level;

/* Set the communicator, the level and whether every rank logs (default: rank 0 only). */
void mpm_log_init(MPI_Comm comm, mpm_log_level level, int all_ranks);
void mpm_log_set_level(mpm_log_level level);
mpm_log_level mpm_log_get_level(void);
/* Parse "error", "warn", "info", "debug", "trace"; returns -1 if unknown. */
int mpm_log_level_parse(const char *name);

/* Log on rank 0 only (or on every rank when all_ranks was set). */
void mpm_log(mpm_log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Log on the calling rank, whatever its number, with a [rank] prefix when size > 1. */
void mpm_log_all(mpm_log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
