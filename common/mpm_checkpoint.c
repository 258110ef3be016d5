/* Checkpoints: the complete particle state in one parallel HDF5 file, for restarts.
 * mpm_output.h gives the layout; this file adds, as attributes, "format" on the root (what
 * marks an mpmfsi checkpoint) and on each phase group "dim", "field_names" (comma-separated)
 * and "field_ncomp", so that a restart can tell whether the stored particles fit the set
 * the run created. Invariants:
 *
 * - A checkpoint proves its own integrity: it is written in the HDF5 1.10 format, whose
 *   superblock, object headers (so every attribute) and chunk indexes carry checksums, every
 *   dataset has the Fletcher32 filter, and "text_hash" attributes (on the root and on each
 *   phase group) hash the strings, which HDF5 keeps in its unchecksummed global heap. A
 *   reader refuses a file whose bytes changed, and then validates what it holds: finite
 *   values, the stored time, step and time step, ids non-negative and unique over all ranks,
 *   each field within the range its module declares (mpm_particles_set_range). Files of
 *   format 1 (no checksums) are still read, with the same validation.
 * - A damaged checkpoint is bad input (MPM_ERR_INPUT): one line names the file and what is
 *   wrong; HDF5's own error stack stays silent from open to close.
 *
 * - The file at PATH is always a complete checkpoint or absent: ranks write PATH.tmp, close
 *   it, agree that every rank succeeded, and only then rank 0 flushes it to disk and renames
 *   it over PATH. A failed write removes PATH.tmp and leaves an earlier PATH untouched.
 * - Particle data is stored exactly as it lies in memory, component-major [ncomp][N] with
 *   the ranks' blocks one after another in rank order, and counts[r] records rank r's
 *   share. Reading back on the same number of ranks returns each rank its own block in its
 *   own order, bit for bit, so a restart continues the same trajectory.
 * - Every rank takes part in every collective call; local failures (checks, allocations,
 *   what one rank read) are agreed on with an MPI_Allreduce first, here and inside the HDF5
 *   helpers of mpm_h5.h, so all ranks return the same code and none is left waiting. */
#define _POSIX_C_SOURCE 200809L /* fsync, O_DIRECTORY */
#include "mpm_error.h"
#include "mpm_h5.h"
#include "mpm_iowatch.h"
#include "mpm_path.h"
#include "mpm_output.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define CHECKPOINT_FORMAT   "mpmfsi checkpoint 2"
#define CHECKPOINT_FORMAT_1 "mpmfsi checkpoint 1" /* before checksums: still read */

struct mpm_checkpoint {
  MPI_Comm comm;
  int rank, size;
  hid_t file;
  char *path, *config;
  int nranks;         /* ranks that wrote the checkpoint */
  int hashed;         /* the strings carry text_hash attributes (format 2) */
  mpm_h5_quiet quiet; /* HDF5's error printing, silenced from open to close */
};

static int h5_failed(void);

/* ---- reading attributes ---------------------------------------------------------------- */

/* Read the n values of attribute name into value (memory type type); -1 if it is missing
 * or does not hold n values, -2 if HDF5 cannot read it (a damaged file). */
static int attr_read(hid_t loc, const char *name, hid_t type, int n, void *value) {
  const htri_t exists = H5Aexists(loc, name);
  if (exists <= 0) return exists < 0 ? h5_failed() : -1;
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return h5_failed();
  const hid_t space = H5Aget_space(a);
  const hssize_t npoints = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  int st = npoints < 0 ? h5_failed() : npoints == n ? 0 : -1;
  if (!st && H5Aread(a, type, value) < 0) st = h5_failed();
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  return st;
}

/* ---- string hashes --------------------------------------------------------------------- */

/* The hash of the strings a (and b, if not NULL), each with its terminating zero. */
static unsigned long long text_hash(const char *a, const char *b) {
  unsigned long long h = mpm_h5_hash(MPM_H5_HASH0, a, strlen(a) + 1);
  return b ? mpm_h5_hash(h, b, strlen(b) + 1) : h;
}

/* ---- writing --------------------------------------------------------------------------- */

/* Field names joined by commas, in the order of p's fields. */
static char *field_names(const mpm_particles *p) {
  size_t len = 1;
  for (int f = 0; f < p->nfields; ++f) len += strlen(p->field[f].name) + 1;
  char *s = calloc(len, 1);
  for (int f = 0; s && f < p->nfields; ++f) {
    if (f) strcat(s, ",");
    strcat(s, p->field[f].name);
  }
  return s;
}

static int write_phase_attrs(const mpm_h5 *h, hid_t g, const mpm_particles *p) {
  int ncomp[MPM_PARTICLES_MAX_FIELDS];
  for (int f = 0; f < p->nfields; ++f) ncomp[f] = p->field[f].ncomp;
  char *names = field_names(p);
  if (!names) mpm_log_all(MPM_LOG_ERROR, "checkpoint: cannot list the field names");
  int rc = mpm_h5_agree(h->comm, names ? 0 : MPM_ERR_MEMORY);
  if (!rc) rc = mpm_h5_attr_fixed_string(h, g, "field_names", names);
  const unsigned long long hash = names ? text_hash(names, NULL) : 0;
  if (!rc) rc = mpm_h5_attr(h, g, "text_hash", H5T_NATIVE_ULLONG, 1, &hash);
  free(names);
  MPM_CALL(rc);
  MPM_CALL(mpm_h5_attr(h, g, "field_ncomp", H5T_NATIVE_INT, p->nfields, ncomp));
  MPM_CALL(mpm_h5_attr(h, g, "dim", H5T_NATIVE_INT, 1, &p->dim));
  MPM_CALL(mpm_h5_attr(h, g, "id_next", H5T_NATIVE_INT64, 1, &p->id_next));
  return 0;
}

