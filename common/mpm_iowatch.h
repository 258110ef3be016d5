/* Failed collective writes: what every writer of the run's files shares so that a full disk
 * (or any failed write) ends a parallel run within a bounded time with one line.
 *
 * - The one line names the file, the cause and the newest checkpoint that is known to be
 *   complete (mpm_iowatch_set_checkpoint), so the user knows where to restart from.
 * - A collective write (mpm_h5_write_file) never lets a full disk fail a write inside parallel
 *   HDF5 1.10, because what HDF5 and Open MPI's MPI-IO do then cannot be agreed on: a rank
 *   whose MPI-IO write fails inside HDF5 (its metadata flush at H5Fclose, say) leaves HDF5's
 *   collective sequence (it skips the sync point's barrier and goes on to MPI_File_close)
 *   while the others wait in that barrier, so no code of ours runs again; and Open MPI 4.1's
 *   MPI-IO drops some failed writes without an error at all. So rank 0 reserves the file's
 *   blocks (mpm_iowatch_reserve) before each stage that may write, up to HDF5's end of
 *   allocation plus what the stage adds plus a margin, and the ranks agree on the outcome
 *   before the stage runs: a full disk fails the reservation, every rank skips the stage,
 *   and the file's close writes only into blocks it already holds. The blocks beyond the
 *   end of the closed file are released (mpm_iowatch_release).
 * - Where blocks cannot be reserved (a file system without fallocate), the free space is
 *   checked instead, which a race or a quota can beat. The last resort is a watchdog armed
 *   around the file's close: if the ranks have not all closed the file within
 *   MPM_IOWATCH_SECONDS ($MPMFSI_IO_WATCHDOG seconds, if set), it logs the one line and
 *   exits (status 1; mpiexec then ends the other ranks). It never fires on a close that ends,
 *   failed or not. */
#ifndef MPM_IOWATCH_H
#define MPM_IOWATCH_H

#include <stddef.h>

#define MPM_IOWATCH_SECONDS 120

/* A collective write of path (a "snapshot", "checkpoint", ...) starts on this rank. */
void mpm_iowatch_begin(const char *what, const char *path);

/* Its file is about to be closed (err: the errno of a failure this rank saw, or 0): start
 * the watchdog. */
void mpm_iowatch_arm(int err);

/* Every rank has closed the file and agreed on the outcome: stop the watchdog. */
void mpm_iowatch_end(void);

/* Make sure the blocks [0, end) of the open file fd are allocated (*reserved: the end
 * reserved so far, updated; *unsupported: set once the file system cannot reserve, after
 * which the free space is checked instead). 0, or the errno (ENOSPC, EDQUOT, ...). */
int mpm_iowatch_reserve(int fd, long long end, long long *reserved, int *unsupported);

/* 0 if the file system of path (a file to be created) has bytes free, ENOSPC if not. */
int mpm_iowatch_room(const char *path, long long bytes);

/* Release the reserved blocks beyond the end of file fd (best effort). */
void mpm_iowatch_release(int fd, long long reserved);

/* path is a complete checkpoint (just written, or a restart's source). */
void mpm_iowatch_set_checkpoint(const char *path);

/* "earlier checkpoints are intact: PATH" or what to say when there is none yet, for the end
 * of a failure's line. */
void mpm_iowatch_intact(char *buf, size_t size);

/* The cause of a failed write in words: "no space left on device (N bytes free)" and the
 * like, from errno err and the free space of dir's file system. */
void mpm_iowatch_cause(char *buf, size_t size, int err, const char *dir);

/* "cannot write the WHAT PATH: <cause>; <intact>", the one line for a failed write of a
 * small file (errno err), in a buffer that the next call reuses. */
const char *mpm_iowatch_failed_write(const char *what, const char *path, int err);

#endif
