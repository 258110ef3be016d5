/* File-path helpers (see mpm_path.h). */
#define _POSIX_C_SOURCE 200809L /* mkdir, stat, access */
#include "mpm_path.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

char *mpm_path_join(const char *dir, const char *name) {
  const size_t len = strlen(dir) + strlen(name) + 2;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s/%s", dir, name);
  return s;
}

char *mpm_path_parent(const char *path) {
  const char *slash = strrchr(path, '/');
  const size_t n = !slash ? 1 : slash == path ? 1 : (size_t)(slash - path);
  char *dir = malloc(n + 1);
  if (!dir) return NULL;
  memcpy(dir, slash ? path : ".", n);
  dir[n] = 0;
  return dir;
}

int mpm_path_make_dir(const char *dir) {
  if (!dir[0]) return ENOENT;
  const size_t len = strlen(dir);
  char *p = malloc(len + 1);
  int err = p ? 0 : ENOMEM;
  if (p) memcpy(p, dir, len + 1);
  for (char *q = p ? p + 1 : NULL; q && !err; ++q) { /* each component in turn */
    if (*q != '/' && *q != 0) continue;
    const char c = *q;
    *q = 0;
    if (mkdir(p, 0777) != 0 && errno != EEXIST) err = errno;
    *q = c;
    if (!c) break;
  }
  free(p);
  struct stat st;
  if (!err && stat(dir, &st) != 0) err = errno;
  if (!err && !S_ISDIR(st.st_mode)) err = ENOTDIR;
  if (!err && access(dir, W_OK | X_OK) != 0) err = errno;
  return err;
}
