/* Files written without following links (see mpm_safefile.h). */
#define _POSIX_C_SOURCE 200809L /* O_NOFOLLOW, O_CLOEXEC, lstat, fdopen */
#include "mpm_safefile.h"

#include "mpm_error.h"
#include "mpm_iowatch.h"
#include "mpm_log.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int mpm_file_is_link(const char *path) {
  struct stat st;
  return path && lstat(path, &st) == 0 && S_ISLNK(st.st_mode);
}

static char *tmp_name(const char *path) {
  const size_t len = strlen(path) + 5;
  char *tmp = malloc(len);
  if (tmp) snprintf(tmp, len, "%s.tmp", path);
  return tmp;
}

int mpm_file_remove(const char *path) {
  return unlink(path) == 0 || errno == ENOENT ? 0 : errno;
}

FILE *mpm_file_begin(const char *path, const char *mode) {
  char *tmp = tmp_name(path);
  if (!tmp) return errno = ENOMEM, NULL;
  /* O_EXCL never opens an existing name (a link included): what is written is new. */
  int err = mpm_file_remove(tmp);
  const int fd = err ? -1 : open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (!err && fd < 0) err = errno;
  FILE *f = fd >= 0 ? fdopen(fd, mode) : NULL;
  if (fd >= 0 && !f) {
    err = errno;
    close(fd);
    unlink(tmp);
  }
  free(tmp);
  errno = err;
  return f;
}

int mpm_file_publish(const char *path) {
  char *tmp = tmp_name(path);
  if (!tmp) return ENOMEM;
  const int err = rename(tmp, path) == 0 ? 0 : errno; /* replaces a link, never its target */
  if (err) unlink(tmp);
  free(tmp);
  return err;
}

int mpm_file_commit(FILE *f, const char *path) {
  const int bad = ferror(f);
  int err = fclose(f) != 0 ? errno : bad ? EIO : 0;
  if (err) {
    mpm_file_abandon(NULL, path);
    return err;
  }
  return mpm_file_publish(path);
}

void mpm_file_abandon(FILE *f, const char *path) {
  if (f) fclose(f);
  char *tmp = tmp_name(path);
  if (tmp) unlink(tmp);
  free(tmp);
}

int mpm_file_open_fd(const char *path, int flags) {
  /* O_TRUNC only once the file is known to be ours: a hard link planted under the name (whose
   * other name may be anywhere) is refused before anything of it is cut. */
  const int fd = open(path, (flags & ~O_TRUNC) | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
  if (fd < 0) return -1;
  struct stat st;
  const int fl = fcntl(fd, F_GETFL);
  const int err = fstat(fd, &st) != 0                                                      ? errno
                  : S_ISDIR(st.st_mode)                                                    ? EISDIR
                  : !S_ISREG(st.st_mode)                                                   ? EINVAL
                  : st.st_nlink > 1                                                        ? EMLINK
                  : fl < 0                                                                 ? errno
                  : (flags & O_NONBLOCK) == 0 && fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) != 0 ? errno
                  : (flags & O_TRUNC) && ftruncate(fd, 0) != 0                             ? errno
                                                                                           : 0;
  if (err) {
    close(fd);
    errno = err;
    return -1;
  }
  return fd;
}

int mpm_file_fail(const char *path, int err, const char *what) {
  char *tmp = tmp_name(path);
  const int link = err == ELOOP || mpm_file_is_link(path) || mpm_file_is_link(tmp);
  if (link)
    mpm_log_all(MPM_LOG_ERROR, MPM_LINK_REFUSAL, mpm_file_is_link(tmp) ? tmp : path);
  else
    mpm_log_all(MPM_LOG_ERROR, "%s", mpm_iowatch_failed_write(what, path, err));
  free(tmp);
  return mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_FILE);
}
