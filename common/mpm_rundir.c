/* The output folder of a run (see mpm_rundir.h). All file work is done by rank 0; the outcome
 * is broadcast, so every rank returns the same code. */
#define _DEFAULT_SOURCE /* flock, realpath, lstat */
#include "mpm_rundir.h"

#include "mpm_error.h"
#include "mpm_h5.h"
#include "mpm_path.h"
#include "mpm_safefile.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <fnmatch.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define LOCK_NAME  ".lock"
#define RUNID_NAME "run.id"

struct mpm_rundir {
  int fd; /* the locked file, rank 0 only (-1 elsewhere) */
};

/* What mpmfsi writes into an output folder, by exact name pattern. Anything else in the
 * folder belongs to the user (post-processing too) and is never touched. */
static const char *const g_ours[] = {"snap_[0-9]*.h5",
                                     "checkpoint_[0-9]*.h5",
                                     "checkpoint_final.h5",
                                     "series.xmf",
                                     "grid.xmf",
                                     "diagnostics.csv",
                                     "coupling.csv",
                                     "probes.csv",
                                     "timers.csv",
                                     "summary.json",
                                     "obstacles.csv",
                                     "surface_*.csv",
                                     RUNID_NAME,
                                     "run.log",
                                     "view.py"};

/* 1: a result; 2: a leftover of an interrupted write (a result's name + ".tmp", or the lock
 * test Open MPI's OMPIO makes beside a file it opens, NAME.locktest.RANK); 0: not ours. */
static int is_ours(const char *name) {
  char base[256];
  size_t n = strlen(name);
  const char *test = strstr(name, ".locktest.");
  const int locktest = test && test[10] && !test[10 + strspn(test + 10, "0123456789")];
  if (locktest) n = (size_t)(test - name);
  const int tmp = n > 4 && n < sizeof base && strncmp(name + n - 4, ".tmp", 4) == 0;
  if (n >= sizeof base) return 0;
  snprintf(base, sizeof base, "%.*s", (int)(tmp ? n - 4 : n), name);
  for (size_t k = 0; k < sizeof g_ours / sizeof g_ours[0]; ++k)
    if (fnmatch(g_ours[k], base, 0) == 0) return tmp || locktest ? 2 : 1;
  return 0;
}

/* ---- the lock -------------------------------------------------------------------------- */

static int take_lock(const char *dir, int *fd_out) {
  char *path = mpm_path_join(dir, LOCK_NAME);
  if (!path) MPM_FAIL(MPM_ERR_MEMORY, "out of memory naming the lock of '%s'", dir);
  const int fd = mpm_file_open_fd(path, O_RDWR | O_CREAT);
  const int e = errno;
  if (fd < 0 && e == ELOOP) mpm_log_all(MPM_LOG_ERROR, MPM_LINK_REFUSAL, path);
  free(path);
  if (fd < 0 && e == ELOOP) return mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT);
  if (fd < 0)
    MPM_FAIL(MPM_ERR_INPUT, "cannot create the lock file %s/%s: %s; choose another output.dir", dir,
             LOCK_NAME, strerror(e));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0 && errno != EWOULDBLOCK) {
    const int e = errno;
    close(fd);
    MPM_FAIL(MPM_ERR_INPUT,
             "cannot lock %s/%s: %s (the file system may not support locks, as Lustre without "
             "-o flock or some network mounts); choose an output.dir on a local or lock-capable "
             "file system",
             dir, LOCK_NAME, strerror(e));
  }
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    char owner[128] = "";
    const ssize_t n = pread(fd, owner, sizeof owner - 1, 0);
    owner[n > 0 ? n : 0] = 0;
    owner[strcspn(owner, "\n")] = 0;
    close(fd);
    MPM_FAIL(MPM_ERR_INPUT,
             "output folder '%s' is in use by another mpmfsi run (%s); wait for it to end or "
             "choose another output.dir",
             dir, owner[0] ? owner : "owner unknown");
  }
  char owner[128];
  const int n =
      snprintf(owner, sizeof owner, "pid %ld, started %ld\n", (long)getpid(), (long)time(NULL));
  if (ftruncate(fd, 0) != 0 || pwrite(fd, owner, (size_t)n, 0) != n) { /* informative only */
  }
  *fd_out = fd;
  return 0;
}

