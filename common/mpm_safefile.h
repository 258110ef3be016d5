/* Writing files into the output folder without ever writing through a link.
 *
 * Every file mpmfsi creates or writes in an output folder goes through these functions (HDF5
 * files through mpm_h5.c, which creates them the same way). Invariants:
 *
 * - A file written whole goes to PATH.tmp, then is renamed over PATH. Whatever had the
 *   temporary name is removed first (unlink removes a link itself, never its target), and the
 *   temporary is created with O_CREAT | O_EXCL, which fails on any existing name, a link
 *   included, so nothing is opened that this call did not create. rename then replaces
 *   whatever PATH was (a link too) and never touches what a link pointed to.
 * - A file continued in place (run.log on a restart, the lock) is opened with O_NOFOLLOW, and
 *   only a regular file is written: a link of that name fails the open with ELOOP.
 * - A failure is one line naming the file; a link gets MPM_LINK_REFUSAL, which says to
 *   remove it. */
#ifndef MPM_SAFEFILE_H
#define MPM_SAFEFILE_H

#include <stdio.h>

/* The refusal for a link where a result goes (printf format, one %s: the path). */
#define MPM_LINK_REFUSAL "%s is a symbolic link; mpmfsi does not write through links: remove it"

/* 1 when path itself is a symbolic link (lstat), 0 otherwise. */
int mpm_file_is_link(const char *path);

/* Start writing path whole: a new, empty PATH.tmp, opened for writing ("w" or "wb").
 * NULL with errno set on failure. */
FILE *mpm_file_begin(const char *path, const char *mode);

/* Move PATH.tmp over path (the stream stays open and keeps writing into the same file).
 * 0 or an errno value; on failure PATH.tmp is removed. */
int mpm_file_publish(const char *path);

/* Close f (from mpm_file_begin) and publish it. 0 or an errno value; on any failure the
 * temporary is removed and path is left as it was. */
int mpm_file_commit(FILE *f, const char *path);

/* Give up a file begun with mpm_file_begin: close f (may be NULL) and remove PATH.tmp. */
void mpm_file_abandon(FILE *f, const char *path);

/* open(2) for writing an existing or new regular file in place, never through a link: flags
 * as for open (O_NOFOLLOW, O_NONBLOCK and O_CLOEXEC are added; O_NONBLOCK is cleared again
 * once the file is known to be regular; O_TRUNC is applied only then). -1 with errno set on
 * failure: ELOOP for a link, EMLINK for a file with another (hard) link, EISDIR for a folder,
 * ENXIO or EINVAL for anything else that is not a regular file. */
int mpm_file_open_fd(const char *path, int flags);

/* Remove path, a link itself if it is one: 0 or an errno value (ENOENT counts as success). */
int mpm_file_remove(const char *path);

/* Log the one line for a failure to write path (err: the errno value) and return
 * MPM_ERR_FILE. A link gets MPM_LINK_REFUSAL; otherwise "cannot write the WHAT PATH: CAUSE". */
int mpm_file_fail(const char *path, int err, const char *what);

#endif
