/* Case-file configuration: reading, overrides, validation messages, getters, instances and
 * the resolved text.
 *
 * Every bad-input test checks the return code and the message: stderr (where mpm_log
 * writes) is redirected to a temporary file around the call and read back, so a test can
 * assert that the one line names the file, the line and the key. */
#define _POSIX_C_SOURCE 200809L

#include "mpm_config.h"
#include "mpm_error.h"

#include <math.h>
#include <mpi.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

static const mpm_key_spec g_keys[] = {
    {"grid.dx", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL, "grid spacing, m", 0, NULL},
    {"grid.n", MPM_KEY_INT, "10", 1, 1000, 0, 0, NULL, "cells per direction", 0, NULL},
    {"grid.periodic", MPM_KEY_BOOL, "false", 0, 0, 0, 0, NULL, "periodic boundaries", 0, NULL},
    {"grid.lo", MPM_KEY_REALS, "0 0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL, "lower corner, m", 0,
     NULL},
    {"run.name", MPM_KEY_STRING, "case", 0, 0, 0, 0, NULL, "run name", 0, NULL},
    {"run.log_level", MPM_KEY_ENUM, "info", 0, 0, 0, 0, "error|warn|info|debug|trace", "log level",
     0, NULL},
    {"time.t_end", MPM_KEY_REAL, "1", 0, HUGE_VAL, 1, 0, NULL, "end time, s", 0, NULL},
    {"geometry.*.type", MPM_KEY_ENUM, NULL, 0, 0, 0, 0, "box|sphere", "region shape", 0, NULL},
    {"geometry.*.lo", MPM_KEY_REALS, "0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL, "lower corner, m", 0,
     NULL},
    {"geometry.*.radius", MPM_KEY_REAL, "1", 0, HUGE_VAL, 1, 0, NULL, "radius, m", 0, NULL},
    {"geometry.*.of", MPM_KEY_NAMES, "none", 0, 0, 0, 0, NULL, "regions to join", 0, NULL},
    {"mesh.scale", MPM_KEY_REAL, "1", 0, HUGE_VAL, 1, 0, NULL, "mesh scale", 0, NULL},
    {"mesh.file", MPM_KEY_PATH, NULL, 0, 0, 0, 0, NULL, "mesh file", 0, NULL},
};
static const int g_nkeys = (int)(sizeof g_keys / sizeof g_keys[0]);

/* ---- capturing the log ------------------------------------------------------------------ */

static int g_saved_fd = -1;
static FILE *g_tmp;
static char *g_log; /* what the last captured call wrote */

static void cap_begin(void) {
  fflush(stderr);
  g_tmp = tmpfile();
  assert_non_null(g_tmp);
  g_saved_fd = dup(STDERR_FILENO);
  assert_true(g_saved_fd >= 0);
  assert_true(dup2(fileno(g_tmp), STDERR_FILENO) >= 0);
}

static void cap_end(void) {
  fflush(stderr);
  dup2(g_saved_fd, STDERR_FILENO);
  close(g_saved_fd);
  long n = lseek(fileno(g_tmp), 0, SEEK_END);
  free(g_log);
  g_log = calloc((size_t)n + 1, 1);
  assert_non_null(g_log);
  lseek(fileno(g_tmp), 0, SEEK_SET);
  assert_int_equal(read(fileno(g_tmp), g_log, (size_t)n), n);
  fclose(g_tmp);
}

static void expect_log(const char *part) {
  if (!strstr(g_log, part)) fail_msg("log lacks \"%s\"; log was:\n%s", part, g_log);
}

static int log_lines(void) {
  int n = 0;
  for (const char *p = g_log; *p; ++p) n += *p == '\n';
  return n;
}

/* ---- fixtures --------------------------------------------------------------------------- */

static mpm_config *new_cfg(void) {
  mpm_config *cfg = NULL;
  assert_int_equal(mpm_config_new(&cfg, MPI_COMM_WORLD), 0);
  assert_int_equal(mpm_config_add_schema(cfg, g_keys, g_nkeys), 0);
  return cfg;
}

/* Read text as "case.ini", then validate; returns validate's code (read must succeed). */
static int read_validate(mpm_config *cfg, const char *text) {
  assert_int_equal(mpm_config_read_string(cfg, text, "case.ini", "."), 0);
  cap_begin();
  int rc = mpm_config_validate(cfg);
  cap_end();
  return rc;
}

/* Read text as "case.ini" and expect a read error whose message contains each part. */
static void expect_read_error(const char *text, const char *part1, const char *part2) {
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_string(cfg, text, "case.ini", ".");
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log(part1);
  if (part2) expect_log(part2);
  mpm_config_destroy(&cfg);
}

/* Read text (which must read cleanly) and expect validation to fail with these parts. */
static void expect_invalid(const char *text, const char *part1, const char *part2) {
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, text), MPM_ERR_INPUT);
  expect_log(part1);
  if (part2) expect_log(part2);
  mpm_config_destroy(&cfg);
}

static char g_dir[] = "/tmp/mpm_test_config_XXXXXX";

static void write_file(const char *path, const char *text, size_t len) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(text, 1, len, f), len);
  fclose(f);
}

/* ---- reading and getters ---------------------------------------------------------------- */

