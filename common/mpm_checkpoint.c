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
 * - Every rank takes part in every collective call; local failures are agreed on with an
 *   MPI_Allreduce first, so all ranks return the same code. */
#define _POSIX_C_SOURCE 200809L /* fsync, O_DIRECTORY */
#include "mpm_error.h"
#include "mpm_output.h"

#include <hdf5.h>

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

#define FAIL_ON_ROOT(rank, code, ...)                                                              \
  do {                                                                                             \
    if ((rank) == 0) MPM_FAIL(code, __VA_ARGS__);                                                  \
    return mpm_trace(__FILE__, __LINE__, __func__, (code));                                        \
  } while (0)

static int agree(MPI_Comm comm, int rc) {
  int worst = rc;
  if (MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, comm) != MPI_SUCCESS) return MPM_ERR_MPI;
  return worst;
}

/* ---- HDF5 helpers ---------------------------------------------------------------------- */

static int attr_write(hid_t loc, const char *name, hid_t type, int n, const void *value) {
  const hsize_t dims = (hsize_t)n;
  const hid_t space = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dims, NULL);
  const hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t w = a >= 0 ? H5Awrite(a, type, value) : -1;
  if (a >= 0) H5Aclose(a);
  H5Sclose(space);
  if (w < 0) MPM_FAIL(MPM_ERR_HDF5, "cannot write the checkpoint attribute '%s'", name);
  return 0;
}

static hid_t string_type(void) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  return type;
}

/* Variable-length, so that a long case text does not hit the object-header size limit. */
static int attr_string(hid_t loc, const char *name, const char *value) {
  const hid_t type = string_type();
  const int rc = attr_write(loc, name, type, 1, &value);
  H5Tclose(type);
  return rc;
}

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
    const hid_t type = string_type();
    char *s = NULL;
    if (H5Aread(a, type, &s) >= 0 && s) {
      copy = malloc(strlen(s) + 1);
      if (copy) memcpy(copy, s, strlen(s) + 1);
      H5free_memory(s);
    }
    H5Tclose(type);
  }
  if (ftype >= 0) H5Tclose(ftype);
  if (a >= 0) H5Aclose(a);
  return copy;
}

/* Collective block I/O on a dataset: this rank's block [start, start + count) to or from
 * the contiguous buffer buf. A rank with an empty block selects nothing but still takes
 * part. */
static herr_t block_io(hid_t dset, int write, hid_t mtype, int rank, const hsize_t *start,
                       const hsize_t *count, void *buf) {
  static double dummy; /* a valid pointer for an empty transfer */
  hsize_t n = 1, one = 1;
  for (int d = 0; d < rank; ++d) n *= count[d];
  const hid_t fspace = H5Dget_space(dset);
  const hid_t mspace = n ? H5Screate_simple(rank, count, NULL) : H5Screate_simple(1, &one, NULL);
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  herr_t st = fspace < 0 || mspace < 0 || dxpl < 0 ? -1 : 0;
  if (st >= 0) st = H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  if (st >= 0 && n) st = H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL);
  if (st >= 0 && !n) st = H5Sselect_none(fspace) < 0 || H5Sselect_none(mspace) < 0 ? -1 : 0;
  /* An empty dataset has no storage: even an empty collective transfer would fail on it;
   * every rank sees the same extents, so all skip it together. */
  if (st >= 0 && H5Sget_simple_extent_npoints(fspace) == 0) st = 1;
  if (st == 0 && write) st = H5Dwrite(dset, mtype, mspace, fspace, dxpl, n ? buf : &dummy);
  if (st == 0 && !write) st = H5Dread(dset, mtype, mspace, fspace, dxpl, n ? buf : &dummy);
  if (dxpl >= 0) H5Pclose(dxpl);
  if (mspace >= 0) H5Sclose(mspace);
  if (fspace >= 0) H5Sclose(fspace);
  return st < 0 ? -1 : 0;
}