/* ---- what the folder holds ------------------------------------------------------------- */

typedef struct listing {
  char **name;
  int n;
} listing;

static void listing_free(listing *l) {
  for (int k = 0; k < l->n; ++k) free(l->name[k]);
  free(l->name);
  l->name = NULL, l->n = 0;
}

/* The folder's mpmfsi files (regular files only; the lock excluded). */
static int list_ours(const char *dir, listing *l) {
  DIR *d = opendir(dir);
  if (!d) MPM_FAIL(MPM_ERR_INPUT, "cannot list the output folder '%s': %s", dir, strerror(errno));
  int cap = 0, rc = 0;
  for (struct dirent *e; !rc && (e = readdir(d));) {
    if (!is_ours(e->d_name)) continue;
    struct stat st;
    char *path = mpm_path_join(dir, e->d_name);
    const int regular = path && lstat(path, &st) == 0 && S_ISREG(st.st_mode);
    free(path);
    if (!regular) continue; /* a FIFO, a link or a folder of that name is not ours */
    if (l->n == cap) {
      char **nn = realloc(l->name, sizeof *nn * (size_t)(cap = 2 * cap + 16));
      if (!nn) {
        rc = MPM_ERR_MEMORY;
        break;
      }
      l->name = nn;
    }
    if (!(l->name[l->n] = strdup(e->d_name)))
      rc = MPM_ERR_MEMORY;
    else
      ++l->n;
  }
  closedir(d);
  if (rc) MPM_FAIL(rc, "out of memory listing the output folder '%s'", dir);
  return 0;
}

static int remove_file(const char *dir, const char *name) {
  char *path = mpm_path_join(dir, name);
  const int ok = path && (unlink(path) == 0 || errno == ENOENT);
  const int e = errno;
  free(path);
  if (!ok)
    MPM_FAIL(MPM_ERR_INPUT,
             "cannot delete %s/%s: %s; remove it by hand or choose another "
             "output.dir",
             dir, name, strerror(e));
  return 0;
}

/* The whole of a small text file, or NULL. */
static char *slurp(const char *dir, const char *name) {
  char *path = mpm_path_join(dir, name), *buf = NULL;
  FILE *f = path ? fopen(path, "r") : NULL;
  free(path);
  if (!f) return NULL;
  size_t len = 0, cap = 0;
  for (int c; (c = fgetc(f)) != EOF;) {
    if (len + 2 > cap) {
      char *nb = realloc(buf, cap = 2 * cap + 4096);
      if (!nb) {
        free(buf), fclose(f);
        return NULL;
      }
      buf = nb;
    }
    buf[len++] = (char)c;
  }
  fclose(f);
  if (buf) buf[len] = 0;
  return buf;
}