static void test_values_and_defaults(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[grid]\ndx = 0.5\nperiodic = Yes\nlo = 1, 2 3\n"
                                      "[run]\nname = my run\nlog_level = debug\n"),
                   0);
  double dx, lo[3], t;
  int n, per, count;
  const char *s;
  assert_int_equal(mpm_config_get_real(cfg, "grid.dx", &dx), 0);
  assert_true(dx == 0.5);
  assert_int_equal(mpm_config_get_int(cfg, "grid.n", &n), 0);
  assert_int_equal(n, 10);
  assert_int_equal(mpm_config_get_bool(cfg, "grid.periodic", &per), 0);
  assert_int_equal(per, 1);
  assert_int_equal(mpm_config_get_reals(cfg, "grid.lo", lo, 3, &count), 0);
  assert_int_equal(count, 3);
  assert_true(lo[0] == 1 && lo[1] == 2 && lo[2] == 3);
  assert_int_equal(mpm_config_get_string(cfg, "run.name", &s), 0);
  assert_string_equal(s, "my run");
  assert_int_equal(mpm_config_get_string(cfg, "run.log_level", &s), 0);
  assert_string_equal(s, "debug");
  assert_int_equal(mpm_config_get_real(cfg, "time.t_end", &t), 0);
  assert_true(t == 1);
  assert_true(mpm_config_has(cfg, "grid.dx"));
  assert_false(mpm_config_has(cfg, "grid.n"));
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), "case.ini:2");
  assert_string_equal(mpm_config_where(cfg, "run.name"), "case.ini:6");
  assert_string_equal(mpm_config_where(cfg, "grid.n"), "default");
  mpm_config_destroy(&cfg);
  mpm_config_destroy(&cfg); /* NULL is fine */
}

static void test_bools(void **state) {
  (void)state;
  /* The first four are true, the rest false; letter case does not matter. */
  static const char *const words[] = {"true", "YES", "On", "1", "false", "no", "OFF", "0"};
  char text[64];
  for (int i = 0; i < 8; ++i) {
    mpm_config *cfg = new_cfg();
    snprintf(text, sizeof text, "[grid]\ndx = 1\nperiodic = %s\n", words[i]);
    assert_int_equal(read_validate(cfg, text), 0);
    int v = -1;
    assert_int_equal(mpm_config_get_bool(cfg, "grid.periodic", &v), 0);
    assert_int_equal(v, i < 4);
    mpm_config_destroy(&cfg);
  }
  expect_invalid("[grid]\ndx = 1\nperiodic = maybe\n", "case.ini:3: grid.periodic = maybe",
                 "expected true or false");
}

static void test_comments_blanks_crlf_bom(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  const char *text = "\xEF\xBB\xBF# a comment\r\n"
                     "; another\r\n"
                     "  [ grid ]   # header comment\r\n"
                     "    dx = 0.25   # m\r\n"
                     "\tn=20;not a comment\r\n"
                     "\r\n"
                     "[run]\n"
                     "name = a;b # c\n"
                     "log_level =# all comment: empty value\n";
  assert_int_equal(mpm_config_read_string(cfg, text, "case.ini", "."), 0);
  double dx;
  const char *s;
  assert_int_equal(mpm_config_get_real(cfg, "grid.dx", &dx), 0);
  assert_true(dx == 0.25);
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), "case.ini:4");
  assert_int_equal(mpm_config_get_string(cfg, "run.name", &s), 0);
  assert_string_equal(s, "a;b");
  /* "n=20;not..." is an INT that does not parse: the ';' was not after a blank. */
  cap_begin();
  int n, rc = mpm_config_get_int(cfg, "grid.n", &n);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("case.ini:5: grid.n = 20;not a comment: expected a whole number");
  /* An indented line is an ordinary line, not the continuation of a value. */
  assert_string_equal(mpm_config_where(cfg, "grid.n"), "case.ini:5");
  cap_begin();
  rc = mpm_config_get_string(cfg, "run.log_level", &s);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("case.ini:9: run.log_level = : expected one of error|warn|info|debug|trace");
  mpm_config_destroy(&cfg);
}

static void test_long_lines_and_names(void **state) {
  (void)state;
  /* Far beyond inih's 200-byte line buffer and 50-byte section names (names stay within
   * MPM_CONFIG_NAME_MAX). */
  size_t nval = 100000;
  const char *inst = "a_long_instance_name_that_is_longer_than_fifty_bytes_sure"; /* <= 63 */
  char *text = malloc(nval + 512);
  assert_non_null(text);
  int k = sprintf(text, "[run]\nname = ");
  memset(text + k, 'x', nval);
  sprintf(text + k + nval, "\n[geometry.%s]\ntype = box\n[grid]\ndx = 2\n", inst);
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, text), 0);
  const char *s, *const *names;
  int count;
  assert_int_equal(mpm_config_get_string(cfg, "run.name", &s), 0);
  assert_int_equal(strlen(s), nval);
  assert_int_equal(mpm_config_instances(cfg, "geometry", &names, &count), 0);
  assert_int_equal(count, 1);
  assert_string_equal(names[0], inst);
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), "case.ini:6");
  mpm_config_destroy(&cfg);
  free(text);
}

/* ---- bad values ------------------------------------------------------------------------- */

static void test_bad_real(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = abc\n", "case.ini:2: grid.dx = abc: expected a finite real",
                 "(grid spacing, m)");
  expect_invalid("[grid]\ndx = nan\n", "case.ini:2: grid.dx = nan", "finite");
  expect_invalid("[grid]\ndx = inf\n", "case.ini:2: grid.dx = inf", "finite");
  expect_invalid("[grid]\ndx = 1e999\n", "case.ini:2: grid.dx = 1e999", "finite");
  expect_invalid("[grid]\ndx = 1.0 m\n", "case.ini:2: grid.dx = 1.0 m", "finite");
  expect_invalid("[grid]\ndx =\n", "case.ini:2: grid.dx = : expected", NULL);
}