static int write_dataset(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int rank,
                         const hsize_t *fdims, const hsize_t *start, const hsize_t *count,
                         const void *buf) {
  const hid_t space = H5Screate_simple(rank, fdims, NULL);
  const hid_t dset = H5Dcreate2(loc, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t st = dset >= 0 ? block_io(dset, 1, mtype, rank, start, count, (void *)buf) : -1;
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  if (st < 0) MPM_FAIL(MPM_ERR_HDF5, "cannot write the checkpoint dataset '%s'", name);
  return 0;
}

/* Open or create path collectively, with HDF5's error stack silenced: the caller says what
 * went wrong in words a user can act on. */
static hid_t file_access(MPI_Comm comm, const char *path, int create) {
  H5E_auto2_t func;
  void *data;
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0 || H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) < 0) return -1;
  H5Eget_auto2(H5E_DEFAULT, &func, &data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  const hid_t file = create ? H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)
                            : H5Fopen(path, H5F_ACC_RDONLY, fapl);
  H5Eset_auto2(H5E_DEFAULT, func, data);
  H5Pclose(fapl);
  return file;
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

static int write_phase_attrs(hid_t g, const mpm_particles *p) {
  int ncomp[MPM_PARTICLES_MAX_FIELDS];
  for (int f = 0; f < p->nfields; ++f) ncomp[f] = p->field[f].ncomp;
  char *names = field_names(p);
  if (!names) MPM_FAIL(MPM_ERR_MEMORY, "checkpoint: cannot list the field names");
  int rc = attr_string(g, "field_names", names);
  free(names);
  MPM_CALL(rc);
  MPM_CALL(attr_write(g, "field_ncomp", H5T_NATIVE_INT, p->nfields, ncomp));
  MPM_CALL(attr_write(g, "dim", H5T_NATIVE_INT, 1, &p->dim));
  MPM_CALL(attr_write(g, "id_next", H5T_NATIVE_INT64, 1, &p->id_next));
  return 0;
}

/* counts: every rank's particle count (the same array on every rank). */
static int write_phase_data(hid_t g, int rank, int size, const mpm_particles *p,
                            const int64_t *counts) {
  int64_t total = 0, offset = 0;
  for (int r = 0; r < size; ++r) total += counts[r], offset += r < rank ? counts[r] : 0;
  MPM_CALL(write_phase_attrs(g, p));
  hsize_t fdims[2] = {(hsize_t)total}, start[2] = {(hsize_t)offset}, count[2] = {(hsize_t)p->n};
  MPM_CALL(write_dataset(g, "id", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start, count, p->id));
  fdims[0] = count[0] = (hsize_t)p->ncomp, start[0] = 0;
  fdims[1] = (hsize_t)total, start[1] = (hsize_t)offset, count[1] = (hsize_t)p->n;
  MPM_CALL(
      write_dataset(g, "data", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, fdims, start, count, p->data));
  /* Rank 0 writes the whole counts array; the others select nothing. */
  fdims[0] = (hsize_t)size, start[0] = 0, count[0] = rank == 0 ? (hsize_t)size : 0;
  MPM_CALL(
      write_dataset(g, "counts", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start, count, counts));
  return 0;
}

typedef struct ck_contents {
  const char *config;
  const char *const *attr_names;
  const double *attr_values;
  int nattr;
  const mpm_particles *const *phases;
  const char *const *names;
  int nphases;
  const int64_t *counts; /* [nphases][size] */
} ck_contents;

