/* Checkpoints: the complete particle state in one parallel HDF5 file, for restarts.
 * mpm_output.h gives the layout; this file adds, as attributes, "format" on the root (what
 * marks an mpmfsi checkpoint) and on each phase group "dim", "field_names" (comma-separated)
 * and "field_ncomp", so that a restart can tell whether the stored particles fit the set
 * the run created. Invariants:
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
#include "mpm_output.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define CHECKPOINT_FORMAT "mpmfsi checkpoint 1"

struct mpm_checkpoint {
  MPI_Comm comm;
  int rank, size;
  hid_t file;
  char *path, *config;
  int nranks; /* ranks that wrote the checkpoint */
};

/* ---- reading attributes ---------------------------------------------------------------- */

/* Read the n values of attribute name into value (memory type type); -1 if it is missing
 * or does not hold n values. */
static int attr_read(hid_t loc, const char *name, hid_t type, int n, void *value) {
  if (H5Aexists(loc, name) <= 0) return -1;
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  const hid_t space = a >= 0 ? H5Aget_space(a) : -1;
  const hssize_t npoints = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  const herr_t r = npoints == n ? H5Aread(a, type, value) : -1;
  if (space >= 0) H5Sclose(space);
  if (a >= 0) H5Aclose(a);
  return r < 0 ? -1 : 0;
}

/* A string attribute as a malloc'ed copy, or NULL if it is missing or not a string. */
static char *attr_read_string(hid_t loc, const char *name) {
  if (H5Aexists(loc, name) <= 0) return NULL;
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  const hid_t ftype = a >= 0 ? H5Aget_type(a) : -1;
  char *copy = NULL;
  if (ftype >= 0 && H5Tget_class(ftype) == H5T_STRING && H5Tis_variable_str(ftype) > 0) {
    const hid_t type = mpm_h5_string_type();
    char *s = NULL;
    if (type >= 0 && H5Aread(a, type, &s) >= 0 && s) {
      copy = malloc(strlen(s) + 1);
      if (copy) memcpy(copy, s, strlen(s) + 1);
      H5free_memory(s);
    }
    if (type >= 0) H5Tclose(type);
  }
  if (ftype >= 0) H5Tclose(ftype);
  if (a >= 0) H5Aclose(a);
  return copy;
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
  if (!rc) rc = mpm_h5_attr_string(h, g, "field_names", names);
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
  MPM_CALL(mpm_h5_attr_string(h, file, "format", CHECKPOINT_FORMAT));
  MPM_CALL(mpm_h5_attr_string(h, file, "config", c->config));
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
  char *dir = malloc(strlen(path) + 2);
  if (!dir) return;
  strcpy(dir, path);
  char *slash = strrchr(dir, '/');
  if (!slash)
    strcpy(dir, ".");
  else if (slash == dir)
    dir[1] = 0;
  else
    *slash = 0;
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
        strcmp(attr_names[k], "config") == 0 || strcmp(attr_names[k], "nranks") == 0)
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
    rc = mpm_h5_write_file(&h, tmp, write_contents, &c);
    /* mpm_h5_write_file returns once every rank has closed the file: its agreement is the
     * barrier. */
    if (rank == 0 && rc) remove(tmp);
    if (rank == 0 && !rc) rc = commit(tmp, path);
    if (MPI_Bcast(&rc, 1, MPI_INT, 0, comm) != MPI_SUCCESS) rc = MPM_ERR_MPI;
  }
  free(tmp), free(counts);
  MPM_CALL(rc);
  return 0;
}

/* ---- reading --------------------------------------------------------------------------- */

/* Rank 0 looks at the file first so that a missing or foreign file gets a clear message
 * before any collective HDF5 call. */