/* counts: every rank's particle count (the same array on every rank). */
static int write_phase_data(const mpm_h5 *h, hid_t g, int size, const mpm_particles *p,
                            const int64_t *counts) {
  int64_t total = 0, offset = 0;
  for (int r = 0; r < size; ++r) total += counts[r], offset += r < h->rank ? counts[r] : 0;
  MPM_CALL(write_phase_attrs(h, g, p));
  hsize_t fdims[2] = {(hsize_t)total}, start[2] = {(hsize_t)offset}, count[2] = {(hsize_t)p->n};
  MPM_CALL(mpm_h5_write_block(h, g, "id", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start, count,
                              p->id));
  fdims[0] = count[0] = (hsize_t)p->ncomp, start[0] = 0;
  fdims[1] = (hsize_t)total, start[1] = (hsize_t)offset, count[1] = (hsize_t)p->n;
  MPM_CALL(mpm_h5_write_block(h, g, "data", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, fdims, start,
                              count, p->data));
  /* Rank 0 writes the whole counts array; the others select nothing. */
  fdims[0] = (hsize_t)size, start[0] = 0, count[0] = h->rank == 0 ? (hsize_t)size : 0;
  MPM_CALL(mpm_h5_write_block(h, g, "counts", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start,
                              count, counts));
  return 0;
}

typedef struct ck_contents {
  int size; /* ranks writing */
  const char *config;
  const char *const *attr_names;
  const double *attr_values;
  int nattr;
  const mpm_particles *const *phases;
  const char *const *names;
  int nphases;
  const int64_t *counts; /* [nphases][size] */
} ck_contents;

/* Fills the checkpoint file (an mpm_h5_fill; arg is the ck_contents). */
static int write_contents(const mpm_h5 *h, hid_t file, const void *arg) {
  const ck_contents *c = arg;
  MPM_CALL(mpm_h5_attr_fixed_string(h, file, "format", CHECKPOINT_FORMAT));
  MPM_CALL(mpm_h5_attr_fixed_string(h, file, "config", c->config));
  const unsigned long long hash = text_hash(CHECKPOINT_FORMAT, c->config);
  MPM_CALL(mpm_h5_attr(h, file, "text_hash", H5T_NATIVE_ULLONG, 1, &hash));
  MPM_CALL(mpm_h5_attr(h, file, "nranks", H5T_NATIVE_INT, 1, &c->size));
  for (int k = 0; k < c->nattr; ++k)
    MPM_CALL(mpm_h5_attr(h, file, c->attr_names[k], H5T_NATIVE_DOUBLE, 1, &c->attr_values[k]));
  for (int k = 0; k < c->nphases; ++k) {
    hid_t g;
    MPM_CALL(mpm_h5_group(h, file, c->names[k], &g));
    const int rc =
        write_phase_data(h, g, c->size, c->phases[k], c->counts + (size_t)k * (size_t)c->size);
    H5Gclose(g);
    MPM_CALL(rc);
  }
  return 0;
}

/* Push the file's data (and then its directory entry) to disk, so that a crash right after
 * the rename cannot leave PATH naming an incomplete file. Best effort: not every file
 * system supports fsync on a directory. */
static void sync_path(const char *path, int directory) {
  const int fd = open(path, directory ? O_RDONLY | O_DIRECTORY : O_RDONLY);
  if (fd < 0) return;
  fsync(fd);
  close(fd);
}

static void sync_parent(const char *path) {
  char *dir = mpm_path_parent(path);
  if (!dir) return;
  sync_path(dir, 1);
  free(dir);
}

/* Rank 0, once every rank has written and closed PATH.tmp. */
static int commit(const char *tmp, const char *path) {
  sync_path(tmp, 0);
  if (rename(tmp, path) != 0)
    MPM_FAIL(MPM_ERR_FILE, "cannot rename the checkpoint %s to %s: %s", tmp, path, strerror(errno));
  sync_parent(path);
  return 0;
}

static int check_write_args(const char *path, const char *const *attr_names, int nattr,
                            const mpm_particles *const *phases, const char *const *names,
                            int nphases) {
  if (!path || !path[0]) MPM_FAIL(MPM_ERR_INPUT, "checkpoint: no path was given");
  for (int k = 0; k < nattr; ++k)
    if (!attr_names[k] || !attr_names[k][0] || strcmp(attr_names[k], "format") == 0 ||
        strcmp(attr_names[k], "config") == 0 || strcmp(attr_names[k], "nranks") == 0 ||
        strcmp(attr_names[k], "text_hash") == 0)
      MPM_FAIL(MPM_ERR_INTERNAL, "checkpoint: '%s' cannot name a checkpoint attribute",
               attr_names[k] ? attr_names[k] : "(null)");
  for (int k = 0; k < nphases; ++k)
    if (!phases[k] || !names[k] || !names[k][0] || strchr(names[k], '/'))
      MPM_FAIL(MPM_ERR_INTERNAL, "checkpoint: phase %d has no set or no valid name", k);
  return 0;
}

