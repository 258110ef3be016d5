/* A CSV time series of diagnostics (one row per step or per interval), written by rank 0
 * and flushed after every row so that a run stopped at any moment leaves a valid file. */
#ifndef MPM_DIAG_H
#define MPM_DIAG_H

#include <mpi.h>

typedef struct mpm_diag mpm_diag;

/* Open path with the given column names. With append (a restart), rows whose first
 * column (time) exceeds t_keep are dropped and new rows follow; otherwise the file is new. */
int mpm_diag_open(mpm_diag **d, MPI_Comm comm, const char *path, int ncols,
                  const char *const *names, int append, double t_keep);
/* Write one row (rank 0 writes; the values must be the same on every rank). Collective: a
 * failed write is MPM_ERR_OUTPUT on every rank, explained once by rank 0. */
int mpm_diag_row(mpm_diag *d, const double *values);
/* Write one row whose second column is text: values[0], label, values[1 .. ncols - 2]
 * (several rows of one time, one per named object). */
int mpm_diag_row_label(mpm_diag *d, const char *label, const double *values);
void mpm_diag_close(mpm_diag **d);

#endif
