/* Parallel HDF5 helpers shared by snapshots and checkpoints; mpm_h5.h states what callers
 * may rely on. Each collective helper runs in stages: the local part of a stage (dataspaces,
 * property lists, the result of the previous collective call) is agreed on with one
 * MPI_Allreduce, and the stage's collective HDF5 call runs only where every rank is ready
 * for it, so a local failure never leaves the other ranks waiting inside HDF5. The last
 * stage is agreed on too, so every helper returns the same code on every rank. */
#define _GNU_SOURCE /* O_NOFOLLOW, O_CLOEXEC */
#include "mpm_h5.h"
#include "mpm_iowatch.h"
#include "mpm_path.h"
#include "mpm_safefile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* While mpm_h5_write_file runs, the helpers record what failed here instead of logging, so
 * that the user reads one line that names the file and the cause. */
static struct {
  int active;
  char what[160];     /* the first object that failed, e.g. "dataset 'data'" */
  int err;            /* errno just after the first failure on this rank */
  int checksums;      /* the file being written gets checksums */
  int fd;             /* rank 0: the file being written, to reserve its blocks (-1: cannot) */
  long long declared; /* rank 0: the bytes the stages so far may have allocated */
  long long reserved; /* rank 0: the file's blocks [0, reserved) are allocated */
  int unsupported;    /* rank 0: the file system cannot reserve blocks */
} g_write = {0, "", 0, 0, -1, 0, 0, 0};

/* What a stage allocates beyond the bytes it declares (an object header, B-tree nodes, a
 * block of HDF5's metadata aggregator: each well under this), and the margin for what HDF5
 * allocates when the file is created and closed. The sum of the declared bytes and these
 * bounds HDF5's end of allocation, which HDF5 1.10 does not tell for an MPI-IO file
 * (H5Fget_eoa wants a SWMR driver, and H5Fget_filesize counts the reserved blocks). */
#define STAGE_OVERHEAD (4 << 10)
#define RESERVE_MARGIN (64 << 10)

/* Before a stage that may write need bytes to the file being written (mpm_iowatch.h): rank 0
 * makes sure that the blocks of everything the file may hold once the stage is done are
 * allocated. Returns 1 (with errno in g_write.err) if they cannot be, for the stage's
 * agreement; 0 on the other ranks and outside mpm_h5_write_file. */
static int reserve(unsigned long long need) {
  if (!g_write.active || g_write.fd < 0) return 0;
  g_write.declared += (long long)need + STAGE_OVERHEAD;
  const int err = mpm_iowatch_reserve(g_write.fd, g_write.declared + RESERVE_MARGIN,
                                      &g_write.reserved, &g_write.unsupported);
  if (err && !g_write.err) g_write.err = err;
  return err != 0;
}

/* A file could not be closed (agreed on every rank): see write_file. */
static int g_unclosed;

int mpm_h5_unclosed(void) {
  return g_unclosed;
}

int mpm_h5_agree(MPI_Comm comm, int rc) {
  int worst = rc;
  if (MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, comm) != MPI_SUCCESS) return MPM_ERR_MPI;
  return worst;
}

/* Agree on one stage: 0 if it went well on every rank, an error code everywhere if not. */
static int stage(MPI_Comm comm, int failed) {
  return mpm_h5_agree(comm, failed ? MPM_ERR_HDF5 : 0);
}

unsigned long long mpm_h5_hash(unsigned long long h, const void *s, size_t n) {
  const unsigned char *b = s;
  for (size_t k = 0; k < n; ++k) h = (h ^ b[k]) * 0x100000001b3ULL;
  return h;
}

static herr_t blames_checksum(unsigned n, const H5E_error2_t *e, void *found) {
  (void)n;
  if (e->desc && (strstr(e->desc, "checksum") || strstr(e->desc, "Checksum"))) *(int *)found = 1;
  return 0;
}

int mpm_h5_error_is_checksum(void) {
  int found = 0;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, blames_checksum, &found);
  return found;
}