static void test_range(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = -1\n",
                 "error: case.ini:2: grid.dx = -1: must be > 0 (grid "
                 "spacing, m)\n",
                 NULL);
  /* min_exclusive: 0 itself is out. */
  expect_invalid("[grid]\ndx = 0\n", "case.ini:2: grid.dx = 0: must be > 0", NULL);
  expect_invalid("[grid]\ndx = 1\nn = 0\n", "case.ini:3: grid.n = 0: must be in [1, 1000]", NULL);
  expect_invalid("[grid]\ndx = 1\nn = 1001\n", "case.ini:3: grid.n = 1001: must be in [1, 1000]",
                 NULL);
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[grid]\ndx = 1e-300\nn = 1000\n"), 0);
  mpm_config_destroy(&cfg);
}

static void test_bad_int(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = 1\nn = 1.5\n", "case.ini:3: grid.n = 1.5: expected a whole number",
                 "(cells per direction)");
  expect_invalid("[grid]\ndx = 1\nn = ten\n", "case.ini:3: grid.n = ten", "whole number");
  expect_invalid("[grid]\ndx = 1\nn = 99999999999999999999\n", "case.ini:3: grid.n = 9999",
                 "too large");
}

static void test_bad_enum(void **state) {
  (void)state;
  expect_invalid("[run]\nlog_level = loud\n", "case.ini:2: run.log_level = loud",
                 "expected one of error|warn|info|debug|trace");
  expect_invalid("[run]\nlog_level = Info\n", "case.ini:2: run.log_level = Info", "one of");
}

static void test_bad_reals(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = 1\nlo = 1 2 3 4\n", "case.ini:3: grid.lo = 1 2 3 4",
                 "too many values: 4 given, at most 3");
  expect_invalid("[grid]\ndx = 1\nlo = 1 x 3\n", "case.ini:3: grid.lo = 1 x 3",
                 "value 2 ('x') is not a finite real number");
  expect_invalid("[grid]\ndx = 1\nlo = , ,\n", "case.ini:3: grid.lo = , ,", "one or more");
  expect_invalid("[geometry.g]\ntype = box\nof = ,\n", "case.ini:3: geometry.g.of = ,",
                 "one or more names");
}

static void test_paths(void **state) {
  (void)state;
  char sub[256], file[300], text[600];
  snprintf(sub, sizeof sub, "%s/cases", g_dir);
  snprintf(file, sizeof file, "%s/mesh.dat", sub);
  mkdir(sub, 0700);
  write_file(file, "mesh\n", 5);
  /* Relative to the case file's folder. */
  mpm_config *cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = mesh.dat\n", "c.ini", sub), 0);
  cap_begin();
  int rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, 0);
  const char *s;
  assert_int_equal(mpm_config_get_string(cfg, "mesh.file", &s), 0);
  assert_string_equal(s, file);
  mpm_config_destroy(&cfg);
  /* A missing file: the message names the resolved path and the line. */
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = nope.dat\n", "c.ini", sub), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  snprintf(text, sizeof text, "c.ini:2: mesh.file = nope.dat: cannot open '%s/nope.dat'", sub);
  expect_log(text);
  expect_log("No such file or directory");
  mpm_config_destroy(&cfg);
  /* A folder is not a file. */
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = .\n", "c.ini", sub), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("is a folder");
  mpm_config_destroy(&cfg);
  /* From the command line, relative to the current folder, not the case file's. */
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = mesh.dat\n", "c.ini", sub), 0);
  assert_int_equal(mpm_config_override(cfg, "mesh.file=mesh.dat"), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("command line: mesh.file = mesh.dat: cannot open 'mesh.dat'");
  expect_log("current folder");
  cap_begin();
  assert_int_equal(mpm_config_override(cfg, file), MPM_ERR_INPUT); /* no '=' */
  cap_end();
  mpm_config_destroy(&cfg);
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = mesh.dat\n", "c.ini", sub), 0);
  snprintf(text, sizeof text, "mesh.file=%s", file);
  assert_int_equal(mpm_config_override(cfg, text), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, 0);
  mpm_config_destroy(&cfg);
  /* A device (or FIFO) would be read forever: only regular files are data. */
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = /dev/zero\n", "c.ini", sub), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("c.ini:2: mesh.file = /dev/zero: '/dev/zero' is not a regular file");
  mpm_config_destroy(&cfg);
  unlink(file);
  rmdir(sub);
}

/* ---- keys --------------------------------------------------------------------------------- */

