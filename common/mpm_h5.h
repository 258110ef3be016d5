/* Parallel HDF5 helpers shared by snapshots (mpm_output.c) and checkpoints
 * (mpm_checkpoint.c): one place for how both open and create their files, write attributes
 * and move one rank's block of a dataset. Internal to common/.
 *
 * Invariants, which the callers rely on:
 *
 * - A helper that takes a communicator (directly or through an mpm_h5) is collective: every
 *   rank of the communicator calls it, and it returns the same value on every rank. It agrees
 *   on each rank's local status (mpm_h5_agree) before every collective HDF5 call, so a
 *   failure on one rank (an allocation, a dataspace) makes all ranks skip the call together
 *   instead of leaving the others waiting in it.
 * - Callers keep the same discipline: a decision whether to call a collective helper is
 *   taken on an agreed value, so the ranks stay on one path through every collective call.
 * - A failure every rank meets at once is explained by rank 0 only (MPM_FAIL_ON_ROOT); a
 *   purely local failure is explained by the rank that met it.
 * - Files are opened through the MPI-IO driver with collective metadata writes, and with
 *   HDF5's own error stack silenced while opening and while a file is written, so the
 *   caller's message is the one the user reads. Metadata reads stay independent: reading
 *   attributes needs no agreement.
 * - A file written with checksums (checkpoints) uses the HDF5 1.10 file format, whose
 *   superblock, object headers (attributes included) and chunk indexes all carry
 *   checksums, and stores every non-empty dataset chunked with the Fletcher32 filter, so
 *   HDF5 itself refuses to return altered bytes. Variable-length strings live in the global
 *   heap, which has no checksum: the caller protects those (mpm_h5_hash).
 * - A failed write is explained in one line by mpm_h5_write_file, naming the file, the
 *   object that failed and the likely cause (a full file system, from statvfs and errno);
 *   the helpers it runs stay silent. */
#ifndef MPM_H5_H
#define MPM_H5_H

#include "mpm_error.h"

#include <hdf5.h>
#include <mpi.h>
#include <stddef.h>

/* A failure every rank meets at once: rank 0 explains it and the others only return the
 * code, so the user reads the message once. */
#define MPM_FAIL_ON_ROOT(rank, code, ...)                                                          \
  do {                                                                                             \
    if ((rank) == 0) MPM_FAIL(code, __VA_ARGS__);                                                  \
    return mpm_trace(__FILE__, __LINE__, __func__, (code));                                        \
  } while (0)

/* The largest code over all ranks (MPM_ERR_MPI if the reduction fails): every rank then
 * returns the same result. Collective. */
int mpm_h5_agree(MPI_Comm comm, int rc);

/* Who writes, for the collective helpers below. */
typedef struct mpm_h5 {
  MPI_Comm comm;
  int rank;         /* in comm */
  const char *what; /* the kind of file, for messages: "snapshot", "checkpoint" */
} mpm_h5;

/* A 64-bit FNV-1a hash of the n bytes at s, continuing from h (start with MPM_H5_HASH0):
 * what protects the strings of a checkpoint, which HDF5 keeps in the unchecksummed global
 * heap. */
#define MPM_H5_HASH0 0xcbf29ce484222325ULL
unsigned long long mpm_h5_hash(unsigned long long h, const void *s, size_t n);

/* After a failed HDF5 call (before any other): 1 if HDF5's error stack blames a checksum,
 * i.e. the bytes in the file were altered. */
int mpm_h5_error_is_checksum(void);

/* Silence HDF5's automatic error printing (*saved keeps the handler), or restore it. */
typedef struct mpm_h5_quiet {
  H5E_auto2_t func;
  void *data;
} mpm_h5_quiet;
void mpm_h5_quiet_begin(mpm_h5_quiet *saved);
void mpm_h5_quiet_end(const mpm_h5_quiet *saved);

/* Fills a freshly created file; returns an agreed code. */
typedef int (*mpm_h5_fill)(const mpm_h5 *h, hid_t file, const void *arg);

/* Create path anew (whatever had the name is removed first, a link itself, and the file is
 * created exclusively: see mpm_safefile.h), fill it and close it. Returns once every rank has
 * closed the file, so the agreement doubles as a barrier: rank 0 may then rename it. A
 * failure of the helpers below (a full disk) is reported here, once, as one line. */
int mpm_h5_write_file(const mpm_h5 *h, const char *path, mpm_h5_fill fill, const void *arg);

/* The same with checksums: the 1.10 file format (checksummed metadata) and every non-empty
 * dataset that fill writes chunked with the Fletcher32 filter. */
int mpm_h5_write_file_checksummed(const mpm_h5 *h, const char *path, mpm_h5_fill fill,
                                  const void *arg);

/* 1 on every rank once a file written by mpm_h5_write_file could not be closed (a failed
 * flush the disk space reservation could not prevent, mpm_iowatch.h): HDF5 1.10 then keeps an
 * identifier that crashes its own termination, so the run must end without MPI_Finalize. */
int mpm_h5_unclosed(void);

/* Open path read-only; the same file on every rank, or -1 on every rank (without a
 * message: the caller says what went wrong). */
hid_t mpm_h5_open(MPI_Comm comm, const char *path);

/* Attribute name of n values (a scalar if n == 1) of memory type type. */
int mpm_h5_attr(const mpm_h5 *h, hid_t loc, const char *name, hid_t type, int n, const void *value);

/* A variable-length UTF-8 string: it lives in the file's global heap, so a long case text
 * does not hit the 64 KiB limit of an object header, and h5py reads it as str. */
int mpm_h5_attr_string(const mpm_h5 *h, hid_t loc, const char *name, const char *value);
/* The same as a fixed-length string: it lives in the object header (or the dense attribute
 * storage), which HDF5 checksums, where a variable-length string's bytes sit in the global heap,
 * which it does not (a damaged heap can crash the reader). Checkpoints use this. */
int mpm_h5_attr_fixed_string(const mpm_h5 *h, hid_t loc, const char *name, const char *value);

/* The memory type of mpm_h5_attr_string; the caller closes it. */
hid_t mpm_h5_string_type(void);

/* Create the group name under loc into *group, or fail on every rank. */
int mpm_h5_group(const mpm_h5 *h, hid_t loc, const char *name, hid_t *group);

/* Create dataset name (extents fdims, file type ftype) under loc and write this rank's block
 * [start, start + count) from the contiguous buffer buf (memory type mtype). A rank with an
 * empty block still takes part, selecting nothing. */
int mpm_h5_write_block(const mpm_h5 *h, hid_t loc, const char *name, hid_t ftype, hid_t mtype,
                       int rank, const hsize_t *fdims, const hsize_t *start, const hsize_t *count,
                       const void *buf);

/* Read this rank's block [start, start + count) of dset into buf. 0, or MPM_ERR_HDF5 on
 * every rank without a message; then *checksum (may be NULL) is 1 on every rank if HDF5
 * found a checksum mismatch on any rank. */
int mpm_h5_read_block(MPI_Comm comm, hid_t dset, hid_t mtype, int rank, const hsize_t *start,
                      const hsize_t *count, void *buf, int *checksum);

#endif
