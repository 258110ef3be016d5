/* Logging and error strings. Messages go to stderr so that stdout stays clean for
 * machine-readable output such as `mpmfsi check`. */
#include "mpm_error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static struct {
  int rank, size, all_ranks;
  mpm_log_level level;
} g_log = {0, 1, 0, MPM_LOG_INFO};

static const char *const g_level_names[] = {"error", "warn", "info", "debug", "trace"};

void mpm_log_init(MPI_Comm comm, mpm_log_level level, int all_ranks) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized) {
    MPI_Comm_rank(comm, &g_log.rank);
    MPI_Comm_size(comm, &g_log.size);
  }
  g_log.level = level;
  g_log.all_ranks = all_ranks;
}

void mpm_log_set_level(mpm_log_level level) {
  g_log.level = level;
}
mpm_log_level mpm_log_get_level(void) {
  return g_log.level;
}

int mpm_log_level_parse(const char *name) {
  for (int i = 0; i <= MPM_LOG_TRACE; ++i)
    if (strcmp(name, g_level_names[i]) == 0) return i;
  return -1;
}

static void vlog(mpm_log_level level, const char *fmt, va_list ap) {
  char line[4096];
  int k = 0;
  if (g_log.size > 1 && (g_log.all_ranks || g_log.rank != 0))
    k = snprintf(line, sizeof line, "[%d] ", g_log.rank);
  if (level <= MPM_LOG_WARN)
    k += snprintf(line + k, sizeof line - (size_t)k, "%s: ", g_level_names[level]);
  vsnprintf(line + k, sizeof line - (size_t)k, fmt, ap);
  fprintf(stderr, "%s\n", line);
  fflush(stderr);
}

void mpm_log(mpm_log_level level, const char *fmt, ...) {
  if (level > g_log.level || (g_log.rank != 0 && !g_log.all_ranks)) return;
  va_list ap;
  va_start(ap, fmt);
  vlog(level, fmt, ap);
  va_end(ap);
}

void mpm_log_all(mpm_log_level level, const char *fmt, ...) {
  if (level > g_log.level) return;
  va_list ap;
  va_start(ap, fmt);
  vlog(level, fmt, ap);
  va_end(ap);
}

const char *mpm_error_string(int code) {
  static const char *const msgs[] = {
#define MPM_X_MSG(code, msg) msg,
      MPM_ERROR_LIST(MPM_X_MSG)
#undef MPM_X_MSG
  };
  if (code < 0 || code >= MPM_ERR_COUNT) return "unknown error";
  return msgs[code];
}

int mpm_trace(const char *file, int line, const char *func, int code) {
  mpm_log_all(MPM_LOG_DEBUG, "  at %s:%d in %s(): %s", file, line, func, mpm_error_string(code));
  return code;
}
