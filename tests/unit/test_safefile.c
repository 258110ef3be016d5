/* Writers never write through a link (mpm_safefile.h), tested below the output folder's claim
 * (which refuses or removes such links first): links planted at a checkpoint's final and
 * temporary names and at Open MPI's lock-test names, and at a CSV's names, leave their
 * targets as they were, existing or not. On 1 and 2 ranks. Usage: test_safefile DIR. */
#define _DEFAULT_SOURCE /* symlink, mkdtemp */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "mpm_diag.h"
#include "mpm_error.h"
#include "mpm_log.h"
#include "mpm_output.h"
#include "mpm_rundir.h"
#include "mpm_safefile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int g_rank, g_size;
static char g_dir[2048], g_victims[2048];
static const char g_precious[] = "precious: never to be written by mpmfsi\n";

static void join(char *buf, size_t n, const char *dir, const char *name) {
  snprintf(buf, n, "%s/%s", dir, name);
}

/* A file at path holding g_precious, which mpmfsi must never write. */
static void make_victim(const char *path) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(g_precious, f);
  fclose(f);
}

/* dir/name -> victims/target; the target is made (holding g_precious) if exists. Rank 0. */
static void plant(const char *name, const char *target, int exists) {
  char link[4200], to[4200];
  join(link, sizeof link, g_dir, name);
  join(to, sizeof to, g_victims, target);
  if (exists) make_victim(to);
  unlink(link);
  assert_int_equal(symlink(to, link), 0);
}

/* The target is as planted: g_precious if it existed, absent if not. */
static void assert_untouched(const char *target, int exists) {
  char to[4200], buf[256] = "";
  join(to, sizeof to, g_victims, target);
  FILE *f = fopen(to, "r");
  if (!exists) {
    assert_null(f);
    return;
  }
  assert_non_null(f);
  const size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = 0;
  assert_string_equal(buf, g_precious);
}

static void assert_regular(const char *name) {
  char path[4200];
  struct stat st;
  join(path, sizeof path, g_dir, name);
  assert_int_equal(lstat(path, &st), 0);
  assert_true(S_ISREG(st.st_mode));
}

static void test_checkpoint_links(void **state) {
  (void)state;
  if (g_rank == 0) {
    plant("ck.h5", "final", 1);
    plant("ck.h5.tmp", "tmp", 1);
    plant("ck.h5.tmp.locktest.0", "locktest0", 0);
    plant("ck.h5.tmp.locktest.1", "locktest1", 0);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  char path[4200];
  join(path, sizeof path, g_dir, "ck.h5");
  const char *names[1] = {"t"};
  const double values[1] = {0.5};
  assert_int_equal(
      mpm_checkpoint_write(MPI_COMM_WORLD, path, "[run]\n", names, values, 1, NULL, NULL, 0), 0);
  if (g_rank == 0) {
    assert_untouched("final", 1);
    assert_untouched("tmp", 1);
    assert_untouched("locktest0", 0);
    assert_untouched("locktest1", 0);
    assert_regular("ck.h5");
  }
  mpm_checkpoint *ck = NULL;
  double t = 0;
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path), 0);
  assert_int_equal(mpm_checkpoint_attr(ck, "t", &t), 0);
  assert_true(t == 0.5);
  mpm_checkpoint_close(&ck);
  MPI_Barrier(MPI_COMM_WORLD);
}

static void test_csv_links(void **state) {
  (void)state;
  if (g_rank == 0) {
    plant("a.csv", "a", 1);
    plant("b.csv.tmp", "btmp", 0);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const char *cols[2] = {"t", "x"};
  const double row[2] = {1, 2};
  char path[4200];
  for (int k = 0; k < 2; ++k) {
    mpm_diag *d = NULL;
    join(path, sizeof path, g_dir, k ? "b.csv" : "a.csv");
    assert_int_equal(mpm_diag_open(&d, MPI_COMM_WORLD, path, 2, cols, 0, 0), 0);
    assert_int_equal(mpm_diag_row(d, row), 0);
    mpm_diag_close(&d);
  }
  if (g_rank == 0) {
    assert_untouched("a", 1);
    assert_untouched("btmp", 0);
    assert_regular("a.csv");
    assert_regular("b.csv");
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

/* A file continued in place refuses a link; the claim's checks find one by name. */
static void test_in_place_and_check(void **state) {
  (void)state;
  if (g_rank != 0) return;
  plant("run.log", "log", 0);
  char path[4200], why[1024];
  join(path, sizeof path, g_dir, "run.log");
  errno = 0;
  assert_int_equal(mpm_file_open_fd(path, O_WRONLY | O_CREAT | O_APPEND), -1);
  assert_int_equal(errno, ELOOP);
  assert_untouched("log", 0);
  assert_int_equal(mpm_rundir_check_dir(g_dir, 0, why, sizeof why), MPM_ERR_INPUT);
  assert_non_null(strstr(why, "is a symbolic link; mpmfsi does not write through links"));
  assert_int_equal(mpm_rundir_check_dir(g_dir, 1, why, sizeof why), 0);
}

/* A hard link planted at a file written in place (run.log, .lock) is refused before anything of
 * it is cut: the other name may be anywhere on the same file system. Our own file, with one
 * name, is truncated as asked. */
static void test_hard_link(void **state) {
  (void)state;
  if (g_rank != 0) return;
  char path[4200], to[4200];
  join(path, sizeof path, g_dir, "run.log");
  join(to, sizeof to, g_victims, "hard");
  make_victim(to);
  unlink(path);
  assert_int_equal(link(to, path), 0);
  errno = 0;
  assert_int_equal(mpm_file_open_fd(path, O_WRONLY | O_CREAT | O_TRUNC), -1);
  assert_int_equal(errno, EMLINK);
  assert_untouched("hard", 1);
  assert_int_equal(unlink(path), 0);
  const int fd = mpm_file_open_fd(path, O_WRONLY | O_CREAT | O_TRUNC);
  assert_true(fd >= 0);
  assert_int_equal(write(fd, "x", 1), 1);
  close(fd);
  const int again = mpm_file_open_fd(path, O_WRONLY | O_CREAT | O_TRUNC);
  struct stat st;
  assert_true(again >= 0);
  assert_int_equal(fstat(again, &st), 0);
  assert_int_equal((int)st.st_size, 0);
  close(again);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  snprintf(g_dir, sizeof g_dir, "%s/out", argc > 1 ? argv[1] : "test_safefile_dir");
  snprintf(g_victims, sizeof g_victims, "%s/victims", argc > 1 ? argv[1] : "test_safefile_dir");
  if (g_rank == 0) {
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' '%s'", g_dir, g_victims);
    if (system(cmd) != 0) return 1;
    mkdir(argc > 1 ? argv[1] : "test_safefile_dir", 0777);
    mkdir(g_dir, 0777);
    mkdir(g_victims, 0777);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_checkpoint_links),
      cmocka_unit_test(test_csv_links),
      cmocka_unit_test(test_in_place_and_check),
      cmocka_unit_test(test_hard_link),
  };
  const int failed = cmocka_run_group_tests(tests, NULL, NULL);
  int any = failed;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any ? 1 : 0;
}
