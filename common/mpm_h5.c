/* Parallel HDF5 helpers shared by snapshots and checkpoints; mpm_h5.h states what callers
 * may rely on. Each collective helper runs in stages: the local part of a stage (dataspaces,
 * property lists, the result of the previous collective call) is agreed on with one
 * MPI_Allreduce, and the stage's collective HDF5 call runs only where every rank is ready
 * for it, so a local failure never leaves the other ranks waiting inside HDF5. The last
 * stage is agreed on too, so every helper returns the same code on every rank. */
#include "mpm_h5.h"

int mpm_h5_agree(MPI_Comm comm, int rc) {
  int worst = rc;
  if (MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, comm) != MPI_SUCCESS) return MPM_ERR_MPI;
  return worst;
}

/* Agree on one stage: 0 if it went well on every rank, an error code everywhere if not. */
static int stage(MPI_Comm comm, int failed) {
  return mpm_h5_agree(comm, failed ? MPM_ERR_HDF5 : 0);
}

/* ---- files ----------------------------------------------------------------------------- */

/* Create or open path on every rank of comm. Collective metadata writes let HDF5 flush its
 * metadata cache in one collective write; they are harmless for a read-only file, which
 * has no metadata to write. HDF5's error stack is silenced: the caller says what went
 * wrong in words a user can act on. */
static hid_t file_access(MPI_Comm comm, const char *path, int create) {
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  const int ready = fapl >= 0 && H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) >= 0 &&
                    H5Pset_coll_metadata_write(fapl, 1) >= 0;
  hid_t file = -1;
  if (!stage(comm, !ready)) {
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    file = create ? H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)
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
  return file_access(comm, path, 0);
}

int mpm_h5_write_file(const mpm_h5 *h, const char *path, mpm_h5_fill fill, const void *arg) {
  const hid_t file = file_access(h->comm, path, 1);
  if (file < 0)
    MPM_FAIL_ON_ROOT(h->rank, MPM_ERR_FILE,
                     "cannot create the %s %s: check that its directory exists and is "
                     "writable, and that the disk is not full",
                     h->what, path);
  const int rc = fill(h, file, arg);
  const int closed = mpm_h5_agree(h->comm, H5Fclose(file) < 0 ? MPM_ERR_FILE : 0);
  if (closed && !rc)
    MPM_FAIL_ON_ROOT(h->rank, closed, "cannot finish the %s %s (is the disk full?)", h->what, path);
  MPM_CALL(rc);
  return 0;
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
  int rc = stage(h->comm, space < 0 || type < 0);
  const hid_t a = rc ? -1 : H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  if (!rc) rc = stage(h->comm, a < 0);
  if (!rc) rc = stage(h->comm, H5Awrite(a, type, value) < 0);
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  if (rc) MPM_FAIL_ON_ROOT(h->rank, rc, "cannot write the %s attribute '%s'", h->what, name);
  return 0;
}

int mpm_h5_attr_string(const mpm_h5 *h, hid_t loc, const char *name, const char *value) {
  const hid_t type = mpm_h5_string_type();
  const int rc = mpm_h5_attr(h, loc, name, type, 1, &value);
  if (type >= 0) H5Tclose(type);
  MPM_CALL(rc);
  return 0;
}

int mpm_h5_group(const mpm_h5 *h, hid_t loc, const char *name, hid_t *group) {
  *group = H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const int rc = stage(h->comm, *group < 0);
  if (rc) {
    if (*group >= 0) H5Gclose(*group);
    *group = -1;
    MPM_FAIL_ON_ROOT(h->rank, rc, "cannot create the %s group '%s'", h->what, name);
  }
  return 0;
}

/* ---- datasets -------------------------------------------------------------------------- */

/* Collective transfer of this rank's block [start, start + count) of dset (which may be
 * invalid on this rank: a failed open or create) to or from the contiguous buffer buf. A
 * rank with an empty block selects nothing but still takes part. */
static int block_io(MPI_Comm comm, hid_t dset, int write, hid_t mtype, int rank,
                    const hsize_t *start, const hsize_t *count, void *buf) {
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
  int rc = stage(comm, st < 0);
  /* An empty dataset has no storage: even an empty collective transfer would fail on it.
   * Every rank sees the same extents, so all skip it together. */
  if (!rc && total > 0) {
    void *p = n ? buf : &dummy;
    st = write ? H5Dwrite(dset, mtype, mspace, fspace, dxpl, p)
               : H5Dread(dset, mtype, mspace, fspace, dxpl, p);
    rc = stage(comm, st < 0);
  }
  if (dxpl >= 0) H5Pclose(dxpl);
  if (mspace >= 0) H5Sclose(mspace);
  if (fspace >= 0) H5Sclose(fspace);
  return rc;
}

int mpm_h5_write_block(const mpm_h5 *h, hid_t loc, const char *name, hid_t ftype, hid_t mtype,
                       int rank, const hsize_t *fdims, const hsize_t *start, const hsize_t *count,
                       const void *buf) {
  const hid_t space = H5Screate_simple(rank, fdims, NULL);
  int rc = stage(h->comm, space < 0);
  const hid_t dset =
      rc ? -1 : H5Dcreate2(loc, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  /* block_io's first stage takes in whether the create succeeded here. */
  if (!rc) rc = block_io(h->comm, dset, 1, mtype, rank, start, count, (void *)buf);
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  if (rc) MPM_FAIL_ON_ROOT(h->rank, rc, "cannot write the %s dataset '%s'", h->what, name);
  return 0;
}

int mpm_h5_read_block(MPI_Comm comm, hid_t dset, hid_t mtype, int rank, const hsize_t *start,
                      const hsize_t *count, void *buf) {
  return block_io(comm, dset, 0, mtype, rank, start, count, buf);
}