static int probe(const char *path) {
  if (access(path, R_OK) != 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "cannot read the checkpoint '%s': %s. Check the restart file named in the case "
             "file or on the command line",
             path, strerror(errno));
  H5E_auto2_t func;
  void *data;
  H5Eget_auto2(H5E_DEFAULT, &func, &data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  const htri_t is_h5 = H5Fis_hdf5(path);
  H5Eset_auto2(H5E_DEFAULT, func, data);
  if (is_h5 <= 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "'%s' is not an HDF5 file, so not an mpmfsi checkpoint. Restart from a file "
             "written by mpmfsi (checkpoint output)",
             path);
  return 0;
}

static int open_file(mpm_checkpoint *ck) {
  int rc = ck->rank == 0 ? probe(ck->path) : 0;
  MPM_CALL_MPI(MPI_Bcast(&rc, 1, MPI_INT, 0, ck->comm));
  MPM_CALL(rc);
  ck->file = mpm_h5_open(ck->comm, ck->path);
  if (ck->file < 0)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT, "cannot open the checkpoint '%s' with HDF5",
                     ck->path);
  char *format = attr_read_string(ck->file, "format");
  rc = format && strcmp(format, CHECKPOINT_FORMAT) == 0 ? 0 : MPM_ERR_INPUT;
  free(format);
  ck->config = attr_read_string(ck->file, "config");
  if (!rc && (!ck->config || attr_read(ck->file, "nranks", H5T_NATIVE_INT, 1, &ck->nranks) < 0 ||
              ck->nranks < 1))
    rc = MPM_ERR_INPUT;
  rc = mpm_h5_agree(ck->comm, rc);
  if (rc)
    MPM_FAIL_ON_ROOT(ck->rank, rc,
                     "'%s' is an HDF5 file but not an mpmfsi checkpoint (no '%s' format mark, "
                     "case text or rank count). Restart from a file written by mpmfsi",
                     ck->path, CHECKPOINT_FORMAT);
  return 0;
}

int mpm_checkpoint_open(mpm_checkpoint **ck, MPI_Comm comm, const char *path) {
  mpm_checkpoint *c;
  *ck = NULL;
  if (!path || !path[0]) MPM_FAIL(MPM_ERR_INPUT, "checkpoint: no path was given");
  MPM_ALLOC(c, 1);
  c->comm = MPI_COMM_NULL, c->file = -1;
  int rc = MPI_Comm_dup(comm, &c->comm) == MPI_SUCCESS ? 0 : MPM_ERR_MPI;
  if (!rc) MPI_Comm_rank(c->comm, &c->rank), MPI_Comm_size(c->comm, &c->size);
  if (!rc) c->path = malloc(strlen(path) + 1);
  if (!rc) rc = mpm_h5_agree(c->comm, c->path ? 0 : MPM_ERR_MEMORY);
  if (!rc) strcpy(c->path, path), rc = open_file(c);
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
  if (c->comm != MPI_COMM_NULL) MPI_Comm_free(&c->comm);
  free(c->path), free(c->config);
  free(c);
  *ck = NULL;
}

const char *mpm_checkpoint_config(const mpm_checkpoint *ck) {
  return ck->config;
}

int mpm_checkpoint_attr(const mpm_checkpoint *ck, const char *name, double *value) {
  if (attr_read(ck->file, name, H5T_NATIVE_DOUBLE, 1, value) < 0)
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' has no value '%s'; it was written by another version of "
                     "mpmfsi or another kind of run",
                     ck->path, name);
  return 0;
}

int mpm_checkpoint_attr_optional(const mpm_checkpoint *ck, const char *name, double *value) {
  return attr_read(ck->file, name, H5T_NATIVE_DOUBLE, 1, value) == 0;
}

/* Describe p's fields as "x(2) v(2) m(1)" for messages. */
static void describe_fields(const mpm_particles *p, char *s, size_t size) {
  size_t k = 0;
  s[0] = 0;
  for (int f = 0; f < p->nfields && k < size; ++f)
    k += (size_t)snprintf(s + k, size - k, "%s%s(%d)", f ? " " : "", p->field[f].name,
                          p->field[f].ncomp);
}