static int write_contents(hid_t file, int rank, int size, const ck_contents *c) {
  MPM_CALL(attr_string(file, "format", CHECKPOINT_FORMAT));
  MPM_CALL(attr_string(file, "config", c->config));
  MPM_CALL(attr_write(file, "nranks", H5T_NATIVE_INT, 1, &size));
  for (int k = 0; k < c->nattr; ++k)
    MPM_CALL(attr_write(file, c->attr_names[k], H5T_NATIVE_DOUBLE, 1, &c->attr_values[k]));
  for (int k = 0; k < c->nphases; ++k) {
    const hid_t g = H5Gcreate2(file, c->names[k], H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) MPM_FAIL(MPM_ERR_HDF5, "cannot create the checkpoint group /%s", c->names[k]);
    const int rc =
        write_phase_data(g, rank, size, c->phases[k], c->counts + (size_t)k * (size_t)size);
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

static int write_file(MPI_Comm comm, int rank, int size, const char *tmp, const ck_contents *c) {
  const hid_t file = file_access(comm, tmp, 1);
  if (file < 0)
    FAIL_ON_ROOT(rank, MPM_ERR_FILE,
                 "cannot create the checkpoint %s: check that its directory exists and is "
                 "writable, and that the disk is not full",
                 tmp);
  const int rc = write_contents(file, rank, size, c);
  if (H5Fclose(file) < 0 && !rc)
    FAIL_ON_ROOT(rank, MPM_ERR_FILE, "cannot finish the checkpoint %s (is the disk full?)", tmp);
  MPM_CALL(rc);
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
  MPM_CALL(agree(comm, n ? 0 : MPM_ERR_MEMORY));
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
  MPM_CALL(check_write_args(path, attr_names, nattr, phases, names, nphases));
  const size_t len = strlen(path) + 5;
  char *tmp = malloc(len);
  int64_t *counts = malloc(((size_t)nphases * (size_t)size + 1) * sizeof *counts);
  int rc = agree(comm, tmp && counts ? 0 : MPM_ERR_MEMORY);
  if (!rc) rc = gather_counts(comm, size, phases, nphases, counts);
  if (!rc) {
    snprintf(tmp, len, "%s.tmp", path);
    const ck_contents c = {config_text ? config_text : "",
                           attr_names,
                           attr_values,
                           nattr,
                           phases,
                           names,
                           nphases,
                           counts};
    rc = agree(comm, write_file(comm, rank, size, tmp, &c));
    /* The MPI_Allreduce in agree() is the barrier: every rank has closed the file. */
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
  ck->file = file_access(ck->comm, ck->path, 0);
  if (ck->file < 0)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT, "cannot open the checkpoint '%s' with HDF5", ck->path);
  char *format = attr_read_string(ck->file, "format");
  rc = format && strcmp(format, CHECKPOINT_FORMAT) == 0 ? 0 : MPM_ERR_INPUT;
  free(format);
  ck->config = attr_read_string(ck->file, "config");
  if (!rc && (!ck->config || attr_read(ck->file, "nranks", H5T_NATIVE_INT, 1, &ck->nranks) < 0 ||
              ck->nranks < 1))
    rc = MPM_ERR_INPUT;
  if (rc)
    FAIL_ON_ROOT(ck->rank, rc,
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
  if (!rc) rc = agree(c->comm, c->path ? 0 : MPM_ERR_MEMORY);
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
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                 "the checkpoint '%s' has no value '%s'; it was written by another version of "
                 "mpmfsi or another kind of run",
                 ck->path, name);
  return 0;
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
  if (!ok)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                 "the checkpoint '%s' does not describe the fields of phase '%s'; it was not "
                 "written by this version of mpmfsi",
                 ck->path, phase);
  if (dim != p->dim || strcmp(have, want) != 0)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                 "the checkpoint '%s' holds phase '%s' as %d-D particles with fields %s, but "
                 "this run needs %d-D particles with fields %s. Restart with the case (model "
                 "and dimension) that wrote the checkpoint, or start a new run",
                 ck->path, phase, dim, have, p->dim, want);
  return 0;
}

/* Every rank reads the whole counts array (collectively); -1 if it is not nranks long. */
static herr_t read_counts(const mpm_checkpoint *ck, hid_t g, int64_t *counts) {
  const hid_t dset = H5Dopen2(g, "counts", H5P_DEFAULT);
  const hid_t space = dset >= 0 ? H5Dget_space(dset) : -1;
  hsize_t start = 0, count = (hsize_t)ck->nranks;
  herr_t st = space >= 0 && H5Sget_simple_extent_npoints(space) == ck->nranks ? 0 : -1;
  if (st >= 0) st = block_io(dset, 0, H5T_NATIVE_INT64, 1, &start, &count, counts);
  if (space >= 0) H5Sclose(space);
  if (dset >= 0) H5Dclose(dset);
  for (int r = 0; st >= 0 && r < ck->nranks; ++r)
    if (counts[r] < 0) st = -1;
  return st;
}