/* counts[k][r]: particles of phase k on rank r, the same on every rank. */
static int gather_counts(MPI_Comm comm, int size, const mpm_particles *const *phases, int nphases,
                         int64_t *counts) {
  int64_t *n = malloc((size_t)(nphases + 1) * (1 + (size_t)size) * sizeof *n);
  const int ok = mpm_h5_agree(comm, n ? 0 : MPM_ERR_MEMORY);
  if (ok) free(n);
  MPM_CALL(ok);
  int64_t *all = n + nphases; /* [r][k] as gathered */
  for (int k = 0; k < nphases; ++k) n[k] = phases[k]->n;
  const int rc = MPI_Allgather(n, nphases, MPI_INT64_T, all, nphases, MPI_INT64_T, comm);
  for (int r = 0; r < size; ++r)
    for (int k = 0; k < nphases; ++k)
      counts[(size_t)k * (size_t)size + (size_t)r] = all[(size_t)r * (size_t)nphases + (size_t)k];
  free(n);
  MPM_CALL_MPI(rc);
  return 0;
}

int mpm_checkpoint_write(MPI_Comm comm, const char *path, const char *config_text,
                         const char *const *attr_names, const double *attr_values, int nattr,
                         const mpm_particles *const *phases, const char *const *names,
                         int nphases) {
  int rank, size;
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  MPM_CALL_MPI(MPI_Comm_size(comm, &size));
  /* Each rank checks its own arguments: agreed on before any collective. */
  int rc = check_write_args(path, attr_names, nattr, phases, names, nphases);
  const size_t len = rc ? 0 : strlen(path) + 5;
  char *tmp = rc ? NULL : malloc(len);
  int64_t *counts = rc ? NULL : malloc(((size_t)nphases * (size_t)size + 1) * sizeof *counts);
  rc = mpm_h5_agree(comm, rc ? rc : tmp && counts ? 0 : MPM_ERR_MEMORY);
  if (!rc) rc = gather_counts(comm, size, phases, nphases, counts);
  if (!rc) {
    snprintf(tmp, len, "%s.tmp", path);
    const ck_contents c = {size,       config_text ? config_text : "",
                           attr_names, attr_values,
                           nattr,      phases,
                           names,      nphases,
                           counts};
    const mpm_h5 h = {comm, rank, "checkpoint"};
    rc = mpm_h5_write_file_checksummed(&h, tmp, write_contents, &c);
    /* mpm_h5_write_file returns once every rank has closed the file: its agreement is the
     * barrier. */
    if (rank == 0 && rc) remove(tmp);
    if (rank == 0 && !rc) rc = commit(tmp, path);
    if (MPI_Bcast(&rc, 1, MPI_INT, 0, comm) != MPI_SUCCESS) rc = MPM_ERR_MPI;
    /* Rank 0's failure (the rename), now known to every rank. */
    if (rc && rc != MPM_ERR_MPI) rc = MPM_ERR_OUTPUT;
    if (!rc) mpm_iowatch_set_checkpoint(path);
  }
  free(tmp), free(counts);
  MPM_CALL(rc);
  return 0;
}

/* ---- reading: verdicts ----------------------------------------------------------------- */

/* Set by the last failed HDF5 read: did HDF5 blame a checksum? (Read right after the
 * failure: the next HDF5 call clears the error stack.) */
static int g_checksum;

static int h5_failed(void) {
  g_checksum = mpm_h5_error_is_checksum();
  return -2;
}

static const char *h5_cause(void) {
  return g_checksum ? "checksum mismatch" : "HDF5 cannot read it";
}