static void test_unknown_keys(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = 1\n\n\n\n\ndxx = 2\n",
                 "error: case.ini:7: unknown key 'grid.dxx'; did you mean 'grid.dx'?\n", NULL);
  /* '*' takes the entry's own instance name. */
  expect_invalid("[geometry.block]\ntyp = box\n",
                 "case.ini:2: unknown key 'geometry.block.typ'; did you mean "
                 "'geometry.block.type'?",
                 NULL);
  expect_invalid("[grid]\ndx = 1\nzzzzzzzzzzzz = 2\n",
                 "case.ini:3: unknown key 'grid.zzzzzzzzzzzz'", "[grid] has: dx, n, periodic, lo");
  /* An unknown section: one line for all its keys, with the nearest section or the list. */
  expect_invalid("[nothing]\nzzzzzzzzzzzz = 2\nyy = 3\n",
                 "case.ini:2: unknown section '[nothing]'; the sections are", NULL);
  assert_int_equal(log_lines(), 1);
  expect_invalid("[TIME]\nT_END = 2\n",
                 "case.ini:2: unknown section '[TIME]'; did you mean '[time]'?", NULL);
  expect_invalid("[geometri.block]\ntype = box\nlo = 0 0\n",
                 "case.ini:2: unknown section '[geometri.block]'; did you mean '[geometry.block]'?",
                 NULL);
  /* An instance name over the limit: one line naming it and the limit. */
  char text[200];
  snprintf(text, sizeof text, "[geometry.%0*d]\ntype = box\nlo = 0 0\n", MPM_CONFIG_NAME_MAX + 1,
           7);
  expect_invalid(text,
                 "case.ini:2: the name in '[geometry.0000000000000000...]' is 64 characters long; "
                 "a name may have at most 63",
                 NULL);
  assert_int_equal(log_lines(), 1);
  snprintf(text, sizeof text, "[geometry.%0*d]\ntype = box\n", MPM_CONFIG_NAME_MAX, 7);
  mpm_config *ok = new_cfg();
  assert_int_equal(read_validate(ok, text), 0);
  mpm_config_destroy(&ok);
  expect_invalid("[geometry]\ntype = box\n",
                 "case.ini:2: section '[geometry]' needs a name: write '[geometry.NAME]'", NULL);
}

static void test_required_instance_key(void **state) {
  (void)state;
  expect_invalid("[grid]\ndx = 1\n[geometry.block]\nlo = 0 0\n",
                 "case.ini:4: [geometry.block] lacks the required key 'type' (region shape)",
                 "add 'type = ...'");
  /* A section in use needs its required keys too; an unused one does not. */
  expect_invalid("[grid]\nn = 3\n", "case.ini:2: [grid] lacks the required key 'dx'", NULL);
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[run]\nname = x\n"), 0);
  double dx;
  cap_begin();
  int rc = mpm_config_get_real(cfg, "grid.dx", &dx);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("missing required key 'grid.dx' (grid spacing, m); add 'dx = ...' under [grid]");
  mpm_config_destroy(&cfg);
}

static void test_duplicates(void **state) {
  (void)state;
  expect_read_error("[grid]\ndx = 1\nn = 2\ndx = 3\n",
                    "case.ini:4: grid.dx is set twice (lines 2 and 4)", NULL);
  /* The same key through a dotted name and a dotted section. */
  expect_read_error("[geometry]\nb.type = box\n[geometry.b]\ntype = sphere\n",
                    "case.ini:4: geometry.b.type is set twice (lines 2 and 4)", NULL);
  /* A second source replaces a value: that is not a duplicate. */
  mpm_config *cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[grid]\ndx = 1\n", "a.ini", "."), 0);
  assert_int_equal(mpm_config_read_string(cfg, "[grid]\n\ndx = 2\n", "b.ini", "."), 0);
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), "b.ini:3");
  mpm_config_destroy(&cfg);
}

static void test_syntax_errors(void **state) {
  (void)state;
  expect_read_error("dx = 1\n[grid]\n",
                    "case.ini:1: key 'dx' is outside any section; put it under a [section]", NULL);
  expect_read_error("[grid]\ndx 1\n", "case.ini:2: syntax error: expected 'key = value'",
                    "got 'dx 1'");
  expect_read_error("[grid]\ndx: 1\n", "case.ini:2: syntax error", "dx: 1");
  expect_read_error("[grid\ndx = 1\n", "case.ini:1: syntax error: '[' without a closing ']'", NULL);
  expect_read_error("[grid] x\n", "case.ini:1: syntax error: unexpected text after ']'", NULL);
  expect_read_error("[gr id]\n", "case.ini:1: syntax error: bad section name '[gr id]'", NULL);
  expect_read_error("[grid..x]\n", "case.ini:1: syntax error: bad section name", NULL);
  expect_read_error("[]\n", "case.ini:1: syntax error: bad section name '[]'", NULL);
  expect_read_error("[grid]\n= 1\n", "case.ini:2: syntax error: no key before '='", NULL);
  expect_read_error("[grid]\nd x = 1\n", "case.ini:2: syntax error: bad key 'd x'", NULL);
  expect_read_error("[grid]\n\xC3\xA9t\xC3\xA9 = 1\n", "case.ini:2: syntax error: bad key", NULL);
  /* Every bad line is reported, and the keys under a bad header are skipped quietly. */
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_string(cfg, "[grid]\nx\ny\n[b c]\nq = 1\n[run]\nname = ok\n", "case.ini",
                                  ".");
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("case.ini:2:");
  expect_log("case.ini:3:");
  expect_log("case.ini:4:");
  assert_int_equal(log_lines(), 3);
  assert_true(mpm_config_has(cfg, "run.name"));
  mpm_config_destroy(&cfg);
}

static void test_validate_reports_all(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[grid]\ndx = -1\nn = x\nlo = 1 2 3 4 5\nfoo = 1\n"
                                      "[geometry.a]\nlo = 1\n[run]\nlog_level = x\n"),
                   MPM_ERR_INPUT);
  expect_log("case.ini:2: grid.dx");
  expect_log("case.ini:3: grid.n");
  expect_log("case.ini:4: grid.lo");
  expect_log("case.ini:5: unknown key 'grid.foo'");
  expect_log("case.ini:7: [geometry.a] lacks the required key 'type'");
  expect_log("case.ini:9: run.log_level");
  assert_int_equal(log_lines(), 6);
  mpm_config_destroy(&cfg);
}

