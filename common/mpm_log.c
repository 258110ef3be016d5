/* Logging and error strings. Messages go to stderr so that stdout stays clean for
 * machine-readable output such as `mpmfsi check`. Rank 0 keeps its lines for run.log as well
 * (see mpm_log.h): held in memory until the run's folder exists, then appended to the file.
 * The record must never stop a run: a failed open or write warns once and the run goes on. */
#define _DEFAULT_SOURCE /* O_NOFOLLOW, O_CLOEXEC */
#include "mpm_error.h"
#include "mpm_safefile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static struct {
  int rank, size, all_ranks;
  mpm_log_level level;
} g_log = {0, 1, 0, MPM_LOG_INFO};

/* The record, rank 0 only. Lines are held until the file is named; a run that logs more than
 * HELD_MAX before its folder exists (it does not: a few dozen lines) keeps the first part. */
#define HELD_MAX (1 << 20)
enum { REC_HOLD, REC_FILE, REC_OFF };
static struct {
  int state;         /* REC_HOLD: into held; REC_FILE: into fd; REC_OFF: a write failed */
  int fd;            /* the open run.log (REC_FILE) */
  char *held;        /* the lines logged before the file was named */
  size_t nheld, cap; /* bytes held, allocated */
  long dropped;      /* lines beyond HELD_MAX */
  int status_len;    /* characters of the live line on the console (0: none shown) */
  char path[4096];   /* the file, for messages */
} g_rec = {REC_HOLD, -1, NULL, 0, 0, 0, 0, ""};

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

/* ---- the record (run.log) -------------------------------------------------------------- */