void mpm_h5_quiet_begin(mpm_h5_quiet *saved) {
  H5Eget_auto2(H5E_DEFAULT, &saved->func, &saved->data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

void mpm_h5_quiet_end(const mpm_h5_quiet *saved) {
  H5Eset_auto2(H5E_DEFAULT, saved->func, saved->data);
}

/* A helper's failure: recorded for mpm_h5_write_file's one line, or explained at once
 * outside it. */
static int write_failed(const mpm_h5 *h, int rc, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int write_failed(const mpm_h5 *h, int rc, const char *fmt, ...) {
  char what[160];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  if (g_write.active) {
    if (!g_write.what[0]) snprintf(g_write.what, sizeof g_write.what, "%s", what);
    return rc;
  }
  if (h->rank == 0) mpm_log_all(MPM_LOG_ERROR, "cannot write the %s %s", h->what, what);
  return rc;
}

/* ---- files ----------------------------------------------------------------------------- */

/* Before creating path: no name the create opens may be a link. Rank 0 removes whatever has
 * the name (a leftover of an interrupted write, or a link: unlink removes the link itself);
 * each rank removes PATH.locktest.RANK, which Open MPI's OMPIO opens with O_CREAT and without
 * O_NOFOLLOW while it chooses its shared-file-pointer method for a file opened for writing.
 * H5F_ACC_EXCL then creates the file with O_EXCL, which never follows a link. 0, or 1 if a
 * name could not be freed. */
static int clear_names(MPI_Comm comm, const char *path) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const size_t len = strlen(path) + 32;
  char *lock = malloc(len);
  if (lock) snprintf(lock, len, "%s.locktest.%d", path, rank);
  const int bad = !lock || mpm_file_remove(lock) != 0 || (rank == 0 && mpm_file_remove(path) != 0);
  free(lock);
  return bad;
}

/* Create or open path on every rank of comm. Collective metadata writes let HDF5 flush its
 * metadata cache in one collective write; they are harmless for a read-only file, which
 * has no metadata to write. HDF5's error stack is silenced: the caller says what went
 * wrong in words a user can act on. */
static hid_t file_access(MPI_Comm comm, const char *path, int create, int checksums) {
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  /* The 1.10 format checksums the superblock, every object header and the chunk indexes
   * (fixed arrays, single-chunk); the 1.8 one would still index chunks by v1 B-trees. */
  const int cleared = !create || !clear_names(comm, path);
  /* cleared joins last: H5Pset_fapl_mpio duplicates comm, a collective call every rank makes */
  const int ready =
      fapl >= 0 && H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) >= 0 && cleared &&
      H5Pset_coll_metadata_write(fapl, 1) >= 0 &&
      (!checksums || H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_V110) >= 0);
  hid_t file = -1;
  if (!stage(comm, !ready)) {
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    file = create ? H5Fcreate(path, H5F_ACC_EXCL, H5P_DEFAULT, fapl)
                  : H5Fopen(path, H5F_ACC_RDONLY, fapl);
    H5Eset_auto2(H5E_DEFAULT, func, data);
    /* The MPI-IO open underneath is collective and fails on every rank together; the
     * agreement makes sure no rank goes on with a file the others do not have. */
    if (stage(comm, file < 0) && file >= 0) H5Fclose(file), file = -1;
  }
  if (fapl >= 0) H5Pclose(fapl);
  return file;
}

hid_t mpm_h5_open(MPI_Comm comm, const char *path) {
  return file_access(comm, path, 0, 0);
}

/* Rank 0's one line for a failed write: the file, what failed, the cause and the checkpoint
 * to restart from. err is the largest errno over the ranks (MPI-IO does not always leave a
 * meaningful one). */
static void explain_write_failure(const mpm_h5 *h, const char *path, const char *what, int err) {
  char *dir = mpm_path_parent(path), cause[512], intact[4200];
  struct stat st;
  if (err != ENOSPC && err != EDQUOT && !what[0] && stat(path, &st) == 0 && S_ISDIR(st.st_mode))
    snprintf(cause, sizeof cause, "a directory of that name is in the way; move it");
  else if (err != ENOSPC && err != EDQUOT && !what[0] && (!dir || access(dir, W_OK) != 0))
    snprintf(cause, sizeof cause, "its directory %s is missing or not writable (%s)",
             dir ? dir : "", strerror(errno));
  else
    mpm_iowatch_cause(cause, sizeof cause, err, dir);
  mpm_iowatch_intact(intact, sizeof intact);
  mpm_log_all(MPM_LOG_ERROR,
              "cannot write the %s %s (%s): %s. The file it was to replace, if any, is left as it "
              "was; %s",
              h->what, path, what[0] ? what : "creating the file", cause, intact);
  free(dir);
}

