/* File-path helpers (see mpm_path.h). */
#define _DEFAULT_SOURCE /* mkdir, stat, access, realpath */
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

/* res + "/" + name, with res absolute ("/" stays single). */
static char *child(const char *res, const char *name, size_t n) {
  const size_t len = strlen(res) + n + 2;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s%s%.*s", strcmp(res, "/") == 0 ? "" : res, "/", (int)n, name);
  return s;
}

char *mpm_path_resolve(const char *dir) {
  char *res = strdup("/");
  int real = 1; /* res exists (and is resolved) */
  if (dir[0] != '/') {
    free(res);
    res = realpath(".", NULL); /* no length limit, unlike getcwd into a buffer */
  }
  for (const char *p = dir; res && *p;) {
    const size_t n = strcspn(p, "/");
    char *next = NULL;
    struct stat st;
    if (n == 0 || (n == 1 && p[0] == '.')) {
      next = strdup(res);
    } else if (!real && n == 2 && p[0] == '.' && p[1] == '.') { /* back out of a new folder */
      next = mpm_path_parent(res);
      real = next && stat(next, &st) == 0;
    } else {
      next = child(res, p, n);
      char *r = next && real && lstat(next, &st) == 0 ? realpath(next, NULL) : NULL;
      if (r) free(next), next = r;
      real = r != NULL;
    }
    free(res);
    res = next;
    p += n + (p[n] == '/');
  }
  return res;
}