/* This rank's slice [*offset, *offset + *n) of the *ntotal stored particles. */
static int choose_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, int64_t *offset,
                        int64_t *n, int64_t *ntotal) {
  int64_t *counts = malloc((size_t)ck->nranks * sizeof *counts);
  MPM_CALL(agree(ck->comm, counts ? 0 : MPM_ERR_MEMORY));
  if (read_counts(ck, g, counts) < 0) {
    free(counts);
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
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
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                 "the checkpoint '%s' holds %lld particles of phase '%s', too many for %d "
                 "rank(s); restart on more ranks",
                 ck->path, (long long)total, phase, ck->size);
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

/* Collective read of [offset, offset + n) of id [total] and data [ncomp][total]. */
static herr_t read_datasets(hid_t g, int ncomp, int64_t total, int64_t offset, int64_t n,
                            mpm_gidx *id, double *data) {
  const hid_t did = H5Dopen2(g, "id", H5P_DEFAULT), dd = H5Dopen2(g, "data", H5P_DEFAULT);
  hsize_t dims[2] = {(hsize_t)ncomp, (hsize_t)total};
  hsize_t start[2] = {(hsize_t)offset}, count[2] = {(hsize_t)n};
  herr_t st = has_extents(did, 1, &dims[1]) && has_extents(dd, 2, dims) ? 0 : -1;
  if (st >= 0) st = block_io(did, 0, H5T_NATIVE_INT64, 1, start, count, id);
  start[0] = 0, count[0] = (hsize_t)ncomp, start[1] = (hsize_t)offset, count[1] = (hsize_t)n;
  if (st >= 0) st = block_io(dd, 0, H5T_NATIVE_DOUBLE, 2, start, count, data);
  if (did >= 0) H5Dclose(did);
  if (dd >= 0) H5Dclose(dd);
  return st;
}

/* Read this rank's slice and make it p's whole contents. */
static int read_slice(const mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p,
                      int64_t total, int64_t offset, int64_t n) {
  mpm_gidx *id = malloc(((size_t)n + 1) * sizeof *id);
  double *data = malloc(((size_t)p->ncomp * (size_t)n + 1) * sizeof *data);
  unsigned char *keep = calloc((size_t)p->n + 1, 1); /* all zero: drop what p held */
  int rc = agree(ck->comm, id && data && keep ? 0 : MPM_ERR_MEMORY);
  if (!rc && read_datasets(g, p->ncomp, total, offset, n, id, data) < 0) {
    rc = MPM_ERR_INPUT; /* the same file on every rank: the same verdict */
    if (ck->rank == 0)
      mpm_log_all(MPM_LOG_ERROR,
                  "cannot read the particles of phase '%s' from the checkpoint '%s': the "
                  "file is damaged",
                  phase, ck->path);
  }
  /* Through mpm_particles_edit, which owns the block's allocation and its invariants. */
  if (!rc) rc = mpm_particles_edit(p, keep, (mpm_lidx)n, id, data);
  free(id), free(data), free(keep);
  MPM_CALL(rc);
  return 0;
}

static int read_phase(mpm_checkpoint *ck, hid_t g, const char *phase, mpm_particles *p) {
  int64_t offset = 0, n = 0, total = 0, id_next = 0;
  MPM_CALL(check_layout(ck, g, phase, p));
  if (attr_read(g, "id_next", H5T_NATIVE_INT64, 1, &id_next) < 0)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT, "the checkpoint '%s' has no id_next for phase '%s'",
                 ck->path, phase);
  MPM_CALL(choose_slice(ck, g, phase, &offset, &n, &total));
  MPM_CALL(read_slice(ck, g, phase, p, total, offset, n));
  p->id_next = id_next;
  return 0;
}

int mpm_checkpoint_read_particles(mpm_checkpoint *ck, const char *phase, mpm_particles *p) {
  if (H5Lexists(ck->file, phase, H5P_DEFAULT) <= 0)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT,
                 "the checkpoint '%s' has no particles of phase '%s'; restart with the case "
                 "that wrote it",
                 ck->path, phase);
  const hid_t g = H5Gopen2(ck->file, phase, H5P_DEFAULT);
  if (g < 0)
    FAIL_ON_ROOT(ck->rank, MPM_ERR_INPUT, "cannot open phase '%s' in '%s'", phase, ck->path);
  const int rc = read_phase(ck, g, phase, p);
  H5Gclose(g);
  MPM_CALL(rc);
  return 0;
}