static int write_file(const mpm_h5 *h, const char *path, mpm_h5_fill fill, const void *arg,
                      int checksums) {
  mpm_h5_quiet quiet;
  mpm_h5_quiet_begin(&quiet);
  mpm_iowatch_begin(h->what, path);
  g_write.active = 1, g_write.what[0] = 0, g_write.err = 0, g_write.checksums = checksums;
  /* A file, once created, must be closed, which writes its superblock and root group: on a
   * disk without room for those, no rank creates it. */
  const int room = h->rank == 0 ? mpm_iowatch_room(path, STAGE_OVERHEAD + RESERVE_MARGIN) : 0;
  g_write.err = room;
  errno = 0;
  const hid_t file = mpm_h5_agree(h->comm, room ? MPM_ERR_FILE : 0)
                         ? -1
                         : file_access(h->comm, path, 1, checksums);
  int rc = file < 0 ? MPM_ERR_FILE : 0;
  if (file < 0 && !g_write.err) g_write.err = errno;
  if (file >= 0) {
    /* Rank 0 reserves the file's blocks as it grows: a full disk then fails a reservation,
     * which the ranks agree on, never a write inside HDF5, which they could not. */
    g_write.declared = 0, g_write.reserved = 0, g_write.unsupported = 0;
    g_write.fd = h->rank == 0 ? open(path, O_WRONLY | O_NOFOLLOW | O_CLOEXEC) : -1;
    /* without that handle nothing could be reserved (and a link swapped in since the create
     * fails O_NOFOLLOW): the stage fails, agreed, rather than writing unguarded */
    const int no_fd = h->rank == 0 && g_write.fd < 0;
    if (no_fd && !g_write.err) g_write.err = errno;
    rc = stage(h->comm, no_fd || reserve(0)); /* what the close will write */
    if (rc) snprintf(g_write.what, sizeof g_write.what, "creating it");
    if (!rc) rc = fill(h, file, arg);
    if (rc && !g_write.err) g_write.err = errno;
    /* The close flushes HDF5's metadata: into blocks reserved here, agreed before. */
    int closing = mpm_h5_agree(h->comm, reserve(0) ? MPM_ERR_FILE : 0);
    if (closing && !rc) rc = closing, snprintf(g_write.what, sizeof g_write.what, "closing it");
    errno = 0;
    mpm_iowatch_arm(g_write.err);
    const int closed = mpm_h5_agree(h->comm, H5Fclose(file) < 0 ? MPM_ERR_FILE : 0);
    if (g_write.fd >= 0) {
      mpm_iowatch_release(g_write.fd, g_write.reserved);
      close(g_write.fd);
    }
    g_write.fd = -1;
    /* HDF5 1.10 keeps a file it failed to close as an identifier that crashes its
     * termination (in MPI_Finalize): main must then end without it (mpm_h5_unclosed). */
    if (closed) g_unclosed = 1;
    if (closed && !rc) {
      rc = closed;
      if (!g_write.err) g_write.err = errno;
      snprintf(g_write.what, sizeof g_write.what, "flushing it on close");
    }
  }
  const int recorded = g_write.what[0] || file < 0;
  g_write.active = 0, g_write.checksums = 0;
  mpm_h5_quiet_end(&quiet);
  /* errno is local; the largest one is as good a guess as any rank's. */
  int err[2] = {g_write.err, recorded};
  const int agreed = MPI_Allreduce(MPI_IN_PLACE, err, 2, MPI_INT, MPI_MAX, h->comm);
  /* Every rank is past the file's last collective call: nothing can hang any more. */
  mpm_iowatch_end();
  if (agreed != MPI_SUCCESS) rc = MPM_ERR_MPI;
  if (rc && err[1] && h->rank == 0) explain_write_failure(h, path, g_write.what, err[0]);
  /* An agreed failure, explained once: the run may end cleanly on every rank. */
  if (rc && rc != MPM_ERR_MPI) rc = MPM_ERR_OUTPUT;
  MPM_CALL(rc);
  return 0;
}

