/* Diagnostics CSV. Only rank 0 holds a FILE; every rank holds the communicator, so that a
 * failed write (a full disk) is known to every rank before any acts on it: each row is
 * collective and returns the same code everywhere (MPM_ERR_OUTPUT, explained once). */
#include "mpm_diag.h"

#include "mpm_error.h"
#include "mpm_iowatch.h"
#include "mpm_safefile.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mpm_diag {
  FILE *f;
  int ncols;
  MPI_Comm comm; /* the caller's: rows are written in the same order on every rank */
  int rank;
  char *path;
};

/* Every rank learns rank 0's status: MPM_ERR_OUTPUT on every rank if it failed. */
static int agree(const mpm_diag *d, int status) {
  if (MPI_Bcast(&status, 1, MPI_INT, 0, d->comm) != MPI_SUCCESS) return MPM_ERR_MPI;
  return status ? MPM_ERR_OUTPUT : 0;
}

/* Keep the header and the rows with time <= t_keep of an existing file (none if there is no
 * file: a restart may write into a new folder). */
static int truncate_after(const char *path, double t_keep, char **kept) {
  FILE *f = fopen(path, "r");
  *kept = NULL;
  if (!f && errno == ENOENT) return 0;
  if (!f) MPM_FAIL(MPM_ERR_FILE, "cannot reopen diagnostics '%s': %s", path, strerror(errno));
  size_t cap = 1 << 16, len = 0;
  char *buf, line[8192];
  MPM_ALLOC(buf, cap);
  for (int first = 1; fgets(line, sizeof line, f); first = 0) {
    if (!first && strtod(line, NULL) > t_keep) break;
    size_t k = strlen(line);
    if (len + k + 1 > cap) {
      char *nb = realloc(buf, cap = 2 * (len + k + 1));
      if (!nb) {
        free(buf);
        fclose(f);
        MPM_FAIL(MPM_ERR_MEMORY, "out of memory reading '%s'", path);
      }
      buf = nb;
    }
    memcpy(buf + len, line, k + 1);
    len += k;
  }
  fclose(f);
  *kept = buf;
  return 0;
}

int mpm_diag_open(mpm_diag **d, MPI_Comm comm, const char *path, int ncols,
                  const char *const *names, int append, double t_keep) {
  int rank, status = 0;
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  MPM_ALLOC(*d, 1);
  (*d)->ncols = ncols, (*d)->comm = comm, (*d)->rank = rank;
  (*d)->path = malloc(strlen(path) + 1);
  if ((*d)->path) strcpy((*d)->path, path);
  if (rank == 0 && !(*d)->path) {
    mpm_log_all(MPM_LOG_ERROR, MPM_OOM_MESSAGE, (double)strlen(path) / 1e6);
    status = MPM_ERR_MEMORY;
  } else if (rank == 0) {
    char *kept = NULL;
    /* The rows up to the checkpoint's time must be read before the file is replaced: if they
     * cannot be, the run stops rather than replace the history with a bare header. The file is
     * written anew beside the old one and moved over it (mpm_safefile.h); the stream then goes
     * on appending to the file in place. */
    if (append && (status = truncate_after(path, t_keep, &kept)) != 0) {
      (*d)->f = NULL;
    } else if (!((*d)->f = mpm_file_begin(path, "w"))) {
      status = mpm_file_fail(path, errno, "diagnostics");
    } else if (kept && kept[0]) {
      fputs(kept, (*d)->f);
    } else {
      for (int c = 0; c < ncols; ++c) fprintf((*d)->f, "%s%s", c ? "," : "", names[c]);
      fputc('\n', (*d)->f);
    }
    free(kept);
    int e = 0;
    if ((*d)->f && (fflush((*d)->f) != 0 || ferror((*d)->f))) {
      e = errno ? errno : EIO;
      mpm_file_abandon((*d)->f, path); /* the old file stays as it was */
      (*d)->f = NULL;
    } else if ((*d)->f) {
      e = mpm_file_publish(path);
    }
    if (e) status = mpm_file_fail(path, e, "diagnostics");
  }
  status = agree(*d, status);
  if (status) {
    mpm_diag_close(d);
    return mpm_trace(__FILE__, __LINE__, __func__, status);
  }
  return 0;
}

/* Columns [0, ncols) of a row; the column `at` is the label (none if label is NULL). */
static int write_row(mpm_diag *d, const char *label, int at, const double *values) {
  int failed = 0;
  if (d->f) {
    for (int c = 0, k = 0; c < d->ncols; ++c) {
      if (c) fputc(',', d->f);
      if (label && c == at)
        fputs(label, d->f);
      else
        fprintf(d->f, "%.17g", values[k++]);
    }
    fputc('\n', d->f);
    errno = 0;
    failed = fflush(d->f) != 0 || ferror(d->f);
    if (failed)
      mpm_log_all(MPM_LOG_ERROR, "%s", mpm_iowatch_failed_write("diagnostics", d->path, errno));
  }
  MPM_CALL(agree(d, failed));
  return 0;
}

int mpm_diag_row(mpm_diag *d, const double *values) {
  return write_row(d, NULL, -1, values);
}

int mpm_diag_row_label(mpm_diag *d, const char *label, const double *values) {
  return write_row(d, label, 1, values);
}

void mpm_diag_close(mpm_diag **d) {
  if (!d || !*d) return;
  if ((*d)->f) fclose((*d)->f);
  free((*d)->path);
  free(*d);
  *d = NULL;
}