/* The time of the last row of a CSV whose first column is t (-inf: no rows). */
static double csv_last_time(const char *dir, const char *name) {
  char *text = slurp(dir, name);
  double t = -HUGE_VAL;
  if (!text) return t;
  for (char *line = strchr(text, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
    char *end;
    const double v = strtod(line + 1, &end);
    if (end != line + 1 && isfinite(v)) t = fmax(t, v);
  }
  free(text);
  return t;
}

/* The snapshots the index lists, each with its time: calls f(name, t) for each. */
static void index_entries(const char *dir, void (*f)(const char *, double, void *), void *arg) {
  char *text = slurp(dir, "series.xmf");
  if (!text) return;
  for (char *p = strstr(text, "<Time Value=\""); p; p = strstr(p, "<Time Value=\"")) {
    p += strlen("<Time Value=\"");
    const double t = strtod(p, NULL);
    char *s = strstr(p, "snap_"), name[64];
    if (!s) break;
    const size_t n = strspn(s + 5, "0123456789");
    if (n == 0 || n > 40) continue;
    snprintf(name, sizeof name, "snap_%.*s.h5", (int)n, s + 5);
    f(name, t, arg);
  }
  free(text);
}

/* The time stored in a checkpoint, or NaN if it cannot be read (a damaged or partial file is
 * no later result). */
static double checkpoint_time(const char *dir, const char *name) {
  char *path = mpm_path_join(dir, name);
  double t = NAN;
  if (!path) return t;
  H5E_auto2_t fn;
  void *data;
  H5Eget_auto2(H5E_DEFAULT, &fn, &data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  const hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file >= 0) {
    if (H5Aexists(file, "t") > 0) {
      const hid_t a = H5Aopen(file, "t", H5P_DEFAULT);
      if (a < 0 || H5Aread(a, H5T_NATIVE_DOUBLE, &t) < 0) t = NAN;
      if (a >= 0) H5Aclose(a);
    }
    H5Fclose(file);
  }
  H5Eset_auto2(H5E_DEFAULT, fn, data);
  free(path);
  return t;
}

static int same_file(const char *a, const char *b) {
  struct stat sa, sb;
  return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* ---- the decisions --------------------------------------------------------------------- */

static double new_run_id(void) {
  unsigned char b[6] = {0};
  FILE *f = fopen("/dev/urandom", "rb");
  const int got = f && fread(b, 1, sizeof b, f) == sizeof b;
  if (f) fclose(f);
  uint64_t v = 0;
  for (int k = 0; k < 6; ++k) v = v << 8 | b[k];
  if (!got) v = ((uint64_t)time(NULL) << 16) ^ (uint64_t)getpid();
  return (double)((v & ((1ULL << 48) - 1)) + 1); /* exact in a double, never 0 */
}

static double folder_run_id(const char *dir) {
  char *text = slurp(dir, RUNID_NAME);
  double id = 0;
  if (text && sscanf(text, "mpmfsi run %lf", &id) != 1) id = 0;
  free(text);
  return id;
}

static int write_run_id(const char *dir, double id) {
  char *path = mpm_path_join(dir, RUNID_NAME);
  FILE *f = path ? mpm_file_begin(path, "w") : NULL;
  int e = f ? 0 : path ? errno : ENOMEM;
  if (f) fprintf(f, "mpmfsi run %.0f\n", id);
  if (f) e = mpm_file_commit(f, path);
  if (e && path) mpm_file_fail(path, e, "run record");
  free(path);
  return e ? mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT) : 0;
}

/* A new record in dir: refused if an earlier run's results are there, unless overwrite.
 * Never deletes the checkpoint the run restarts from (keep, or NULL). */
static int start_fresh(const char *dir, int overwrite, const listing *l, const char *keep) {
  int results = 0, first = -1;
  for (int k = 0; k < l->n; ++k) {
    char *path = keep ? mpm_path_join(dir, l->name[k]) : NULL;
    const int self = path && same_file(path, keep);
    free(path);
    if (self)
      MPM_FAIL(MPM_ERR_INPUT,
               "output folder '%s' holds the checkpoint this run restarts from (%s); choose "
               "another output.dir",
               dir, l->name[k]);
    if (is_ours(l->name[k]) == 1 && ++results == 1) first = k;
  }
  if (results > 0 && !overwrite)
    MPM_FAIL(MPM_ERR_INPUT,
             "output folder '%s' already holds the results of another run (%d files, e.g. %s); "
             "choose a new output.dir, or add output.overwrite=true to delete them first",
             dir, results, l->name[first]);
  for (int k = 0; k < l->n; ++k) MPM_CALL(remove_file(dir, l->name[k]));
  if (results > 0)
    mpm_log(MPM_LOG_INFO, "output.overwrite: deleted the %d result files of the earlier run in %s",
            results, dir);
  return 0;
}

typedef struct later {
  const char *dir;
  double t, latest;
  int remove, failed, removed;
} later;

static void later_snapshot(const char *name, double t, void *arg) {
  later *L = arg;
  if (!(t > L->t * (1 + 1e-12))) return;
  L->latest = fmax(L->latest, t);
  if (L->remove && !L->failed) {
    L->failed = remove_file(L->dir, name) != 0;
    L->removed += !L->failed;
  }
}

/* The time of the checkpoint `name` in dir if it is another one than `checkpoint` and later
 * than t; NaN otherwise (also when it is no checkpoint or cannot be read). */
static double later_checkpoint(const char *dir, const char *name, const char *checkpoint,
                               double t) {
  if (fnmatch("checkpoint_*.h5", name, 0) != 0) return NAN;
  char *path = mpm_path_join(dir, name);
  const int self = path && same_file(path, checkpoint);
  free(path);
  const double tk = self ? NAN : checkpoint_time(dir, name);
  return tk > t * (1 + 1e-12) ? tk : NAN;
}

/* The latest time dir records beyond t: CSV rows, snapshots in the index, checkpoints other
 * than the one at `checkpoint` (-inf: nothing later). */
static double latest_result(const char *dir, const char *checkpoint, double t, const listing *l) {
  later L = {dir, t, -HUGE_VAL, 0, 0, 0};
  static const char *const csv[] = {"diagnostics.csv", "coupling.csv", "probes.csv"};
  for (int k = 0; k < 3; ++k) L.latest = fmax(L.latest, csv_last_time(dir, csv[k]));
  index_entries(dir, later_snapshot, &L);
  for (int k = 0; k < l->n; ++k) /* fmax ignores NaN */
    L.latest = fmax(L.latest, later_checkpoint(dir, l->name[k], checkpoint, t));
  return L.latest;
}

/* Continue dir's record from a checkpoint in it at time t: refused if later results exist,
 * unless truncate (then they are deleted; the index and CSVs are cut when reopened). */
static int continue_in_place(const mpm_rundir_request *req, const listing *l) {
  const char *dir = req->dir;
  later L = {dir, req->t, latest_result(dir, req->checkpoint, req->t, l), 0, 0, 0};
  if (!(L.latest > req->t * (1 + 1e-12))) return 0;
  if (!req->truncate)
    MPM_FAIL(MPM_ERR_INPUT,
             "output folder '%s' holds this run's results up to t = %.6g, later than the "
             "checkpoint (t = %.6g); continuing there would mix them. Give output.dir=NEW_FOLDER "
             "to continue in a new folder, or output.truncate=true to cut this run back to "
             "t = %.6g (its later snapshots and checkpoints are deleted)",
             dir, L.latest, req->t, req->t);
  L.remove = 1;
  index_entries(dir, later_snapshot, &L);
  if (L.failed) return MPM_ERR_INPUT;
  for (int k = 0; k < l->n; ++k) {
    const int tmp = is_ours(l->name[k]) == 2;
    const int stale = tmp || strcmp(l->name[k], "summary.json") == 0 ||
                      !isnan(later_checkpoint(dir, l->name[k], req->checkpoint, req->t));
    if (stale) MPM_CALL(remove_file(dir, l->name[k]));
    L.removed += stale && !tmp;
  }
  mpm_log(MPM_LOG_INFO, "output.truncate: %s cut back to t = %.6g (%d later files deleted)", dir,
          req->t, L.removed);
  return 0;
}

/* Before anything is written: a link named as one of our files (a result, a temporary, the
 * lock) is refused, or with overwrite removed (the link itself; its target is never
 * touched). */
static int clear_links(const char *dir, int overwrite) {
  char *name = mpm_rundir_find_link(dir);
  for (int removed = 0; name; name = mpm_rundir_find_link(dir)) {
    char *path = mpm_path_join(dir, name);
    const int err = !overwrite ? EEXIST : path ? mpm_file_remove(path) : ENOMEM;
    if (err == EEXIST)
      mpm_log_all(MPM_LOG_ERROR,
                  MPM_LINK_REFUSAL " (or give output.overwrite=true to delete the link)",
                  path ? path : name);
    else if (err)
      mpm_log_all(MPM_LOG_ERROR, "cannot delete the link %s: %s; remove it by hand",
                  path ? path : name, strerror(err));
    else if (++removed < 100)
      mpm_log(MPM_LOG_INFO, "output.overwrite: deleted the link %s (not what it points to)", path);
    free(path), free(name);
    if (err) return mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT);
  }
  return 0;
}