int mpm_h5_write_file(const mpm_h5 *h, const char *path, mpm_h5_fill fill, const void *arg) {
  return write_file(h, path, fill, arg, 0);
}

int mpm_h5_write_file_checksummed(const mpm_h5 *h, const char *path, mpm_h5_fill fill,
                                  const void *arg) {
  return write_file(h, path, fill, arg, 1);
}

/* ---- attributes and groups ------------------------------------------------------------- */

hid_t mpm_h5_string_type(void) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  if (type >= 0 && (H5Tset_size(type, H5T_VARIABLE) < 0 || H5Tset_cset(type, H5T_CSET_UTF8) < 0)) {
    H5Tclose(type);
    return -1;
  }
  return type;
}

/* type < 0 (a type this rank could not build) fails like any other local step. */
int mpm_h5_attr(const mpm_h5 *h, hid_t loc, const char *name, hid_t type, int n,
                const void *value) {
  const hsize_t dims = (hsize_t)n;
  const hid_t space = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dims, NULL);
  /* A variable-length string's bytes go to the global heap: its size is not the type's. */
  size_t bytes = type >= 0 ? H5Tget_size(type) * (size_t)n : 0;
  if (type >= 0 && H5Tis_variable_str(type) > 0) bytes = strlen(*(const char *const *)value) + 1;
  int rc = stage(h->comm, space < 0 || type < 0 || reserve(bytes));
  const hid_t a = rc ? -1 : H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  if (!rc) rc = stage(h->comm, a < 0);
  if (!rc) rc = stage(h->comm, H5Awrite(a, type, value) < 0);
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  if (rc)
    return mpm_trace(__FILE__, __LINE__, __func__, write_failed(h, rc, "attribute '%s'", name));
  return 0;
}

int mpm_h5_attr_string(const mpm_h5 *h, hid_t loc, const char *name, const char *value) {
  const hid_t type = mpm_h5_string_type();
  const int rc = mpm_h5_attr(h, loc, name, type, 1, &value);
  if (type >= 0) H5Tclose(type);
  MPM_CALL(rc);
  return 0;
}

int mpm_h5_attr_fixed_string(const mpm_h5 *h, hid_t loc, const char *name, const char *value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  const int bad = type < 0 || H5Tset_size(type, strlen(value) + 1) < 0 ||
                  H5Tset_strpad(type, H5T_STR_NULLTERM) < 0 || H5Tset_cset(type, H5T_CSET_UTF8) < 0;
  const int rc = mpm_h5_attr(h, loc, name, bad ? -1 : type, 1, value);
  if (type >= 0) H5Tclose(type);
  MPM_CALL(rc);
  return 0;
}

int mpm_h5_group(const mpm_h5 *h, hid_t loc, const char *name, hid_t *group) {
  *group = -1;
  int rc = stage(h->comm, reserve(0));
  if (!rc) *group = H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (!rc) rc = stage(h->comm, *group < 0);
  if (rc) {
    if (*group >= 0) H5Gclose(*group);
    *group = -1;
    return mpm_trace(__FILE__, __LINE__, __func__, write_failed(h, rc, "group '%s'", name));
  }
  return 0;
}

/* ---- datasets -------------------------------------------------------------------------- */

/* Collective transfer of this rank's block [start, start + count) of dset (which may be
 * invalid on this rank: a failed open or create) to or from the contiguous buffer buf. A
 * rank with an empty block selects nothing but still takes part. On a failed read,
 * *checksum (if not NULL) says, on every rank, whether any rank's HDF5 blamed a checksum. */