/* The stored layout must be p's: same dimension, same fields in the same order. */
static int check_layout(const mpm_checkpoint *ck, hid_t g, const char *phase,
                        const mpm_particles *p) {
  int dim = 0, ncomp[MPM_PARTICLES_MAX_FIELDS] = {0}, nstored = 0;
  char *names = attr_read_string(g, "field_names"), want[512], have[512] = "";
  if (names) {
    nstored = 1;
    for (const char *c = names; *c; ++c) nstored += *c == ',';
  }
  int ok = names && attr_read(g, "dim", H5T_NATIVE_INT, 1, &dim) == 0 &&
           nstored <= MPM_PARTICLES_MAX_FIELDS &&
           attr_read(g, "field_ncomp", H5T_NATIVE_INT, nstored, ncomp) == 0;
  if (ok) { /* "x,v,m" with ncomp {2,2,1} -> "x(2) v(2) m(1)" */
    size_t k = 0;
    int f = 0;
    char *save = NULL;
    for (char *tok = strtok_r(names, ",", &save); tok && k < sizeof have;
         tok = strtok_r(NULL, ",", &save), ++f)
      k += (size_t)snprintf(have + k, sizeof have - k, "%s%s(%d)", f ? " " : "", tok, ncomp[f]);
  }
  free(names);
  describe_fields(p, want, sizeof want);
  /* What one rank read decides for all: the ranks go on to collective reads together. */
  const int rc = mpm_h5_agree(ck->comm, ok ? 0 : MPM_ERR_INPUT);
  if (rc)
    MPM_FAIL_ON_ROOT(ck->rank, rc,
                     "the checkpoint '%s' does not describe the fields of phase '%s'; it was not "
                     "written by this version of mpmfsi",
                     ck->path, phase);
  if (dim != p->dim || strcmp(have, want) != 0)
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

/* Every rank reads the whole counts array (collectively); MPM_ERR_INPUT or MPM_ERR_HDF5 on
 * every rank if it is not nranks long or a count is negative. */
static int read_counts(const mpm_checkpoint *ck, hid_t g, int64_t *counts) {
  const hid_t dset = H5Dopen2(g, "counts", H5P_DEFAULT);
  const hsize_t start = 0, count = (hsize_t)ck->nranks;
  int rc = mpm_h5_agree(ck->comm, has_extents(dset, 1, &count) ? 0 : MPM_ERR_INPUT);
  if (!rc) rc = mpm_h5_read_block(ck->comm, dset, H5T_NATIVE_INT64, 1, &start, &count, counts);
  if (dset >= 0) H5Dclose(dset);
  for (int r = 0; !rc && r < ck->nranks; ++r) /* the same data on every rank */
    if (counts[r] < 0) rc = MPM_ERR_INPUT;
  return rc;
}

/* This rank's slice [*offset, *offset + *n) of the *ntotal stored particles. */
static int choose_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, int64_t *offset,
                        int64_t *n, int64_t *ntotal) {
  int64_t *counts = malloc((size_t)ck->nranks * sizeof *counts);
  const int ok = mpm_h5_agree(ck->comm, counts ? 0 : MPM_ERR_MEMORY);
  if (ok) free(counts);
  MPM_CALL(ok);
  if (read_counts(ck, g, counts) != 0) {
    free(counts);
    MPM_FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                     "the checkpoint '%s' has no valid particle counts for phase '%s'; the file is "
                     "damaged",
                     ck->path, phase);
  }
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
static int read_datasets(MPI_Comm comm, hid_t g, int ncomp, int64_t total, int64_t offset,
                         int64_t n, mpm_gidx *id, double *data) {
  const hid_t did = H5Dopen2(g, "id", H5P_DEFAULT), dd = H5Dopen2(g, "data", H5P_DEFAULT);
  hsize_t dims[2] = {(hsize_t)ncomp, (hsize_t)total};
  hsize_t start[2] = {(hsize_t)offset}, count[2] = {(hsize_t)n};
  int rc = mpm_h5_agree(
      comm, has_extents(did, 1, &dims[1]) && has_extents(dd, 2, dims) ? 0 : MPM_ERR_INPUT);
  if (!rc) rc = mpm_h5_read_block(comm, did, H5T_NATIVE_INT64, 1, start, count, id);
  start[0] = 0, count[0] = (hsize_t)ncomp, start[1] = (hsize_t)offset, count[1] = (hsize_t)n;
  if (!rc) rc = mpm_h5_read_block(comm, dd, H5T_NATIVE_DOUBLE, 2, start, count, data);
  if (did >= 0) H5Dclose(did);
  if (dd >= 0) H5Dclose(dd);
  return rc;
}