static int claim(const mpm_rundir_request *req, int *fd, int *append, double *run_id,
                 long *next_checkpoint) {
  const char *dir = req->dir;
  listing l = {NULL, 0};
  *append = 0;
  const int err = mpm_path_make_dir(dir);
  if (err)
    MPM_FAIL(MPM_ERR_INPUT,
             "cannot use '%s' as the output folder: %s; choose another output.dir, or create "
             "this one with write permission",
             dir, strerror(err));
  MPM_CALL(clear_links(dir, req->overwrite));
  MPM_CALL(take_lock(dir, fd));
  int rc = list_ours(dir, &l);
  int in_place = 0;
  if (!rc && req->checkpoint) { /* the folder the file really lies in (links resolved) */
    char *real = realpath(req->checkpoint, NULL);
    char *parent = real ? mpm_path_parent(real) : NULL;
    in_place = parent && same_file(parent, dir);
    free(parent), free(real);
  }
  if (!rc && in_place) {
    const double owner = folder_run_id(dir);
    if (owner != 0 && req->run_id != 0 && owner != req->run_id) {
      mpm_log_all(MPM_LOG_ERROR,
                  "output folder '%s' belongs to another run (run.id %.0f) than the checkpoint "
                  "%s (run %.0f); give output.dir=NEW_FOLDER to continue in a new folder",
                  dir, owner, req->checkpoint, req->run_id);
      rc = MPM_ERR_INPUT;
    }
    if (!rc) rc = continue_in_place(req, &l);
    *append = 1;
    *run_id = req->run_id != 0 ? req->run_id : owner != 0 ? owner : new_run_id();
  } else if (!rc) {
    rc = start_fresh(dir, req->overwrite, &l, req->checkpoint);
    *run_id = new_run_id();
  }
  /* Checkpoints are numbered after the highest number left in the folder, so none is ever
   * replaced (a restart may change the interval). */
  listing_free(&l);
  if (!rc) rc = list_ours(dir, &l);
  *next_checkpoint = 1;
  for (int k = 0; !rc && k < l.n; ++k) {
    long num;
    int used = 0;
    if (sscanf(l.name[k], "checkpoint_%ld.h5%n", &num, &used) == 1 &&
        used == (int)strlen(l.name[k]) && num >= *next_checkpoint)
      *next_checkpoint = num + 1;
  }
  listing_free(&l);
  if (!rc) rc = write_run_id(dir, *run_id);
  return rc;
}