/* Note the first thing found wrong, as the whole message, in why (of WHY_SIZE bytes). */
#define WHY_SIZE 640
static void note(char *why, const mpm_checkpoint *ck, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void note(char *why, const mpm_checkpoint *ck, const char *fmt, ...) {
  if (why[0]) return;
  char detail[480];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(detail, sizeof detail, fmt, ap);
  va_end(ap);
  snprintf(why, WHY_SIZE, "the checkpoint '%s' is damaged: %s. Restart from an earlier checkpoint",
           ck->path, detail);
}

/* Agree on the verdicts of all ranks (why empty: nothing wrong here): MPM_ERR_INPUT on every
 * rank if any found something, explained once, by the lowest such rank. Collective. */
static int agree_why(const mpm_checkpoint *ck, const char *why) {
  int who = why[0] ? ck->rank : ck->size;
  if (MPI_Allreduce(MPI_IN_PLACE, &who, 1, MPI_INT, MPI_MIN, ck->comm) != MPI_SUCCESS)
    return MPM_ERR_MPI;
  if (who == ck->size) return 0;
  if (who == ck->rank) mpm_log_all(MPM_LOG_ERROR, "%s", why);
  return MPM_ERR_INPUT;
}

#define AGREE_WHY(ck, why)                                                                         \
  do {                                                                                             \
    const int agree_rc_ = agree_why((ck), (why));                                                  \
    if (agree_rc_) return mpm_trace(__FILE__, __LINE__, __func__, agree_rc_);                      \
  } while (0)

/* ---- reading: the file and its root attributes ----------------------------------------- */

/* Rank 0 looks at the file first so that a missing or foreign file gets a clear message
 * before any collective HDF5 call. */
static int probe(const char *path) {
  if (access(path, R_OK) != 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "cannot read the checkpoint '%s': %s. Check the restart file named in the case "
             "file or on the command line",
             path, strerror(errno));
  struct stat st; /* a FIFO or a device would block or never end */
  if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
    MPM_FAIL(MPM_ERR_INPUT,
             "'%s' is not a regular file, so not an mpmfsi checkpoint. Restart from a file "
             "written by mpmfsi (checkpoint output)",
             path);
  const htri_t is_h5 = H5Fis_hdf5(path); /* HDF5's error printing is off (mpm_checkpoint_open) */
  if (is_h5 <= 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "'%s' is not an HDF5 file, so not an mpmfsi checkpoint (or its first bytes are "
             "damaged). Restart from a file written by mpmfsi (checkpoint output)",
             path);
  return 0;
}

/* What the writer (coupler/mpm_sim.c) stores at the root, beyond "finite": the time is >= 0
 * (a run starts at 0; from a negative time it took steps of zero length and, without the
 * blow-up guard, never ended), the step count is a whole number >= 0 and the next step size
 * is >= 0 (0: no hint). */
typedef struct root_check {
  const mpm_checkpoint *ck;
  char *why;
} root_check;

static herr_t check_root_value(hid_t loc, const char *name, const H5A_info_t *info, void *arg) {
  (void)info;
  const root_check *rc = arg;
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return h5_failed();
  const hid_t type = H5Aget_type(a), space = H5Aget_space(a);
  const int real = type >= 0 && H5Tget_class(type) == H5T_FLOAT;
  const hssize_t npoints = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  double v = 0;
  const herr_t r = real && npoints == 1 ? H5Aread(a, H5T_NATIVE_DOUBLE, &v) : 0;
  if (r < 0 || type < 0 || space < 0) h5_failed();
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  if (r < 0 || type < 0 || space < 0) return -1;
  if (!real || npoints != 1) return 0;
  if (!isfinite(v))
    note(rc->why, rc->ck, "its value '%s' is %g, not a finite number", name, v);
  else if (strcmp(name, "t") == 0 && v < 0)
    note(rc->why, rc->ck, "its time t is %.17g, below zero (a run starts at t = 0)", v);
  else if (strcmp(name, "step") == 0 && (v < 0 || v != floor(v) || v > 0x1p53))
    note(rc->why, rc->ck, "its step count is %.17g, not a whole number >= 0", v);
  else if (strcmp(name, "h_next") == 0 && v < 0)
    note(rc->why, rc->ck, "its next step size h_next is %.17g, below zero", v);
  return 0;
}

/* A string attribute as a malloc'ed copy in *out: 0, -1 if it is missing or not a string,
 * -2 if HDF5 cannot read it. Fixed-length (what mpmfsi writes) or variable-length (checkpoints
 * written before fixed-length strings). */
static int attr_read_string(hid_t loc, const char *name, char **out) {
  *out = NULL;
  const htri_t exists = H5Aexists(loc, name);
  if (exists <= 0) return exists < 0 ? h5_failed() : -1;
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return h5_failed();
  const hid_t ftype = H5Aget_type(a);
  int st = ftype < 0 ? h5_failed() : -1;
  const int is_string = ftype >= 0 && H5Tget_class(ftype) == H5T_STRING;
  const htri_t variable = is_string ? H5Tis_variable_str(ftype) : 0;
  if (is_string && variable > 0) {
    const hid_t type = mpm_h5_string_type();
    char *s = NULL;
    if (type >= 0 && H5Aread(a, type, &s) >= 0 && s) {
      *out = malloc(strlen(s) + 1);
      if (*out) memcpy(*out, s, strlen(s) + 1), st = 0;
      H5free_memory(s);
    } else if (type >= 0) {
      st = h5_failed();
    }
    if (type >= 0) H5Tclose(type);
  } else if (is_string && variable == 0) {
    const size_t size = H5Tget_size(ftype);
    const hid_t type = H5Tcopy(ftype); /* its own size, padding and character set */
    char *s = size > 0 ? calloc(size + 1, 1) : NULL;
    if (s && type >= 0 && H5Aread(a, type, s) >= 0)
      *out = s, st = 0;
    else
      free(s), st = h5_failed();
    if (type >= 0) H5Tclose(type);
  }
  if (ftype >= 0) H5Tclose(ftype);
  H5Aclose(a);
  return st;
}

/* The root attributes: format mark, case text, rank count, the strings' hash, and every
 * stored real value. why gets the first problem. */
static void check_root(mpm_checkpoint *ck, char *why) {
  char *format = NULL;
  int st = attr_read_string(ck->file, "format", &format);
  const int v2 = format && strcmp(format, CHECKPOINT_FORMAT) == 0;
  if (st == -2) note(why, ck, "cannot read its format mark (%s)", h5_cause());
  if (!why[0] && !v2 && !(format && strcmp(format, CHECKPOINT_FORMAT_1) == 0))
    snprintf(why, WHY_SIZE,
             "'%s' is an HDF5 file but not an mpmfsi checkpoint (no '%s' format mark). Restart "
             "from a file written by mpmfsi",
             ck->path, CHECKPOINT_FORMAT);
  st = why[0] ? 0 : attr_read_string(ck->file, "config", &ck->config);
  if (st) note(why, ck, "cannot read its case text (%s)", st == -2 ? h5_cause() : "missing");
  st = why[0] ? 0 : attr_read(ck->file, "nranks", H5T_NATIVE_INT, 1, &ck->nranks);
  if (st) note(why, ck, "cannot read its rank count (%s)", st == -2 ? h5_cause() : "missing");
  if (!why[0] && ck->nranks < 1) note(why, ck, "its rank count is %d", ck->nranks);
  unsigned long long hash = 0;
  st = why[0] ? 0 : attr_read(ck->file, "text_hash", H5T_NATIVE_ULLONG, 1, &hash);
  ck->hashed = st == 0;
  if (st == -2 || (st == -1 && v2))
    note(why, ck, "cannot read the hash of its strings (%s)", st == -2 ? h5_cause() : "missing");
  if (!why[0] && ck->hashed && hash != text_hash(format, ck->config))
    note(why, ck, "checksum mismatch in its format mark or case text (text_hash)");
  free(format);
  const root_check rc = {ck, why};
  if (!why[0] &&
      H5Aiterate2(ck->file, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, check_root_value, (void *)&rc) < 0)
    note(why, ck, "cannot read its root attributes (%s)", h5_cause());
}

static int open_file(mpm_checkpoint *ck) {
  int rc = ck->rank == 0 ? probe(ck->path) : 0;
  MPM_CALL_MPI(MPI_Bcast(&rc, 1, MPI_INT, 0, ck->comm));
  MPM_CALL(rc);
  ck->file = mpm_h5_open(ck->comm, ck->path);
  if (ck->file < 0)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' is damaged: HDF5 cannot open it (its superblock or "
                     "root group is unreadable). Restart from an earlier checkpoint",
                     ck->path);
  char why[WHY_SIZE] = "";
  check_root(ck, why);
  AGREE_WHY(ck, why);
  return 0;
}

