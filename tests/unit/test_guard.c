/* The blow-up guard (coupler/mpm_guard.c) on step and energy sequences, with its defaults
 * read from the schema as a run reads them.
 *
 * The default time.collapse_ratio is 1e-3: on RAE 2822 with a subsonic_outflow face
 * (2026-11-29) a run's step fell to 3e-4 - 8e-4 of its starting CFL step and stayed there for
 * 60000 steps (t = 13.0 to 13.9 of 24) under the earlier default of 1e-4, which never fired.
 * The tests pin what the default must stop (a streak at 5e-4) and what it must let run (steps
 * at 1e-2 of the CFL step, which error-controlled pairs take in a contact, and 2e-3). */
#include "mpm_error.h"
#include "mpm_guard.h"
#include "mpm_log.h"

#include <math.h>
#include <mpi.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#include <cmocka.h>

static const double H0 = 1e-2, E0 = 1.0; /* starting CFL step and total energy */

/* A guard with the schema's defaults and the given overrides (NULL-terminated). */
static void guard_with(mpm_guard *g, mpm_config **cfg, const char *const *over) {
  assert_int_equal(mpm_config_new(cfg, MPI_COMM_WORLD), 0);
  assert_int_equal(mpm_config_add_schema(*cfg, mpm_guard_keys, mpm_guard_nkeys), 0);
  for (int k = 0; over && over[k]; ++k) assert_int_equal(mpm_config_override(*cfg, over[k]), 0);
  assert_int_equal(mpm_guard_init(g, *cfg, H0, E0), 0);
}

/* Steps of h at constant energy from step `from`; returns the step that failed, or 0. */
static long run_steps(mpm_guard *g, long from, long count, double h, int cut_short) {
  for (long k = 0; k < count; ++k)
    if (mpm_guard_check(g, (double)(from + k) * h, from + k, h, cut_short, E0) != 0)
      return from + k;
  return 0;
}

static void test_default_stops_slow_collapse(void **state) {
  (void)state;
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  guard_with(&g, &cfg, NULL);
  assert_int_equal(run_steps(&g, 1, 50, H0, 0), 0);
  /* 99 collapsed steps, one ordinary step (the streak restarts), then the 100th in a row */
  assert_int_equal(run_steps(&g, 51, 99, 5e-4 * H0, 0), 0);
  assert_int_equal(run_steps(&g, 150, 1, H0, 0), 0);
  assert_int_equal(run_steps(&g, 151, 99, 5e-4 * H0, 0), 0);
  assert_int_equal(run_steps(&g, 250, 1, 5e-4 * H0, 0), 250);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
}

static void test_default_lets_small_steps_run(void **state) {
  (void)state;
  const double ratio[] = {1e-2, 2e-3};
  for (int r = 0; r < 2; ++r) {
    mpm_guard g = {0};
    mpm_config *cfg = NULL;
    guard_with(&g, &cfg, NULL);
    assert_int_equal(run_steps(&g, 1, 5000, ratio[r] * H0, 0), 0);
    mpm_guard_free(&g);
    mpm_config_destroy(&cfg);
  }
}

static void test_cut_short_steps_neither_count_nor_break(void **state) {
  (void)state;
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  const char *const over[] = {"time.collapse_steps=10", NULL};
  guard_with(&g, &cfg, over);
  assert_int_equal(run_steps(&g, 1, 9, 1e-4 * H0, 0), 0);
  assert_int_equal(run_steps(&g, 10, 50, 1e-6 * H0, 1), 0); /* landing on output times */
  assert_int_equal(run_steps(&g, 60, 1, 1e-4 * H0, 0), 60);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
}

static void test_off_and_energy(void **state) {
  (void)state;
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  const char *const off[] = {"time.collapse_ratio=0", NULL};
  guard_with(&g, &cfg, off);
  assert_int_equal(run_steps(&g, 1, 1000, 1e-8 * H0, 0), 0);
  assert_int_equal(mpm_guard_check(&g, 1.0, 1001, H0, 0, NAN), MPM_ERR_UNPHYSICAL);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
  /* geometric growth: 1.5 per step passes time.energy_growth = 1000 over half the run */
  guard_with(&g, &cfg, NULL);
  double e = E0;
  long failed = 0;
  for (long k = 1; k <= 200 && !failed; ++k) {
    e *= 1.5;
    if (mpm_guard_check(&g, (double)k * H0, k, H0, 0, e) != 0) failed = k;
  }
  assert_true(failed > 20 && failed < 60);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
}

/* A step of zero length (t + h == t: an edited checkpoint time of 1e17) repeats forever: it is
 * stopped at once, even with both criteria off, and as the first step of a run. */
static void test_zero_step_stops(void **state) {
  (void)state;
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  const char *const off[] = {"time.collapse_ratio=0", "time.energy_growth=0", NULL};
  guard_with(&g, &cfg, off);
  assert_int_equal(mpm_guard_check(&g, 1e17, 1, 0.0, 0, E0), MPM_ERR_UNPHYSICAL);
  assert_int_equal(mpm_guard_check(&g, 1e17, 2, 0.0, 1, E0), MPM_ERR_UNPHYSICAL);
  assert_int_equal(mpm_guard_check(&g, 1.0, 3, H0, 0, E0), 0);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_default_stops_slow_collapse),
      cmocka_unit_test(test_default_lets_small_steps_run),
      cmocka_unit_test(test_cut_short_steps_neither_count_nor_break),
      cmocka_unit_test(test_off_and_energy),
      cmocka_unit_test(test_zero_step_stops),
  };
  const int failed = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return failed;
}