/* ---- files ---------------------------------------------------------------------------- */

static void test_read_file(void **state) {
  (void)state;
  char path[300], mesh[300], text[700];
  snprintf(path, sizeof path, "%s/case.ini", g_dir);
  snprintf(mesh, sizeof mesh, "%s/m.dat", g_dir);
  write_file(mesh, "x", 1);
  const char *body = "[grid]\ndx = 0.1\n[mesh]\nfile = m.dat\n";
  write_file(path, body, strlen(body));
  mpm_config *cfg = new_cfg();
  assert_int_equal(mpm_config_read_file(cfg, path), 0);
  cap_begin();
  int rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, 0);
  snprintf(text, sizeof text, "%s:2", path);
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), text);
  const char *s;
  assert_int_equal(mpm_config_get_string(cfg, "mesh.file", &s), 0);
  assert_string_equal(s, mesh);
  mpm_config_destroy(&cfg);
  unlink(mesh);
  unlink(path);
}

static void test_missing_file(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_file(cfg, "/nonexistent/dir/case.ini");
  cap_end();
  assert_int_equal(rc, MPM_ERR_FILE);
  expect_log("cannot read case file '/nonexistent/dir/case.ini': No such file or directory; "
             "check the path");
  cap_begin();
  rc = mpm_config_read_file(cfg, g_dir);
  cap_end();
  assert_int_equal(rc, MPM_ERR_FILE);
  expect_log(": cannot read it as a case file: it is a folder; give the path of a case file");
  assert_int_equal(log_lines(), 1);
  mpm_config_destroy(&cfg);
}

/* A device, a FIFO or a huge file is no case file: refused at once, without reading it
 * (a FIFO without a writer would block the open, /dev/zero would never end). */
static void test_not_a_case_file(void **state) {
  (void)state;
  char fifo[300], big[300];
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_file(cfg, "/dev/zero");
  cap_end();
  assert_int_equal(rc, MPM_ERR_FILE);
  expect_log("error: /dev/zero: cannot read it as a case file: it is a character device; give "
             "the path of a case file\n");
  assert_int_equal(log_lines(), 1);
  snprintf(fifo, sizeof fifo, "%s/pipe.ini", g_dir);
  assert_int_equal(mkfifo(fifo, 0600), 0);
  cap_begin();
  rc = mpm_config_read_file(cfg, fifo);
  cap_end();
  assert_int_equal(rc, MPM_ERR_FILE);
  expect_log("pipe.ini: cannot read it as a case file: it is a FIFO");
  unlink(fifo);
  /* 17 MiB of valid-looking text: over the size limit. */
  snprintf(big, sizeof big, "%s/big.ini", g_dir);
  FILE *f = fopen(big, "w");
  assert_non_null(f);
  for (int k = 0; k < 17 * 1024; ++k) {
    char line[1024];
    memset(line, ' ', sizeof line);
    memcpy(line, "# ", 2);
    line[sizeof line - 1] = '\n';
    assert_int_equal(fwrite(line, 1, sizeof line, f), sizeof line);
  }
  fclose(f);
  cap_begin();
  rc = mpm_config_read_file(cfg, big);
  cap_end();
  assert_int_equal(rc, MPM_ERR_FILE);
  expect_log("big.ini: cannot read it as a case file: it is larger than 16 MiB");
  unlink(big);
  mpm_config_destroy(&cfg);
}

/* Garbage gives a screenful of errors, then one line counting the rest. */
static void test_error_cap(void **state) {
  (void)state;
  size_t n = 0;
  char *text = malloc(1000 * 16);
  assert_non_null(text);
  for (int k = 0; k < 1000; ++k) n += (size_t)sprintf(text + n, "garbage %d\n", k);
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_string(cfg, text, "junk.ini", ".");
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  assert_int_equal(log_lines(), 21);
  expect_log("error: junk.ini:20: syntax error");
  expect_log("error: ... and 980 more errors in junk.ini; fix the ones above first\n");
  mpm_config_destroy(&cfg);
  /* Validation too: 30 unknown keys and a missing one give 20 lines and the count. */
  n = (size_t)sprintf(text, "[grid]\n");
  for (int k = 0; k < 30; ++k) n += (size_t)sprintf(text + n, "zz%d = 1\n", k);
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, text, "junk.ini", "."), 0);
  cap_begin();
  rc = mpm_config_validate(cfg);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  assert_int_equal(log_lines(), 21);
  expect_log("error: ... and 11 more errors in junk.ini; fix the ones above first\n");
  mpm_config_destroy(&cfg);
  /* More keys than any case file has: refused, and reading stops there. */
  free(text);
  text = malloc(12000 * 16);
  assert_non_null(text);
  n = (size_t)sprintf(text, "[grid]\n");
  for (int k = 0; k < 12000; ++k) n += (size_t)sprintf(text + n, "k%d = 1\n", k);
  cfg = new_cfg();
  cap_begin();
  rc = mpm_config_read_string(cfg, text, "many.ini", ".");
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log("error: many.ini:10002: more than 10000 keys");
  assert_int_equal(log_lines(), 1);
  mpm_config_destroy(&cfg);
  free(text);
}