int mpm_checkpoint_open(mpm_checkpoint **ck, MPI_Comm comm, const char *path) {
  mpm_checkpoint *c;
  *ck = NULL;
  if (!path || !path[0]) MPM_FAIL(MPM_ERR_INPUT, "checkpoint: no path was given");
  MPM_ALLOC(c, 1);
  c->comm = MPI_COMM_NULL, c->file = -1;
  mpm_h5_quiet_begin(&c->quiet);
  int rc = MPI_Comm_dup(comm, &c->comm) == MPI_SUCCESS ? 0 : MPM_ERR_MPI;
  if (!rc) MPI_Comm_rank(c->comm, &c->rank), MPI_Comm_size(c->comm, &c->size);
  if (!rc) c->path = malloc(strlen(path) + 1);
  if (!rc) rc = mpm_h5_agree(c->comm, c->path ? 0 : MPM_ERR_MEMORY);
  if (!rc) strcpy(c->path, path), rc = open_file(c);
  if (!rc) mpm_iowatch_set_checkpoint(path); /* a restart's source: complete and valid */
  if (rc) {
    mpm_checkpoint_close(&c);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *ck = c;
  return 0;
}

void mpm_checkpoint_close(mpm_checkpoint **ck) {
  if (!ck || !*ck) return;
  mpm_checkpoint *c = *ck;
  if (c->file >= 0) H5Fclose(c->file);
  mpm_h5_quiet_end(&c->quiet);
  if (c->comm != MPI_COMM_NULL) MPI_Comm_free(&c->comm);
  free(c->path), free(c->config);
  free(c);
  *ck = NULL;
}

const char *mpm_checkpoint_config(const mpm_checkpoint *ck) {
  return ck->config;
}

int mpm_checkpoint_attr(const mpm_checkpoint *ck, const char *name, double *value) {
  const int st = attr_read(ck->file, name, H5T_NATIVE_DOUBLE, 1, value);
  if (st == -2)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' is damaged: cannot read its value '%s' (%s). Restart "
                     "from an earlier checkpoint",
                     ck->path, name, h5_cause());
  if (st < 0)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' has no value '%s'; it was written by another version of "
                     "mpmfsi or another kind of run",
                     ck->path, name);
  return 0;
}

int mpm_checkpoint_attr_optional(const mpm_checkpoint *ck, const char *name, double *value) {
  return attr_read(ck->file, name, H5T_NATIVE_DOUBLE, 1, value) == 0;
}

/* ---- reading: particles ---------------------------------------------------------------- */

