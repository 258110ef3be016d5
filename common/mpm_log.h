/* Logging: rank 0 by default, every rank with a [rank] prefix when asked.
 *
 * Rank 0 also keeps a record of what it logs for the run's folder (run.log): the lines are
 * held in memory from the start of the process until mpm_log_file_open names the file (the
 * folder does not exist before the run claims it), then written there as they come. A live
 * progress line (mpm_log_status) is drawn on the console only; any other line first clears it,
 * so the terminal never shows a log line glued to a half-overwritten progress line. */
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
/* Into the record (run.log) only, not the console: rank 0, same level rule as mpm_log. */
void mpm_log_record(mpm_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Does the user watch this process's messages on a terminal? Rank 0's stderr is one; or,
 * under an MPI launcher (Open MPI's or MPICH's rank variables set), rank 0's stderr is the
 * launcher's pipe and the launcher (the parent process; above MPICH's hydra_pmi_proxy, the
 * grandparent) writes what it reads to its own stderr, which is one. Read from /proc (Linux);
 * elsewhere only stderr itself counts. A launcher that redirects, a pipe (`| tee`), a file,
 * ctest and batch schedulers (srun, whose ranks are not children of the user's shell) all
 * answer no. */
int mpm_log_console_is_terminal(void);

/* Draw one live status line on the console (rank 0): carriage-return redrawn, no newline.
 * The next log line clears it first; mpm_log_status_end ends it with a newline. */
void mpm_log_status(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void mpm_log_status_end(void);

/* Start writing the record into path (rank 0; a no-op elsewhere): the lines held so far go
 * first, after `separator` when appending to an existing record (append = 1: restart in
 * place). The file is opened without following a link, and must be a regular file. A failure
 * to open or to write warns once on the console and the run carries on without it. */
void mpm_log_file_open(const char *path, int append, const char *separator);
/* Close the record and drop the lines held (a run that never opened it: `check`); later
 * lines are held again, for a next run in the process. */
void mpm_log_file_close(void);

#endif
