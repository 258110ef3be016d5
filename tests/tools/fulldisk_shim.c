/* A full disk for tests that cannot mount a small tmpfs (no CAP_SYS_ADMIN): an LD_PRELOAD
 * library that makes writes to the files under one folder fail with ENOSPC once a budget of
 * 4 KiB pages, shared by every process of the run, is spent. Test-only; never linked into
 * mpmfsi.
 *
 *   MPMFSI_FULLDISK_DIR     only regular files whose path starts with this folder (absolute,
 *                           resolved) count; every other call passes through
 *   MPMFSI_FULLDISK_BYTES   the budget in bytes, over all processes
 *   MPMFSI_FULLDISK_NO_RESERVE  if set, fallocate fails with EOPNOTSUPP and statvfs tells the
 *                           real free space: a file system that cannot reserve blocks, where
 *                           a write fails although the free space looked sufficient (a quota)
 *   MPMFSI_FULLDISK_COUNTER a file (outside that folder) holding the pages used so far;
 *                           COUNTER.<inode> holds one byte per page of that file, 1 once the
 *                           page is allocated. Updated under flock, so ranks share them.
 *
 * Like a file system's blocks: a page costs the first time a write or fallocate touches it
 * (later writes to it are free, as are pages reserved by fallocate), and a write or fallocate
 * whose new pages exceed the budget changes nothing and fails with ENOSPC. Files removed or
 * truncated give nothing back (the runs under test end at their first failure); statvfs of
 * the folder reports what is left of the budget as its free space. Intercepted: write,
 * pwrite, writev, pwritev (and the 64-bit names), pwritev2, fallocate, posix_fallocate,
 * statvfs, fstatvfs. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <unistd.h>

/* 1 if path lies under MPMFSI_FULLDISK_DIR. */
static int under(const char *path) {
  const char *dir = getenv("MPMFSI_FULLDISK_DIR");
  if (!dir || !dir[0]) return 0;
  const size_t len = strlen(dir);
  return strncmp(path, dir, len) == 0 && (path[len] == '/' || path[len] == 0);
}

/* 1 if fd is a regular file under MPMFSI_FULLDISK_DIR. */
static int counted(int fd) {
  const char *dir = getenv("MPMFSI_FULLDISK_DIR");
  if (!dir || !dir[0]) return 0;
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  char link[64], path[PATH_MAX];
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, path, sizeof path - 1);
  if (n <= 0) return 0;
  path[n] = 0;
  const size_t len = strlen(dir);
  return strncmp(path, dir, len) == 0 && (path[len] == '/' || path[len] == 0);
}

#define PAGE 4096

/* Allocate the pages of [off, off + n) of fd's file from the shared budget: 0, or -1 with
 * errno = ENOSPC if the new ones do not fit. Raw system calls, past our own wrappers. */