/* Describe p's fields as "x(2) v(2) m(1)" for messages. */
static void describe_fields(const mpm_particles *p, char *s, size_t size) {
  size_t k = 0;
  s[0] = 0;
  for (int f = 0; f < p->nfields && k < size; ++f)
    k += (size_t)snprintf(s + k, size - k, "%s%s(%d)", f ? " " : "", p->field[f].name,
                          p->field[f].ncomp);
}

/* How the stored components map onto p's: src[c] is the stored component that p's component c
 * takes (-1: none, left zero), of nstored in all. The identity when the layouts are equal. */
typedef struct layout_map {
  int nstored;
  int src[MPM_PARTICLES_MAX_COMPONENTS];
} layout_map;

/* Fill map from the stored fields names[0..nf) (ncomp each) by name: 1 if every field of p is
 * stored with its size, or is one whose stored value no step reads (scratch: written before it
 * is read; derived: recomputed before use), else 0. Stored fields p lacks are dropped: the
 * stored case is this run's but for time.*, so the layouts differ only where time.method
 * arranges its fields (the gas's lagged strain rate is state in usl and musl, the ERK pairs add
 * their pending one), and the switch needs nothing more. */
static int map_layout(const mpm_particles *p, char *const *names, const int *ncomp, int nf,
                      layout_map *map) {
  int start[MPM_PARTICLES_MAX_FIELDS];
  map->nstored = 0;
  for (int k = 0; k < nf; ++k) start[k] = map->nstored, map->nstored += ncomp[k];
  for (int f = 0; f < p->nfields; ++f) {
    int k = 0;
    while (k < nf && strcmp(names[k], p->field[f].name) != 0) ++k;
    if (k < nf && ncomp[k] != p->field[f].ncomp) return 0;
    if (k == nf && !((p->scratch | p->derived) >> f & 1u)) return 0;
    for (int c = 0; c < p->field[f].ncomp; ++c)
      map->src[p->offset[f] + c] = k < nf ? start[k] + c : -1;
  }
  return 1;
}

/* The stored layout must supply p's: the same dimension, and every field p needs
 * (map_layout). */
static int check_layout(const mpm_checkpoint *ck, hid_t g, const char *phase,
                        const mpm_particles *p, layout_map *map) {
  int dim = 0, ncomp[MPM_PARTICLES_MAX_FIELDS] = {0}, nstored = 0, nf = 0;
  char *names = NULL, want[512], have[512] = "", why[WHY_SIZE] = "";
  char *field[MPM_PARTICLES_MAX_FIELDS];
  unsigned long long hash = 0;
  int st = attr_read_string(g, "field_names", &names);
  if (names) {
    nstored = 1;
    for (const char *c = names; *c; ++c) nstored += *c == ',';
  }
  if (!st) st = attr_read(g, "dim", H5T_NATIVE_INT, 1, &dim);
  if (!st) st = nstored <= MPM_PARTICLES_MAX_FIELDS ? 0 : -1;
  if (!st) st = attr_read(g, "field_ncomp", H5T_NATIVE_INT, nstored, ncomp);
  if (!st && ck->hashed) st = attr_read(g, "text_hash", H5T_NATIVE_ULLONG, 1, &hash);
  if (st == -2) note(why, ck, "cannot read the layout of phase '%s' (%s)", phase, h5_cause());
  if (!st && ck->hashed && hash != text_hash(names, NULL))
    note(why, ck, "checksum mismatch in the field names of phase '%s' (text_hash)", phase);
  for (int f = 0; !st && !why[0] && f < nstored; ++f) /* a size no field has: damaged */
    if (ncomp[f] < 1 || ncomp[f] > MPM_PARTICLES_MAX_NCOMP) st = -1;
  if (!st && !why[0]) { /* "x,v,m" with ncomp {2,2,1} -> "x(2) v(2) m(1)" */
    size_t k = 0;
    char *save = NULL;
    for (char *tok = strtok_r(names, ",", &save); tok && nf < nstored;
         tok = strtok_r(NULL, ",", &save), ++nf) {
      field[nf] = tok;
      if (k < sizeof have)
        k += (size_t)snprintf(have + k, sizeof have - k, "%s%s(%d)", nf ? " " : "", tok, ncomp[nf]);
    }
  }
  describe_fields(p, want, sizeof want);
  const int fits = !st && !why[0] && nf == nstored && map_layout(p, field, ncomp, nf, map);
  free(names);
  if (st == -1)
    snprintf(why, sizeof why,
             "the checkpoint '%s' does not describe the fields of phase '%s'; it was not "
             "written by this version of mpmfsi",
             ck->path, phase);
  /* What one rank read decides for all: the ranks go on to collective reads together. */
  AGREE_WHY(ck, why);
  if (dim != p->dim || !fits)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' holds phase '%s' as %d-D particles with fields %s, but "
                     "this run needs %d-D particles with fields %s. Restart with the case (model "
                     "and dimension) that wrote the checkpoint, or start a new run",
                     ck->path, phase, dim, have, p->dim, want);
  return 0;
}

/* Does dset have exactly these extents? A dataset of another size would be read without
 * complaint by a smaller selection, so the stored extents are checked first. */