static void test_nul_in_file(void **state) {
  (void)state;
  char path[300];
  snprintf(path, sizeof path, "%s/bin.ini", g_dir);
  write_file(path, "[grid]\ndx = 1\n\0junk\n", 20);
  mpm_config *cfg = new_cfg();
  cap_begin();
  int rc = mpm_config_read_file(cfg, path);
  cap_end();
  assert_int_equal(rc, MPM_ERR_INPUT);
  expect_log(":3: contains a NUL byte");
  mpm_config_destroy(&cfg);
  unlink(path);
}

/* ---- overrides ------------------------------------------------------------------------ */

static void test_overrides(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[grid]\ndx = 1\n", "case.ini", "."), 0);
  const char *before;
  assert_int_equal(mpm_config_get_string(cfg, "run.name", &before), 0);
  assert_int_equal(mpm_config_override(cfg, "  grid.dx =  3   # a comment"), 0);
  assert_int_equal(mpm_config_override(cfg, "run.name = a = b"), 0);
  assert_int_equal(mpm_config_override(cfg, "geometry.g.type=sphere"), 0);
  double dx;
  const char *s;
  assert_int_equal(mpm_config_get_real(cfg, "grid.dx", &dx), 0);
  assert_true(dx == 3);
  assert_string_equal(mpm_config_where(cfg, "grid.dx"), "command line");
  assert_int_equal(mpm_config_get_string(cfg, "run.name", &s), 0);
  assert_string_equal(s, "a = b");
  assert_string_equal(before, "case"); /* earlier results stay valid */
  cap_begin();
  assert_int_equal(mpm_config_validate(cfg), 0);
  cap_end();
  static const char *const bad[] = {"grid.dx",    "=3",           "dx=1", "grid..dx=1",
                                    "grid.d x=1", "grid.dx=1\n2", ""};
  for (int i = 0; i < 7; ++i) {
    cap_begin();
    int rc = mpm_config_override(cfg, bad[i]);
    cap_end();
    assert_int_equal(rc, MPM_ERR_INPUT);
    expect_log("command line: expected key=value, got '");
    assert_int_equal(log_lines(), 1);
  }
  /* The command line is one source, like a file: a key given twice there is an error that
   * names both assignments, as a file names both lines. */
  cap_begin();
  assert_int_equal(mpm_config_override(cfg, "grid.dx=4"), MPM_ERR_INPUT);
  cap_end();
  expect_log("error: command line: grid.dx is given twice (grid.dx=3 and grid.dx=4); keep one\n");
  assert_int_equal(log_lines(), 1);
  mpm_config_destroy(&cfg);
  /* An override with a bad value is caught by validate, naming the command line. */
  cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[grid]\ndx = 1\n", "case.ini", "."), 0);
  assert_int_equal(mpm_config_override(cfg, "grid.dx=-4"), 0);
  cap_begin();
  assert_int_equal(mpm_config_validate(cfg), MPM_ERR_INPUT);
  cap_end();
  expect_log("command line: grid.dx = -4: must be > 0");
  mpm_config_destroy(&cfg);
}

/* ---- instances, where, fail ----------------------------------------------------------- */

static void test_instances(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[geometry.b]\ntype = box\n[geometry.a]\ntype = sphere\n"
                                      "radius = 2\n[geometry.b]\nlo = 1 2\n"),
                   0);
  const char *const *names, *const *again;
  int count;
  assert_int_equal(mpm_config_instances(cfg, "geometry", &names, &count), 0);
  assert_int_equal(count, 2);
  assert_string_equal(names[0], "b");
  assert_string_equal(names[1], "a");
  assert_int_equal(mpm_config_instances(cfg, "geometry", &again, &count), 0);
  assert_ptr_equal(names, again); /* cached, not rebuilt */
  assert_int_equal(mpm_config_override(cfg, "geometry.c.type=box"), 0);
  assert_int_equal(mpm_config_instances(cfg, "geometry", &again, &count), 0);
  assert_int_equal(count, 3);
  assert_string_equal(again[2], "c");
  assert_string_equal(names[1], "a"); /* the earlier list is still valid */
  assert_int_equal(mpm_config_instances(cfg, "grid", &names, &count), 0);
  assert_int_equal(count, 0);
  double r;
  assert_int_equal(mpm_config_get_real(cfg, "geometry.a.radius", &r), 0);
  assert_true(r == 2);
  assert_int_equal(mpm_config_get_real(cfg, "geometry.b.radius", &r), 0);
  assert_true(r == 1);
  assert_string_equal(mpm_config_where(cfg, "geometry.a.radius"), "case.ini:5");
  assert_string_equal(mpm_config_where(cfg, "geometry.b.lo"), "case.ini:7");
  assert_string_equal(mpm_config_where(cfg, "geometry.b.radius"), "default");
  mpm_config_destroy(&cfg);
}

static void test_fail(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[grid]\ndx = 1\n[geometry.g]\ntype = box\n"), 0);
  cap_begin();
  assert_int_equal(mpm_config_fail(cfg, "grid.dx", "too coarse for %d cells", 3), MPM_ERR_INPUT);
  assert_int_equal(mpm_config_fail(cfg, "grid.n", "not a power of two"), MPM_ERR_INPUT);
  assert_int_equal(mpm_config_fail(cfg, "geometry.g", "is empty"), MPM_ERR_INPUT);
  assert_int_equal(mpm_config_fail(cfg, "geometry.g.radius", "is %s", "odd"), MPM_ERR_INPUT);
  assert_int_equal(mpm_config_fail(cfg, "solid", "no bodies"), MPM_ERR_INPUT);
  cap_end();
  expect_log("error: case.ini:2: grid.dx = 1: too coarse for 3 cells\n");
  /* A default is located by its section. */
  expect_log("error: case.ini:2: grid.n = 10 (default): not a power of two\n");
  expect_log("error: case.ini:4: [geometry.g]: is empty\n");
  expect_log("error: case.ini:4: geometry.g.radius = 1 (default): is odd\n");
  expect_log("error: solid: no bodies\n");
  mpm_config_destroy(&cfg);
}