char *mpm_rundir_find_link(const char *dir) {
  DIR *d = opendir(dir);
  char *found = NULL;
  for (struct dirent *e; d && !found && (e = readdir(d));) {
    if (!is_ours(e->d_name) && strcmp(e->d_name, LOCK_NAME) != 0) continue;
    char *path = mpm_path_join(dir, e->d_name);
    if (mpm_file_is_link(path)) found = strdup(e->d_name);
    free(path);
  }
  if (d) closedir(d);
  return found;
}

/* The top folders of the system: the root itself is refused too. */
static const char *const g_system[] = {"bin",    "boot", "dev",  "etc", "lib", "lib32", "lib64",
                                       "libx32", "proc", "sbin", "sys", "usr", "var",   "run"};

/* The system folder the resolved path real lies in ("/" for the root; NULL: none). A folder
 * inside one is the user's (allowed) when a folder on the way down to it, below the system
 * folder, belongs to a user other than root or is a shared scratch folder (world-writable
 * with the sticky bit, as /var/tmp and /dev/shm). */
static const char *system_folder(const char *real) {
  if (strcmp(real, "/") == 0) return "/";
  const size_t n = strcspn(real + 1, "/");
  const char *top = NULL;
  for (size_t k = 0; k < sizeof g_system / sizeof g_system[0] && !top; ++k) {
    const size_t m = strlen(g_system[k]);
    if (n == m && strncmp(real + 1, g_system[k], m) == 0) top = g_system[k];
  }
  if (!top) return NULL;
  char *p = strdup(real);
  int own = 0;
  for (char *q = p ? p + 1 + n : NULL; q && *q && !own; ++q) { /* each folder below the top */
    q += strcspn(q + 1, "/") + 1;
    const char c = *q;
    *q = 0;
    struct stat st;
    own = stat(p, &st) == 0 && S_ISDIR(st.st_mode) &&
          (st.st_uid != 0 || ((st.st_mode & S_ISVTX) && (st.st_mode & S_IWOTH)));
    *q = c;
    if (!c) break;
  }
  free(p);
  return own ? NULL : top;
}