static int has_extents(hid_t dset, int rank, const hsize_t *dims) {
  hsize_t have[2] = {0, 0};
  const hid_t space = dset >= 0 ? H5Dget_space(dset) : -1;
  const int ok = space >= 0 && H5Sget_simple_extent_ndims(space) == rank &&
                 H5Sget_simple_extent_dims(space, have, NULL) == rank;
  if (space >= 0) H5Sclose(space);
  for (int d = 0; d < rank; ++d)
    if (!ok || have[d] != dims[d]) return 0;
  return 1;
}

/* Open dataset name of g with the given extents, or note in why what is wrong. */
static hid_t open_dataset(const mpm_checkpoint *ck, hid_t g, const char *phase, const char *name,
                          int rank, const hsize_t *dims, char *why) {
  const hid_t d = H5Dopen2(g, name, H5P_DEFAULT);
  if (d < 0) h5_failed();
  if (d < 0)
    note(why, ck, "cannot open the dataset '/%s/%s' (%s)", phase, name, h5_cause());
  else if (!has_extents(d, rank, dims))
    note(why, ck, "the dataset '/%s/%s' does not have the extents its particle counts imply", phase,
         name);
  return d;
}

/* Collective read of this rank's block of an open dataset (d < 0: this rank could not open
 * it, and why says so). */
static int read_dataset(const mpm_checkpoint *ck, hid_t d, const char *phase, const char *name,
                        hid_t mtype, int rank, const hsize_t *start, const hsize_t *count,
                        void *buf, char *why) {
  AGREE_WHY(ck, why);
  int checksum = 0;
  if (mpm_h5_read_block(ck->comm, d, mtype, rank, start, count, buf, &checksum) != 0) {
    note(why, ck, "cannot read the dataset '/%s/%s' (%s)", phase, name,
         checksum ? "checksum mismatch in its data" : "HDF5 cannot read it");
    if (ck->rank == 0) mpm_log_all(MPM_LOG_ERROR, "%s", why);
    return mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT);
  }
  return 0;
}

/* Every rank reads the whole counts array (collectively): nranks counts, none negative. */
static int read_counts(const mpm_checkpoint *ck, hid_t g, const char *phase, int64_t *counts) {
  char why[WHY_SIZE] = "";
  const hsize_t start = 0, count = (hsize_t)ck->nranks;
  const hid_t dset = open_dataset(ck, g, phase, "counts", 1, &count, why);
  const int rc =
      read_dataset(ck, dset, phase, "counts", H5T_NATIVE_INT64, 1, &start, &count, counts, why);
  if (dset >= 0) H5Dclose(dset);
  MPM_CALL(rc);
  int64_t total = 0;
  for (int r = 0; r < ck->nranks; ++r) { /* the same data on every rank */
    if (counts[r] < 0 || counts[r] > ((int64_t)1 << 48) - total)
      note(why, ck, "rank %d's particle count of phase '%s' is %lld", r, phase,
           (long long)counts[r]);
    total += why[0] ? 0 : counts[r];
  }
  AGREE_WHY(ck, why);
  return 0;
}

/* This rank's slice [*offset, *offset + *n) of the *ntotal stored particles. */
static int choose_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, int64_t *offset,
                        int64_t *n, int64_t *ntotal) {
  int64_t *counts = malloc((size_t)ck->nranks * sizeof *counts);
  const int ok = mpm_h5_agree(ck->comm, counts ? 0 : MPM_ERR_MEMORY);
  if (ok) free(counts);
  MPM_CALL(ok);
  const int rc = read_counts(ck, g, phase, counts);
  if (rc) free(counts);
  MPM_CALL(rc);
  int64_t total = 0, before = 0;
  for (int r = 0; r < ck->nranks; ++r) total += counts[r], before += r < ck->rank ? counts[r] : 0;
  if (ck->nranks == ck->size) { /* each rank takes back exactly what it wrote */
    *offset = before, *n = counts[ck->rank];
  } else { /* even chunks in rank order; the caller migrates */
    const int64_t q = total / ck->size, rem = total % ck->size;
    *offset = ck->rank * q + MPM_MIN(ck->rank, rem);
    *n = q + (ck->rank < rem);
  }
  free(counts);
  *ntotal = total;
  if (total / ck->size >= INT32_MAX) /* the same verdict on every rank */
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' holds %lld particles of phase '%s', too many for %d "
                     "rank(s); restart on more ranks",
                     ck->path, (long long)total, phase, ck->size);
  return 0;
}

/* Collective read of [offset, offset + n) of id [total] and data [ncomp][total]; the same
 * code on every rank. */
static int read_datasets(const mpm_checkpoint *ck, hid_t g, const char *phase, int ncomp,
                         int64_t total, int64_t offset, int64_t n, mpm_gidx *id, double *data) {
  char why[WHY_SIZE] = "";
  hsize_t dims[2] = {(hsize_t)ncomp, (hsize_t)total};
  const hid_t did = open_dataset(ck, g, phase, "id", 1, &dims[1], why);
  const hid_t dd = open_dataset(ck, g, phase, "data", 2, dims, why);
  hsize_t start[2] = {(hsize_t)offset}, count[2] = {(hsize_t)n};
  int rc = read_dataset(ck, did, phase, "id", H5T_NATIVE_INT64, 1, start, count, id, why);
  start[0] = 0, count[0] = (hsize_t)ncomp, start[1] = (hsize_t)offset, count[1] = (hsize_t)n;
  if (!rc) rc = read_dataset(ck, dd, phase, "data", H5T_NATIVE_DOUBLE, 2, start, count, data, why);
  if (did >= 0) H5Dclose(did);
  if (dd >= 0) H5Dclose(dd);
  return rc;
}