static int write_all(int fd, const char *buf, size_t n) {
  while (n > 0) {
    const ssize_t k = write(fd, buf, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return k < 0 ? errno : EIO;
    buf += k, n -= (size_t)k;
  }
  return 0;
}

/* Give up on the file (full disk, a removed mount): once, on the console only. */
static void record_failed(const char *what, int err, const char *hint) {
  if (g_rec.state == REC_FILE) close(g_rec.fd);
  g_rec.state = REC_OFF, g_rec.fd = -1;
  fprintf(stderr,
          "warn: cannot %s the run's log %s: %s; the run goes on without it (the console shows "
          "every line)%s\n",
          what, g_rec.path, strerror(err), hint);
  fflush(stderr);
}

static void hold(const char *line, size_t n) {
  if (g_rec.nheld + n > HELD_MAX) {
    g_rec.dropped++;
    return;
  }
  if (g_rec.nheld + n > g_rec.cap) {
    size_t cap = g_rec.cap ? 2 * g_rec.cap : 8192;
    while (cap < g_rec.nheld + n) cap *= 2;
    char *b = realloc(g_rec.held, cap);
    if (!b) {
      g_rec.dropped++;
      return;
    }
    g_rec.held = b, g_rec.cap = cap;
  }
  memcpy(g_rec.held + g_rec.nheld, line, n);
  g_rec.nheld += n;
}

/* One line, newline included. */
static void record(const char *line, size_t n) {
  if (g_log.rank != 0) return;
  if (g_rec.state == REC_HOLD) hold(line, n);
  if (g_rec.state != REC_FILE) return;
  const int err = write_all(g_rec.fd, line, n);
  if (err) record_failed("write", err, "; free disk space for the next run");
}

void mpm_log_file_open(const char *path, int append, const char *separator) {
  if (g_log.rank != 0) return;
  if (g_rec.state == REC_FILE) close(g_rec.fd); /* a record still open: the lines held stay */
  snprintf(g_rec.path, sizeof g_rec.path, "%s", path);
  /* No link is followed (a link planted in the folder would redirect the write), a FIFO is not
   * waited on, and only a regular file is written (mpm_safefile.h). */
  const int fd = mpm_file_open_fd(path, O_WRONLY | O_CREAT | O_APPEND | (append ? 0 : O_TRUNC));
  struct stat st;
  int err = fd < 0 ? errno : fstat(fd, &st) != 0 ? errno : 0;
  if (err) {
    if (fd >= 0) close(fd);
    /* A link, FIFO or folder of that name is left alone (as mpm_rundir does). */
    record_failed("open", err == EINVAL ? EISDIR : err,
                  err == EINVAL || err == ELOOP || err == ENXIO
                      ? "; it is not a regular file: remove it to keep a log next time"
                      : "");
    free(g_rec.held), g_rec.held = NULL, g_rec.nheld = g_rec.cap = 0;
    return;
  }
  g_rec.state = REC_FILE, g_rec.fd = fd;
  if (append && separator) {
    char sep[1024];
    const int n = snprintf(sep, sizeof sep, "%s%s\n", st.st_size > 0 ? "\n" : "", separator);
    record(sep, (size_t)(n < (int)sizeof sep ? n : (int)sizeof sep - 1));
  }
  if (g_rec.nheld) record(g_rec.held, g_rec.nheld);
  if (g_rec.dropped) {
    char note[128];
    const int n = snprintf(note, sizeof note, "(%ld earlier lines not kept)\n", g_rec.dropped);
    record(note, (size_t)n);
  }
  free(g_rec.held), g_rec.held = NULL, g_rec.nheld = g_rec.cap = 0, g_rec.dropped = 0;
}

void mpm_log_file_close(void) {
  if (g_rec.state == REC_FILE) close(g_rec.fd);
  g_rec.state = REC_HOLD, g_rec.fd = -1;
  free(g_rec.held), g_rec.held = NULL, g_rec.nheld = g_rec.cap = 0, g_rec.dropped = 0;
}

/* ---- the console ----------------------------------------------------------------------- */

static void status_clear(void) {
  if (g_rec.status_len > 0) fprintf(stderr, "\r%*s\r", g_rec.status_len, "");
  g_rec.status_len = 0;
}

void mpm_log_status(const char *fmt, ...) {
  if (g_log.rank != 0) return;
  char line[512];
  va_list ap;
  va_start(ap, fmt);
  const int n = vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  const int len = n < (int)sizeof line ? n : (int)sizeof line - 1;
  /* Pad over what a longer line left. */
  fprintf(stderr, "\r%s%*s", line, g_rec.status_len > len ? g_rec.status_len - len : 0, "");
  if (g_rec.status_len > len) fprintf(stderr, "\r%s", line);
  g_rec.status_len = len > 0 ? len : 1;
  fflush(stderr);
}

void mpm_log_status_end(void) {
  if (g_log.rank != 0 || g_rec.status_len == 0) return;
  fputc('\n', stderr);
  fflush(stderr);
  g_rec.status_len = 0;
}

/* Is the stderr of process pid (its fd 2, through /proc) a terminal? */
static int stderr_is_terminal(long pid) {
  char path[64];
  struct stat st;
  snprintf(path, sizeof path, "/proc/%ld/fd/2", pid);
  if (stat(path, &st) != 0 || !S_ISCHR(st.st_mode)) return 0; /* a file, pipe or socket */
  const int fd = open(path, O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  const int tty = fd >= 0 && isatty(fd);
  if (fd >= 0) close(fd);
  return tty;
}

/* The parent of pid and its command name, from /proc/PID/stat ("pid (comm) state ppid ..."). */
static long parent_of(long pid, char *comm, size_t n) {
  char path[64], text[512];
  snprintf(path, sizeof path, "/proc/%ld/stat", pid);
  FILE *f = fopen(path, "r");
  const size_t len = f ? fread(text, 1, sizeof text - 1, f) : 0;
  if (f) fclose(f);
  text[len] = 0;
  char *open = strchr(text, '('), *close = strrchr(text, ')');
  long ppid = 0;
  if (!open || !close || close < open || sscanf(close + 1, " %*c %ld", &ppid) != 1) return 0;
  snprintf(comm, n, "%.*s", (int)(close - open - 1), open + 1);
  return ppid;
}

int mpm_log_console_is_terminal(void) {
  if (isatty(STDERR_FILENO)) return 1;
  /* Set by mpiexec (Open MPI 4 and 5, MPICH), not by a singleton start (Open MPI's sets
   * PMIX_RANK, and OMPI_MCA_ess=singleton): without a launcher, stderr was redirected by the
   * user and the parent (a shell, a test driver) does not forward it. */
  const char *ess = getenv("OMPI_MCA_ess");
  const int launched =
      (getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMI_RANK")) &&
      !(ess && strcmp(ess, "singleton") == 0);
  struct stat st; /* a launcher forwards through a pipe or a socket */
  if (!launched || fstat(STDERR_FILENO, &st) != 0 ||
      !(S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode)))
    return 0;
  char comm[64] = "";
  long pid = parent_of((long)getpid(), comm, sizeof comm);
  if (pid > 1 && parent_of(pid, comm, sizeof comm) > 1 && strcmp(comm, "hydra_pmi_proxy") == 0)
    pid = parent_of(pid, comm, sizeof comm); /* MPICH: the proxy forwards to mpiexec */
  return pid > 1 && stderr_is_terminal(pid);
}

/* ---- the lines ------------------------------------------------------------------------- */

enum { TO_CONSOLE = 1, TO_RECORD = 2 };

static void vlog(mpm_log_level level, int to, const char *fmt, va_list ap) {
  char line[4096];
  int k = 0;
  if (g_log.size > 1 && (g_log.all_ranks || g_log.rank != 0))
    k = snprintf(line, sizeof line, "[%d] ", g_log.rank);
  if (level <= MPM_LOG_WARN)
    k += snprintf(line + k, sizeof line - (size_t)k, "%s: ", g_level_names[level]);
  k += vsnprintf(line + k, sizeof line - (size_t)k, fmt, ap);
  if (k > (int)sizeof line - 2) k = (int)sizeof line - 2;
  line[k++] = '\n', line[k] = 0;
  if (to & TO_CONSOLE) {
    status_clear();
    fputs(line, stderr);
    fflush(stderr);
  }
  if (to & TO_RECORD) record(line, (size_t)k);
}

void mpm_log(mpm_log_level level, const char *fmt, ...) {
  if (level > g_log.level || (g_log.rank != 0 && !g_log.all_ranks)) return;
  va_list ap;
  va_start(ap, fmt);
  vlog(level, TO_CONSOLE | TO_RECORD, fmt, ap);
  va_end(ap);
}

void mpm_log_all(mpm_log_level level, const char *fmt, ...) {
  if (level > g_log.level) return;
  va_list ap;
  va_start(ap, fmt);
  vlog(level, TO_CONSOLE | TO_RECORD, fmt, ap);
  va_end(ap);
}

void mpm_log_record(mpm_log_level level, const char *fmt, ...) {
  if (level > g_log.level || g_log.rank != 0) return;
  va_list ap;
  va_start(ap, fmt);
  vlog(level, TO_RECORD, fmt, ap);
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