static int take(int fd, long long off, size_t n) {
  const char *budget = getenv("MPMFSI_FULLDISK_BYTES"),
             *counter = getenv("MPMFSI_FULLDISK_COUNTER");
  struct stat st;
  if (!budget || !counter || n == 0 || off < 0 || fstat(fd, &st) != 0) return 0;
  const long long limit = atoll(budget) / PAGE, first = off / PAGE,
                  last = (off + (long long)n - 1) / PAGE;
  char map_path[PATH_MAX];
  snprintf(map_path, sizeof map_path, "%s.%llu", counter, (unsigned long long)st.st_ino);
  const int cfd = (int)syscall(SYS_openat, AT_FDCWD, counter, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  const int mfd = (int)syscall(SYS_openat, AT_FDCWD, map_path, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (cfd < 0 || mfd < 0) {
    if (cfd >= 0) syscall(SYS_close, cfd);
    if (mfd >= 0) syscall(SYS_close, mfd);
    return 0;
  }
  flock(cfd, LOCK_EX);
  char buf[32] = {0};
  const long got = syscall(SYS_pread64, cfd, buf, sizeof buf - 1, 0L);
  long long used = got > 0 ? atoll(buf) : 0, fresh = 0;
  static char map[1 << 16];
  int rc = 0;
  /* Count, then (if they fit) mark the new pages, a window of the map at a time. */
  for (int pass = 0; pass < 2 && !rc; ++pass) {
    for (long long p = first; p <= last; p += (long long)sizeof map) {
      const long long k =
          last - p + 1 < (long long)sizeof map ? last - p + 1 : (long long)sizeof map;
      memset(map, 0, (size_t)k);
      syscall(SYS_pread64, mfd, map, (size_t)k, (long)p);
      long long count = 0;
      for (long long i = 0; i < k; ++i) count += !map[i], map[i] = 1;
      if (pass == 0)
        fresh += count;
      else
        syscall(SYS_pwrite64, mfd, map, (size_t)k, (long)p);
    }
    if (pass == 0 && used + fresh > limit) rc = -1;
  }
  if (!rc && fresh) {
    const int len = snprintf(buf, sizeof buf, "%lld\n", used + fresh);
    syscall(SYS_pwrite64, cfd, buf, (size_t)len, 0L);
    syscall(SYS_ftruncate, cfd, (long)len);
  }
  flock(cfd, LOCK_UN);
  syscall(SYS_close, mfd);
  syscall(SYS_close, cfd);
  if (rc) errno = ENOSPC;
  return rc;
}

/* The offset a write() or writev() on fd goes to. */
static long long here(int fd) {
  const int flags = fcntl(fd, F_GETFL);
  struct stat st;
  if (flags >= 0 && (flags & O_APPEND) && fstat(fd, &st) == 0) return (long long)st.st_size;
  return (long long)lseek(fd, 0, SEEK_CUR);
}

static size_t iov_bytes(const struct iovec *iov, int n) {
  size_t s = 0;
  for (int k = 0; k < n; ++k) s += iov[k].iov_len;
  return s;
}

/* The next definition of name (libc's), looked up once. */
#define REAL(name, ret, args)                                                                      \
  static ret(*real_##name) args;                                                                   \
  if (!real_##name) *(void **)&real_##name = dlsym(RTLD_NEXT, #name)

ssize_t write(int fd, const void *b, size_t n) {
  REAL(write, ssize_t, (int, const void *, size_t));
  if (counted(fd) && take(fd, here(fd), n)) return -1;
  return real_write(fd, b, n);
}

ssize_t pwrite(int fd, const void *b, size_t n, off_t off) {
  REAL(pwrite, ssize_t, (int, const void *, size_t, off_t));
  if (counted(fd) && take(fd, off, n)) return -1;
  return real_pwrite(fd, b, n, off);
}

ssize_t pwrite64(int fd, const void *b, size_t n, off_t off) {
  REAL(pwrite64, ssize_t, (int, const void *, size_t, off_t));
  if (counted(fd) && take(fd, off, n)) return -1;
  return real_pwrite64(fd, b, n, off);
}

ssize_t writev(int fd, const struct iovec *iov, int cnt) {
  REAL(writev, ssize_t, (int, const struct iovec *, int));
  if (counted(fd) && take(fd, here(fd), iov_bytes(iov, cnt))) return -1;
  return real_writev(fd, iov, cnt);
}

ssize_t pwritev(int fd, const struct iovec *iov, int cnt, off_t off) {
  REAL(pwritev, ssize_t, (int, const struct iovec *, int, off_t));
  if (counted(fd) && take(fd, off, iov_bytes(iov, cnt))) return -1;
  return real_pwritev(fd, iov, cnt, off);
}

ssize_t pwritev64(int fd, const struct iovec *iov, int cnt, off_t off) {
  REAL(pwritev64, ssize_t, (int, const struct iovec *, int, off_t));
  if (counted(fd) && take(fd, off, iov_bytes(iov, cnt))) return -1;
  return real_pwritev64(fd, iov, cnt, off);
}

ssize_t pwritev2(int fd, const struct iovec *iov, int cnt, off_t off, int flags) {
  REAL(pwritev2, ssize_t, (int, const struct iovec *, int, off_t, int));
  if (counted(fd) && take(fd, off < 0 ? here(fd) : off, iov_bytes(iov, cnt))) return -1;
  return real_pwritev2(fd, iov, cnt, off, flags);
}

int fallocate(int fd, int mode, off_t off, off_t len) {
  REAL(fallocate, int, (int, int, off_t, off_t));
  if (counted(fd) && getenv("MPMFSI_FULLDISK_NO_RESERVE")) return errno = EOPNOTSUPP, -1;
  /* A punched hole gives nothing back (see above); anything else allocates. */
  if (counted(fd) && !(mode & FALLOC_FL_PUNCH_HOLE) && take(fd, off, (size_t)len)) return -1;
  return real_fallocate(fd, mode, off, len);
}

int posix_fallocate(int fd, off_t off, off_t len) {
  REAL(posix_fallocate, int, (int, off_t, off_t));
  if (counted(fd) && getenv("MPMFSI_FULLDISK_NO_RESERVE")) return EOPNOTSUPP;
  if (counted(fd) && take(fd, off, (size_t)len)) return ENOSPC;
  return real_posix_fallocate(fd, off, len);
}

/* The pages left of the budget (-1 without one). */
static long long pages_left(void) {
  const char *budget = getenv("MPMFSI_FULLDISK_BYTES"),
             *counter = getenv("MPMFSI_FULLDISK_COUNTER");
  if (!budget || !counter) return -1;
  char buf[32] = {0};
  const int cfd = (int)syscall(SYS_openat, AT_FDCWD, counter, O_RDONLY | O_CLOEXEC);
  long long used = 0;
  if (cfd >= 0) {
    if (syscall(SYS_pread64, cfd, buf, sizeof buf - 1, 0L) > 0) used = atoll(buf);
    syscall(SYS_close, cfd);
  }
  const long long left = atoll(budget) / PAGE - used;
  return left > 0 ? left : 0;
}

static void report_left(struct statvfs *fs) {
  const long long left = pages_left();
  if (left < 0 || getenv("MPMFSI_FULLDISK_NO_RESERVE")) return;
  fs->f_frsize = fs->f_bsize = PAGE;
  fs->f_bavail = fs->f_bfree = (fsblkcnt_t)left;
}

int statvfs(const char *path, struct statvfs *fs) {
  REAL(statvfs, int, (const char *, struct statvfs *));
  const int rc = real_statvfs(path, fs);
  char full[PATH_MAX];
  if (rc == 0 && realpath(path, full) && under(full)) report_left(fs);
  return rc;
}

int fstatvfs(int fd, struct statvfs *fs) {
  REAL(fstatvfs, int, (int, struct statvfs *));
  const int rc = real_fstatvfs(fd, fs);
  if (rc == 0 && counted(fd)) report_left(fs);
  return rc;
}