/* What was read must be a state the run could have written: valid values (mpm_particles_
 * find_invalid, with the ranges the module declared) and ids unique over all ranks. */
static int validate(const mpm_checkpoint *ck, const char *phase, const mpm_particles *p, int64_t n,
                    const mpm_gidx *id, const double *data) {
  char why[WHY_SIZE] = "", detail[400];
  if (mpm_particles_find_invalid(p, (mpm_lidx)n, id, data, detail, sizeof detail) >= 0)
    note(why, ck, "in phase '%s', %s", phase, detail);
  AGREE_WHY(ck, why);
  mpm_gidx dup = -1;
  MPM_CALL(mpm_particles_find_duplicate(ck->comm, id, (mpm_lidx)n, &dup));
  if (dup >= 0)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' is damaged: in phase '%s', particle id %lld is held "
                     "twice. Restart from an earlier checkpoint",
                     ck->path, phase, (long long)dup);
  return 0;
}

/* The stored block (map->nstored components, stride n) in p's layout: a fresh block. */
static double *remap(const layout_map *map, const mpm_particles *p, double *stored, size_t n) {
  double *data = calloc((size_t)p->ncomp * n + 1, sizeof *data);
  for (int c = 0; data && c < p->ncomp; ++c)
    if (map->src[c] >= 0)
      memcpy(data + (size_t)c * n, stored + (size_t)map->src[c] * n, n * sizeof *data);
  free(stored);
  return data;
}

static int identity(const layout_map *map, const mpm_particles *p) {
  int same = map->nstored == p->ncomp;
  for (int c = 0; same && c < p->ncomp; ++c) same = map->src[c] == c;
  return same;
}

/* Read this rank's slice, check it, and make it p's whole contents. */
static int read_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p,
                      const layout_map *map, int64_t total, int64_t offset, int64_t n) {
  mpm_gidx *id = malloc(((size_t)n + 1) * sizeof *id);
  double *data = malloc(((size_t)map->nstored * (size_t)n + 1) * sizeof *data);
  unsigned char *keep = calloc((size_t)p->n + 1, 1); /* all zero: drop what p held */
  int rc = mpm_h5_agree(ck->comm, id && data && keep ? 0 : MPM_ERR_MEMORY);
  if (!rc) rc = read_datasets(ck, g, phase, map->nstored, total, offset, n, id, data);
  if (!rc && !identity(map, p)) {
    data = remap(map, p, data, (size_t)n);
    rc = mpm_h5_agree(ck->comm, data ? 0 : MPM_ERR_MEMORY);
  }
  if (!rc) rc = validate(ck, phase, p, n, id, data);
  /* Through mpm_particles_edit, which owns the block's allocation and its invariants. */
  if (!rc) rc = mpm_particles_edit(p, keep, (mpm_lidx)n, id, data);
  free(id), free(data), free(keep);
  /* The edit is local: agreed on, so that no rank skips the next phase's collective reads. */
  MPM_CALL(mpm_h5_agree(ck->comm, rc));
  return 0;
}

static int read_phase(mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p) {
  int64_t offset = 0, n = 0, total = 0, id_next = 0;
  char why[WHY_SIZE] = "";
  layout_map map;
  MPM_CALL(check_layout(ck, g, phase, p, &map));
  const int st = attr_read(g, "id_next", H5T_NATIVE_INT64, 1, &id_next);
  if (st || id_next < 0)
    note(why, ck, "cannot read a valid id_next for phase '%s' (%s)", phase,
         st == -2 ? h5_cause()
         : st     ? "missing"
                  : "negative");
  AGREE_WHY(ck, why);
  MPM_CALL(choose_slice(ck, g, phase, &offset, &n, &total));
  p->id_next = id_next;
  MPM_CALL(read_slice(ck, g, phase, p, &map, total, offset, n));
  return 0;
}

int mpm_checkpoint_read_particles(mpm_checkpoint *ck, const char *phase, mpm_particles *p) {
  /* Lookups are local: each is agreed on, so that all ranks reach the collective reads. */
  char why[WHY_SIZE] = "";
  const htri_t exists = H5Lexists(ck->file, phase, H5P_DEFAULT);
  if (exists < 0) h5_failed(), note(why, ck, "cannot look up phase '%s' (%s)", phase, h5_cause());
  if (exists == 0)
    snprintf(why, sizeof why,
             "the checkpoint '%s' has no particles of phase '%s'; restart with the case that "
             "wrote it",
             ck->path, phase);
  AGREE_WHY(ck, why);
  const hid_t g = H5Gopen2(ck->file, phase, H5P_DEFAULT);
  if (g < 0) h5_failed(), note(why, ck, "cannot open phase '%s' (%s)", phase, h5_cause());
  AGREE_WHY(ck, why);
  const int rc = read_phase(ck, g, phase, p);
  H5Gclose(g);
  MPM_CALL(rc);
  return 0;
}
