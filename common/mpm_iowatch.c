/* Failed collective writes: the reservation of a file's blocks, the watchdog and the words of
 * the one line (mpm_iowatch.h). The watchdog runs in a timer thread of its own while the main
 * thread may be blocked in MPI; they share only the fields of g_watch below, written before
 * the timer is armed. */
#define _GNU_SOURCE /* fallocate */
#include "mpm_iowatch.h"
#include "mpm_error.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <mpi.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

static struct {
  int installed;     /* the timer and the rank are set up */
  int active;        /* between mpm_iowatch_begin and mpm_iowatch_end */
  int err;           /* errno of a failure this rank saw, for the watchdog's line */
  int armed, rank;   /* the timer runs; this rank in MPI_COMM_WORLD */
  timer_t timer;     /* created on first use */
  int have_timer;    /* timer is valid */
  char what[32];     /* "snapshot", "checkpoint" */
  char path[4096];   /* the file being written */
  char intact[4096]; /* the newest complete checkpoint ("" if none yet) */
} g_watch;

/* The folder of path (a file), for statvfs. */
static void folder_of(const char *path, char *dir, size_t size) {
  snprintf(dir, size, "%s", path);
  char *slash = strrchr(dir, '/');
  if (!slash)
    snprintf(dir, size, ".");
  else if (slash == dir)
    dir[1] = 0;
  else
    *slash = 0;
}

void mpm_iowatch_set_checkpoint(const char *path) {
  snprintf(g_watch.intact, sizeof g_watch.intact, "%s", path ? path : "");
}

void mpm_iowatch_intact(char *buf, size_t size) {
  if (g_watch.intact[0])
    snprintf(buf, size, "earlier checkpoints are intact: %s", g_watch.intact);
  else
    snprintf(buf, size, "no checkpoint of this run was complete yet");
}

void mpm_iowatch_cause(char *buf, size_t size, int err, const char *dir) {
  struct statvfs fs;
  const long long avail =
      dir && statvfs(dir, &fs) == 0 ? (long long)fs.f_bavail * (long long)fs.f_frsize : -1;
  if (err == EDQUOT)
    snprintf(buf, size,
             "the disk quota is exhausted (%lld bytes free on the file system); free some space "
             "or write the output elsewhere (output.dir)",
             avail);
  else if (err == ENOSPC || (avail >= 0 && avail < (1LL << 20)))
    snprintf(buf, size,
             "no space left on device (the file system is full: %lld bytes free); free some "
             "space or write the output elsewhere (output.dir)",
             avail);
  else if (err)
    snprintf(buf, size, "%s (%lld bytes free); check the disk and the permissions of its folder",
             strerror(err), avail);
  else
    snprintf(buf, size,
             "the write failed (%lld bytes free); check the disk and the permissions of its "
             "folder",
             avail);
}

static double watchdog_seconds(void) {
  const char *env = getenv("MPMFSI_IO_WATCHDOG");
  const double s = env ? atof(env) : 0;
  return s > 0 ? fmin(s, 1e6) : MPM_IOWATCH_SECONDS; /* a timer's seconds must fit */
}

/* The timer thread: the write is stuck inside a collective call that another rank left. */
static void expire(union sigval v) {
  (void)v;
  char cause[512], intact[4200], dir[4096];
  folder_of(g_watch.path, dir, sizeof dir);
  mpm_iowatch_cause(cause, sizeof cause, g_watch.err, dir);
  mpm_iowatch_intact(intact, sizeof intact);
  mpm_log_all(MPM_LOG_ERROR,
              "cannot write the %s %s: %s; the ranks did not finish the write together within "
              "the watchdog's %g s, so the run is aborted. The file it was to replace, if any, is "
              "left as it was; %s",
              g_watch.what, g_watch.path, cause, watchdog_seconds(), intact);
  /* Not MPI_Abort: MPI was initialised without thread support and this is the timer's
   * thread. A rank that exits with a non-zero status makes mpiexec end the others. */
  fflush(stderr);
  _exit(1);
}

/* Every rank arms its watchdog for the close; rank r fires r seconds later than rank 0 (at
 * most 10 s later), so that one rank writes the line before its exit ends the others. */
void mpm_iowatch_arm(int err) {
  g_watch.err = err;
  if (g_watch.armed || !g_watch.have_timer || !g_watch.active) return;
  const double s = watchdog_seconds() + (g_watch.rank < 10 ? g_watch.rank : 10);
  struct itimerspec when = {{0, 0}, {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)}};
  if (timer_settime(g_watch.timer, 0, &when, NULL) == 0) g_watch.armed = 1;
}

static void install(void) {
  g_watch.installed = 1;
  struct sigevent ev;
  memset(&ev, 0, sizeof ev);
  ev.sigev_notify = SIGEV_THREAD;
  ev.sigev_notify_function = expire;
  g_watch.have_timer = timer_create(CLOCK_MONOTONIC, &ev, &g_watch.timer) == 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_watch.rank);
}

void mpm_iowatch_begin(const char *what, const char *path) {
  if (!g_watch.installed) install();
  snprintf(g_watch.what, sizeof g_watch.what, "%s", what);
  snprintf(g_watch.path, sizeof g_watch.path, "%s", path);
  g_watch.active = 1;
}

void mpm_iowatch_end(void) {
  g_watch.active = 0;
  if (g_watch.armed) {
    const struct itimerspec off = {{0, 0}, {0, 0}};
    timer_settime(g_watch.timer, 0, &off, NULL);
    g_watch.armed = 0;
  }
}

int mpm_iowatch_reserve(int fd, long long end, long long *reserved, int *unsupported) {
  if (end <= *reserved) return 0;
  if (!*unsupported) {
    /* Blocks below the end of file too: HDF5 leaves holes for the metadata it flushes last. */
    if (fallocate(fd, FALLOC_FL_KEEP_SIZE, 0, (off_t)end) == 0) {
      *reserved = end;
      return 0;
    }
    if (errno != EOPNOTSUPP && errno != ENOSYS && errno != EINVAL) return errno;
    *unsupported = 1;
    errno = 0; /* not the cause of any later failure */
  }
  /* No way to reserve blocks here (NFS, some parallel file systems): at least refuse to start
   * a write the free space cannot hold. */
  struct statvfs fs;
  if (fstatvfs(fd, &fs) == 0 && (long long)fs.f_bavail * (long long)fs.f_frsize < end - *reserved)
    return ENOSPC;
  *reserved = end;
  return 0;
}

int mpm_iowatch_room(const char *path, long long bytes) {
  char dir[4096];
  folder_of(path, dir, sizeof dir);
  struct statvfs fs;
  if (statvfs(dir, &fs) != 0) return 0; /* the create will say what is wrong */
  return (long long)fs.f_bavail * (long long)fs.f_frsize < bytes ? ENOSPC : 0;
}

void mpm_iowatch_release(int fd, long long reserved) {
  struct stat st;
  if (fstat(fd, &st) == 0 && reserved > (long long)st.st_size)
    fallocate(fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, st.st_size,
              (off_t)(reserved - (long long)st.st_size));
}

const char *mpm_iowatch_failed_write(const char *what, const char *path, int err) {
  static char line[9000];
  char cause[512], intact[4200], dir[4096];
  folder_of(path, dir, sizeof dir);
  mpm_iowatch_cause(cause, sizeof cause, err, dir);
  mpm_iowatch_intact(intact, sizeof intact);
  snprintf(line, sizeof line, "cannot write the %s %s: %s; %s", what, path, cause, intact);
  return line;
}