static void test_getter_errors(void **state) {
  (void)state;
  mpm_config *cfg = new_cfg();
  assert_int_equal(read_validate(cfg, "[grid]\ndx = 1\nlo = 1 2 3\n"), 0);
  double v[2];
  int n, count;
  cap_begin();
  assert_int_equal(mpm_config_get_real(cfg, "grid.nope", v), MPM_ERR_INPUT);
  assert_int_equal(mpm_config_get_int(cfg, "grid.dx", &n), MPM_ERR_INTERNAL);
  assert_int_equal(mpm_config_get_reals(cfg, "grid.lo", v, 2, &count), MPM_ERR_INPUT);
  cap_end();
  expect_log("'grid.nope' is not a key of the schema");
  expect_log("'grid.dx' is a real key");
  expect_log("case.ini:3: grid.lo = 1 2 3: too many values: at most 2 are read");
  /* A REAL key can be read as reals, an INT as a real. */
  assert_int_equal(mpm_config_get_reals(cfg, "grid.dx", v, 2, &count), 0);
  assert_int_equal(count, 1);
  assert_int_equal(mpm_config_get_real(cfg, "grid.n", v), 0);
  assert_true(v[0] == 10);
  mpm_config_destroy(&cfg);
}

static void test_bad_schema(void **state) {
  (void)state;
  static const mpm_key_spec bad_default[] = {
      {"a.x", MPM_KEY_REAL, "abc", 0, 1, 0, 0, NULL, "x", 0, NULL}};
  static const mpm_key_spec no_section[] = {
      {"x", MPM_KEY_REAL, "1", 0, 1, 0, 0, NULL, "x", 0, NULL}};
  static const mpm_key_spec star_last[] = {
      {"a.*", MPM_KEY_REAL, "1", 0, 1, 0, 0, NULL, "x", 0, NULL}};
  static const mpm_key_spec no_choices[] = {
      {"a.e", MPM_KEY_ENUM, "x", 0, 0, 0, 0, NULL, "e", 0, NULL}};
  static const mpm_key_spec out_of_range[] = {
      {"a.y", MPM_KEY_INT, "5", 0, 1, 0, 0, NULL, "y", 0, NULL}};
  const mpm_key_spec *tables[] = {bad_default, no_section,   star_last,
                                  no_choices,  out_of_range, g_keys};
  for (int i = 0; i < 6; ++i) {
    mpm_config *cfg = new_cfg(); /* g_keys already in: adding them again is a duplicate */
    cap_begin();
    int rc = mpm_config_add_schema(cfg, tables[i], 1);
    cap_end();
    assert_int_equal(rc, MPM_ERR_INTERNAL);
    expect_log("schema key");
    mpm_config_destroy(&cfg);
  }
}

/* ---- resolved text --------------------------------------------------------------------- */

/* The text without "   # where" comments, which name the source and so differ. */
static char *strip_comments(const char *text) {
  char *out = malloc(strlen(text) + 1), *o = out;
  assert_non_null(out);
  while (*text) {
    const char *eol = strchr(text, '\n'), *c = strstr(text, "   # ");
    size_t n = eol ? (size_t)(eol - text) : strlen(text);
    if (c && c < text + n) n = (size_t)(c - text);
    if (text[0] == '#') n = 0;
    memcpy(o, text, n), o += n, *o++ = '\n';
    text = eol ? eol + 1 : text + strlen(text);
  }
  *o = '\0';
  return out;
}