static int block_io(MPI_Comm comm, hid_t dset, int write, hid_t mtype, int rank,
                    const hsize_t *start, const hsize_t *count, void *buf, int *checksum) {
  static double dummy; /* a valid pointer for an empty transfer */
  hsize_t n = 1, one = 1;
  for (int d = 0; d < rank; ++d) n *= count[d];
  const hid_t fspace = dset >= 0 ? H5Dget_space(dset) : -1;
  const hid_t mspace = n ? H5Screate_simple(rank, count, NULL) : H5Screate_simple(1, &one, NULL);
  const hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
  const hssize_t total = fspace >= 0 ? H5Sget_simple_extent_npoints(fspace) : -1;
  herr_t st = total < 0 || mspace < 0 || dxpl < 0 ? -1 : 0;
  if (st >= 0) st = H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
  if (st >= 0 && n) st = H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL);
  if (st >= 0 && !n) st = H5Sselect_none(fspace) < 0 || H5Sselect_none(mspace) < 0 ? -1 : 0;
  int rc = stage(comm, st < 0), bad_sum = 0;
  /* An empty dataset has no storage: even an empty collective transfer would fail on it.
   * Every rank sees the same extents, so all skip it together. */
  if (!rc && total > 0) {
    void *p = n ? buf : &dummy;
    st = write ? H5Dwrite(dset, mtype, mspace, fspace, dxpl, p)
               : H5Dread(dset, mtype, mspace, fspace, dxpl, p);
    if (st < 0) bad_sum = mpm_h5_error_is_checksum();
    if (st < 0 && write) g_write.err = errno;
    rc = stage(comm, st < 0);
    if (rc && !write && checksum) *checksum = mpm_h5_agree(comm, bad_sum);
  }
  if (dxpl >= 0) H5Pclose(dxpl);
  if (mspace >= 0) H5Sclose(mspace);
  if (fspace >= 0) H5Sclose(fspace);
  return rc;
}

/* Chunks of at most CHUNK_MAX elements, whole along the last (fastest) dimensions. */
#define CHUNK_MAX 65536

/* The creation properties of a dataset of extents fdims: checksummed chunks if the file
 * being written asks for them and the dataset has any element (an empty one has no storage
 * to protect). */
static hid_t dataset_create_plist(int rank, const hsize_t *fdims) {
  hsize_t chunk[8], below = 1, total = 1;
  for (int d = 0; d < rank; ++d) total *= fdims[d];
  if (!g_write.checksums || total == 0 || rank > 8) return H5Pcopy(H5P_DATASET_CREATE_DEFAULT);
  for (int d = rank - 1; d >= 0; --d) {
    const hsize_t room = below < CHUNK_MAX ? CHUNK_MAX / below : 1;
    chunk[d] = fdims[d] < room ? fdims[d] : room;
    below *= chunk[d];
  }
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  /* Every element is written at once: no fill values to write first. */
  if (dcpl >= 0 && (H5Pset_chunk(dcpl, rank, chunk) < 0 || H5Pset_fletcher32(dcpl) < 0 ||
                    H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER) < 0 ||
                    H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY) < 0)) {
    H5Pclose(dcpl);
    return -1;
  }
  return dcpl;
}

int mpm_h5_write_block(const mpm_h5 *h, hid_t loc, const char *name, hid_t ftype, hid_t mtype,
                       int rank, const hsize_t *fdims, const hsize_t *start, const hsize_t *count,
                       const void *buf) {
  const hid_t space = H5Screate_simple(rank, fdims, NULL);
  const hid_t dcpl = dataset_create_plist(rank, fdims);
  /* The data; with checksums twice the data, and per chunk (at most CHUNK_MAX elements) its
   * index entry: parallel HDF5 allocates each chunk early at its size unfiltered, then moves
   * the filtered chunk (4 bytes longer) to new space, leaving the first unused. */
  unsigned long long n = 1;
  for (int d = 0; d < rank; ++d) n *= fdims[d];
  const unsigned long long bytes =
      n * H5Tget_size(ftype) * (g_write.checksums ? 2 : 1) + (n / CHUNK_MAX + 1) * 64;
  int rc = stage(h->comm, space < 0 || dcpl < 0 || reserve(bytes));
  const hid_t dset = rc ? -1 : H5Dcreate2(loc, name, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  /* block_io's first stage takes in whether the create succeeded here. */
  if (!rc) rc = block_io(h->comm, dset, 1, mtype, rank, start, count, (void *)buf, NULL);
  if (dset >= 0) H5Dclose(dset);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  if (rc) return mpm_trace(__FILE__, __LINE__, __func__, write_failed(h, rc, "dataset '%s'", name));
  return 0;
}

int mpm_h5_read_block(MPI_Comm comm, hid_t dset, hid_t mtype, int rank, const hsize_t *start,
                      const hsize_t *count, void *buf, int *checksum) {
  if (checksum) *checksum = 0;
  return block_io(comm, dset, 0, mtype, rank, start, count, buf, checksum);
}
