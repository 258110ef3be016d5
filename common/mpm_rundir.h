/* The output folder of a run: one folder, one run.
 *
 * A run claims its folder before it writes anything: rank 0 takes an exclusive lock on
 * DIR/.lock (flock, held until the run ends, released by the kernel if the process dies), so
 * a second run started into the same folder is refused at once. Then the folder's contents
 * decide:
 *
 * - A new run (and a restart into a folder other than its checkpoint's) needs a folder with
 *   no mpmfsi results in it (files of other kinds are left alone). With `overwrite` the
 *   earlier run's results are deleted first, never mixed with the new ones.
 * - A restart in its checkpoint's own folder continues that run: allowed when nothing in the
 *   folder is later than the checkpoint (the usual "carry on to a later t_end"). When later
 *   results exist (an earlier checkpoint of a finished or crashed run) it is refused, unless
 *   `truncate` asks to cut the run back: the later snapshots and checkpoints are deleted, and
 *   the index and the CSV files are cut by the output writers that reopen them. (`mpmfsi
 *   restart` without an output.dir sends such a restart to a new folder instead, see
 *   app/main.c, so the refusal is met only when that folder is named explicitly.)
 *
 * Before the lock is taken, a symbolic link named as one of our files (a result, a temporary,
 * the lock) is refused, or with `overwrite` deleted (the link, never its target): nothing is
 * ever written through a link (the writers see to it too, mpm_safefile.h).
 *
 * The folder records its run in DIR/run.id; checkpoints carry the same id, so a checkpoint
 * copied into another run's folder is not taken for that run's. */
#ifndef MPM_RUNDIR_H
#define MPM_RUNDIR_H

#include <mpi.h>
#include <stddef.h>

typedef struct mpm_rundir mpm_rundir;

typedef struct mpm_rundir_request {
  const char *dir;        /* the output folder */
  int overwrite;          /* delete an earlier run's results found in dir */
  int truncate;           /* restart in place: cut the later results of the run */
  const char *checkpoint; /* restart: the checkpoint file; NULL for a new run */
  double t;               /* restart: the checkpoint's time */
  double run_id;          /* restart: the checkpoint's run id (0: unknown) */
} mpm_rundir_request;

/* Claim the folder (collective; rank 0 does the file work). On success *append is 1 when the
 * run continues the folder's existing record (restart in place), 0 when it starts a new one;
 * *run_id is the id to store in checkpoints; *next_checkpoint the number of the next
 * checkpoint_NNNNNN.h5 (after every number in the folder, so none is replaced). A folder that
 * cannot be claimed is an input error with one message saying what to do. */
int mpm_rundir_claim(mpm_rundir **rd, MPI_Comm comm, const mpm_rundir_request *req, int *append,
                     double *run_id, long *next_checkpoint);

/* The latest time the folder dir records beyond a checkpoint at time t that lies in it
 * (snapshots, CSV rows, other checkpoints), or -inf when nothing there is later: what decides
 * whether a restart can continue in dir. Collective; rank 0 reads. */
int mpm_rundir_latest(MPI_Comm comm, const char *dir, const char *checkpoint, double t,
                      double *latest);

/* The longest file path mpmfsi can write: Open MPI's MPI-IO (OMPIO, sharedfp/lockedfile in
 * Open MPI 4) writes "FILE.locktest.RANK" for every file it opens for writing into a 256-byte
 * buffer, and aborts beyond it; 238 characters leave room for ".locktest.", a rank of 7 digits
 * and the terminating zero. The longest name in a folder is "checkpoint_NNNNNN.h5.tmp" (24),
 * so output.dir, as written, may have at most 238 - 25 characters. */
#define MPM_RUNDIR_MAX_PATH 238
#define MPM_RUNDIR_MAX_DIR  (MPM_RUNDIR_MAX_PATH - 25)

/* Can dir be an output folder? Refused (MPM_ERR_INPUT, the reason in why, worded to follow
 * "output.dir ..."): a path longer than MPM_RUNDIR_MAX_DIR; the root folder or a system folder
 * (/bin, /boot, /dev, /etc, /lib*, /proc, /sbin, /sys, /usr, /var, /run), links and ".."
 * resolved, and any folder in one unless a folder on the way down belongs to a user other
 * than root or is a shared scratch folder (sticky and world-writable: /var/tmp, /dev/shm);
 * without overwrite, a link named as one of mpmfsi's files in it. Local: no MPI. */
int mpm_rundir_check_dir(const char *dir, int overwrite, char *why, size_t n);

/* The first entry of dir named as one of mpmfsi's files (a result, a temporary, the lock) that
 * is a symbolic link: its name (malloc'ed), or NULL. */
char *mpm_rundir_find_link(const char *dir);

/* Release the lock (the folder and its files stay). */
void mpm_rundir_release(mpm_rundir **rd);

#endif