static void test_resolved_round_trip(void **state) {
  (void)state;
  char mesh[300];
  snprintf(mesh, sizeof mesh, "%s/mesh.dat", g_dir);
  write_file(mesh, "x", 1);
  mpm_config *a = new_cfg(), *b = new_cfg();
  assert_int_equal(mpm_config_read_string(a,
                                          "[grid]\ndx = 0.5 # m\nlo = 1,2 , 3\n"
                                          "[geometry.zeta]\ntype = sphere\nradius = 3\n"
                                          "[geometry.alpha]\ntype = box\nof = zeta, x\n"
                                          "[mesh]\nfile = mesh.dat\n[run]\nname = my  run\n",
                                          "case.ini", g_dir),
                   0);
  assert_int_equal(mpm_config_override(a, "time.t_end = 2.5"), 0);
  assert_int_equal(mpm_config_override(a, "run.log_level=debug"), 0);
  cap_begin();
  assert_int_equal(mpm_config_validate(a), 0);
  cap_end();
  char *ta = NULL, *tb = NULL;
  assert_int_equal(mpm_config_resolved_text(a, &ta), 0);
  /* Defaults are comments: read back, they stay unset. */
  assert_non_null(strstr(ta, "[grid]\ndx = 0.5   # case.ini:2\n# n = 10   # default\n"));
  assert_non_null(strstr(ta, "t_end = 2.5   # command line\n"));
  assert_non_null(strstr(ta, "[geometry.zeta]\n"));
  assert_true(strstr(ta, "[geometry.zeta]") < strstr(ta, "[geometry.alpha]"));
  assert_non_null(strstr(ta, "[mesh]\n# scale = 1   # default\nfile = /"));
  /* Fed back in, it gives the same configuration and the same text. */
  cap_begin();
  int rc = mpm_config_read_string(b, ta, "resolved.ini", "/nonexistent");
  if (!rc) rc = mpm_config_validate(b);
  cap_end();
  assert_int_equal(rc, 0);
  assert_int_equal(mpm_config_resolved_text(b, &tb), 0);
  char *sa = strip_comments(ta), *sb = strip_comments(tb);
  assert_string_equal(sa, sb);
  /* The provenance comments are kept too: the same text, byte for byte. */
  assert_string_equal(ta, tb);
  assert_false(mpm_config_has(b, "grid.n"));
  assert_false(mpm_config_has(b, "geometry.alpha.radius"));
  assert_string_equal(mpm_config_where(b, "grid.dx"), "resolved.ini:4");
  for (int i = 0; i < g_nkeys; ++i) {
    const char *key = g_keys[i].key;
    char inst[64];
    if (strchr(key, '*'))
      snprintf(inst, sizeof inst, "geometry.alpha.%s", strrchr(key, '.') + 1);
    else
      snprintf(inst, sizeof inst, "%s", key);
    double x, y;
    const char *s, *t;
    switch (g_keys[i].type) {
    case MPM_KEY_REAL:
      assert_int_equal(mpm_config_get_real(a, inst, &x), 0);
      assert_int_equal(mpm_config_get_real(b, inst, &y), 0);
      assert_true(x == y);
      break;
    case MPM_KEY_PATH:
      assert_int_equal(mpm_config_get_string(a, inst, &s), 0);
      assert_int_equal(mpm_config_get_string(b, inst, &t), 0);
      assert_string_equal(t, mesh); /* written absolute */
      assert_string_equal(s, mesh);
      break;
    case MPM_KEY_STRING:
    case MPM_KEY_ENUM:
    case MPM_KEY_NAMES:
      assert_int_equal(mpm_config_get_string(a, inst, &s), 0);
      assert_int_equal(mpm_config_get_string(b, inst, &t), 0);
      assert_string_equal(s, t);
      break;
    default:
      break;
    }
  }
  const char *const *na, *const *nb;
  int ca, cb;
  assert_int_equal(mpm_config_instances(a, "geometry", &na, &ca), 0);
  assert_int_equal(mpm_config_instances(b, "geometry", &nb, &cb), 0);
  assert_int_equal(ca, 2);
  assert_int_equal(cb, 2);
  assert_string_equal(nb[0], "zeta");
  assert_string_equal(nb[1], "alpha");
  free(sa), free(sb), free(ta), free(tb);
  mpm_config_destroy(&a);
  mpm_config_destroy(&b);
  unlink(mesh);
}

/* A case with a relative folder: paths become absolute through the current folder. */
static void test_resolved_relative_dir(void **state) {
  (void)state;
  char cwd[512], mesh[300], want[900];
  assert_non_null(getcwd(cwd, sizeof cwd));
  snprintf(mesh, sizeof mesh, "%s/mesh.dat", g_dir);
  write_file(mesh, "x", 1);
  assert_int_equal(chdir(g_dir), 0);
  mpm_config *cfg = new_cfg();
  assert_int_equal(mpm_config_read_string(cfg, "[mesh]\nfile = mesh.dat\n", "c.ini", "."), 0);
  char *t = NULL;
  assert_int_equal(mpm_config_resolved_text(cfg, &t), 0);
  snprintf(want, sizeof want, "file = %s/mesh.dat   # c.ini:2\n", g_dir);
  assert_non_null(strstr(t, want));
  free(t);
  mpm_config_destroy(&cfg);
  assert_int_equal(chdir(cwd), 0);
  unlink(mesh);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  if (!mkdtemp(g_dir)) return 1;
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_values_and_defaults),
      cmocka_unit_test(test_bools),
      cmocka_unit_test(test_comments_blanks_crlf_bom),
      cmocka_unit_test(test_long_lines_and_names),
      cmocka_unit_test(test_bad_real),
      cmocka_unit_test(test_range),
      cmocka_unit_test(test_bad_int),
      cmocka_unit_test(test_bad_enum),
      cmocka_unit_test(test_bad_reals),
      cmocka_unit_test(test_paths),
      cmocka_unit_test(test_unknown_keys),
      cmocka_unit_test(test_required_instance_key),
      cmocka_unit_test(test_duplicates),
      cmocka_unit_test(test_syntax_errors),
      cmocka_unit_test(test_validate_reports_all),
      cmocka_unit_test(test_read_file),
      cmocka_unit_test(test_missing_file),
      cmocka_unit_test(test_not_a_case_file),
      cmocka_unit_test(test_error_cap),
      cmocka_unit_test(test_nul_in_file),
      cmocka_unit_test(test_overrides),
      cmocka_unit_test(test_instances),
      cmocka_unit_test(test_fail),
      cmocka_unit_test(test_getter_errors),
      cmocka_unit_test(test_bad_schema),
      cmocka_unit_test(test_resolved_round_trip),
      cmocka_unit_test(test_resolved_relative_dir),
  };
  int failed = cmocka_run_group_tests(tests, NULL, NULL);
  rmdir(g_dir);
  free(g_log);
  MPI_Finalize();
  return failed ? 1 : 0;
}