/* Read this rank's slice and make it p's whole contents. */
static int read_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p,
                      int64_t total, int64_t offset, int64_t n) {
  mpm_gidx *id = malloc(((size_t)n + 1) * sizeof *id);
  double *data = malloc(((size_t)p->ncomp * (size_t)n + 1) * sizeof *data);
  unsigned char *keep = calloc((size_t)p->n + 1, 1); /* all zero: drop what p held */
  int rc = mpm_h5_agree(ck->comm, id && data && keep ? 0 : MPM_ERR_MEMORY);
  if (!rc && read_datasets(ck->comm, g, p->ncomp, total, offset, n, id, data) != 0) {
    rc = MPM_ERR_INPUT; /* agreed: the same verdict on every rank */
    if (ck->rank == 0)
      mpm_log_all(MPM_LOG_ERROR,
                  "cannot read the particles of phase '%s' from the checkpoint '%s': the "
                  "file is damaged",
                  phase, ck->path);
  }
  /* Through mpm_particles_edit, which owns the block's allocation and its invariants. */
  if (!rc) rc = mpm_particles_edit(p, keep, (mpm_lidx)n, id, data);
  free(id), free(data), free(keep);
  /* The edit is local: agreed on, so that no rank skips the next phase's collective reads. */
  MPM_CALL(mpm_h5_agree(ck->comm, rc));
  return 0;
}

static int read_phase(mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p) {
  int64_t offset = 0, n = 0, total = 0, id_next = 0;
  MPM_CALL(check_layout(ck, g, phase, p));
  const int rc = mpm_h5_agree(
      ck->comm, attr_read(g, "id_next", H5T_NATIVE_INT64, 1, &id_next) < 0 ? MPM_ERR_INPUT : 0);
  if (rc)
    MPM_FAIL_ON_ROOT(ck->rank, rc, "the checkpoint '%s' has no id_next for phase '%s'", ck->path,
                     phase);
  MPM_CALL(choose_slice(ck, g, phase, &offset, &n, &total));
  MPM_CALL(read_slice(ck, g, phase, p, total, offset, n));
  p->id_next = id_next;
  return 0;
}

int mpm_checkpoint_read_particles(mpm_checkpoint *ck, const char *phase, mpm_particles *p) {
  /* Lookups are local: each is agreed on, so that all ranks reach the collective reads. */
  int rc = mpm_h5_agree(ck->comm, H5Lexists(ck->file, phase, H5P_DEFAULT) > 0 ? 0 : MPM_ERR_INPUT);
  if (rc)
    MPM_FAIL_ON_ROOT(ck->rank, rc,
                     "the checkpoint '%s' has no particles of phase '%s'; restart with the case "
                     "that wrote it",
                     ck->path, phase);
  const hid_t g = H5Gopen2(ck->file, phase, H5P_DEFAULT);
  rc = mpm_h5_agree(ck->comm, g < 0 ? MPM_ERR_INPUT : 0);
  if (rc) {
    if (g >= 0) H5Gclose(g);
    MPM_FAIL_ON_ROOT(ck->rank, rc, "cannot open phase '%s' in '%s'", phase, ck->path);
  }
  rc = read_phase(ck, g, phase, p);
  H5Gclose(g);
  MPM_CALL(rc);
  return 0;
}