int mpm_rundir_check_dir(const char *dir, int overwrite, char *why, size_t n) {
  why[0] = 0;
  const size_t len = strlen(dir);
  if (len > MPM_RUNDIR_MAX_DIR)
    snprintf(why, n,
             "is %zu characters long; at most %d fit (the longest file path must stay within "
             "%d characters, the limit of Open MPI's MPI-IO lock-test name): choose a shorter "
             "path",
             len, MPM_RUNDIR_MAX_DIR, MPM_RUNDIR_MAX_PATH);
  char *real = why[0] ? NULL : mpm_path_resolve(dir);
  if (!why[0] && !real) /* never accepted unchecked */
    snprintf(why, n,
             "cannot be resolved (%s): mpmfsi checks where it writes before it does; give a "
             "path whose folders exist and can be searched",
             strerror(errno));
  const char *top = real ? system_folder(real) : NULL;
  if (top) {
    const int root = strcmp(top, "/") == 0, whole = root || strcmp(real + 1, top) == 0;
    char how[64];
    snprintf(how, sizeof how, "%s the %s%s", whole ? "" : " inside",
             root ? "root folder" : "system folder /", root ? "" : top);
    const int same = strcmp(real, dir) == 0;
    snprintf(why, n,
             "%s%s%s%s: mpmfsi does not write there; choose a folder of your own (in your home, "
             "/tmp or /var/tmp)",
             same ? "is" : "resolves to ", same ? "" : real,
             same    ? ""
             : whole ? ", which is"
                     : ",",
             how);
  }
  free(real);
  char *name = why[0] || overwrite ? NULL : mpm_rundir_find_link(dir);
  if (name) {
    char *path = mpm_path_join(dir, name);
    snprintf(why, n, MPM_LINK_REFUSAL " (or give output.overwrite=true to delete the link)",
             path ? path : name);
    free(path), free(name);
  }
  return why[0] ? MPM_ERR_INPUT : 0;
}

int mpm_rundir_latest(MPI_Comm comm, const char *dir, const char *checkpoint, double t,
                      double *latest) {
  int rank;
  double v[2] = {0, -HUGE_VAL};
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    listing l = {NULL, 0};
    struct stat st;
    if (stat(dir, &st) == 0 && S_ISDIR(st.st_mode)) v[0] = list_ours(dir, &l);
    if (!v[0]) v[1] = latest_result(dir, checkpoint, t, &l);
    listing_free(&l);
  }
  MPM_CALL_MPI(MPI_Bcast(v, 2, MPI_DOUBLE, 0, comm));
  *latest = v[1];
  return (int)v[0];
}

int mpm_rundir_claim(mpm_rundir **rd, MPI_Comm comm, const mpm_rundir_request *req, int *append,
                     double *run_id, long *next_checkpoint) {
  int rank;
  *rd = NULL;
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  mpm_rundir *r = malloc(sizeof *r);
  int rc = r ? 0 : MPM_ERR_MEMORY;
  double state[4] = {0, 0, 0, 1};
  if (r) r->fd = -1;
  if (!rc && rank == 0) {
    rc = claim(req, &r->fd, append, run_id, next_checkpoint);
    state[1] = *append, state[2] = *run_id, state[3] = (double)*next_checkpoint;
  }
  state[0] = rc;
  MPM_CALL_MPI(MPI_Bcast(state, 4, MPI_DOUBLE, 0, comm));
  rc = mpm_h5_agree(comm, rc ? rc : (int)state[0]);
  if (rc) {
    mpm_rundir_release(&r);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *append = (int)state[1], *run_id = state[2], *next_checkpoint = (long)state[3];
  *rd = r;
  return 0;
}

void mpm_rundir_release(mpm_rundir **rd) {
  if (!rd || !*rd) return;
  if ((*rd)->fd >= 0) {
    if (ftruncate((*rd)->fd, 0) != 0) { /* the owner line is informative only */
    }
    close((*rd)->fd); /* releases the lock */
  }
  free(*rd);
  *rd = NULL;
}
