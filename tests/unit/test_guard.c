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

/* starting CFL step, total and kinetic energy (an acoustic level, as in issue 55's resonator) */
static const double H0 = 1e-2, E0 = 1.0, K0 = 1e-7;

/* A guard with the schema's defaults and the given overrides (NULL-terminated), from a state
 * with kinetic energy k0. */
static void guard_from(mpm_guard *g, mpm_config **cfg, const char *const *over, double k0) {
  assert_int_equal(mpm_config_new(cfg, MPI_COMM_WORLD), 0);
  assert_int_equal(mpm_config_add_schema(*cfg, mpm_guard_keys, mpm_guard_nkeys), 0);
  for (int k = 0; over && over[k]; ++k) assert_int_equal(mpm_config_override(*cfg, over[k]), 0);
  assert_int_equal(mpm_guard_init(g, *cfg, H0, E0, k0), 0);
}

static void guard_with(mpm_guard *g, mpm_config **cfg, const char *const *over) {
  guard_from(g, cfg, over, K0);
}

/* Steps of h at constant energy from step `from`; returns the step that failed, or 0. */
static long run_steps(mpm_guard *g, long from, long count, double h, int cut_short) {
  for (long k = 0; k < count; ++k)
    if (mpm_guard_check(g, (double)(from + k) * h, from + k, h, cut_short, E0, K0) != 0)
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
  assert_int_equal(mpm_guard_check(&g, 1.0, 1001, H0, 0, NAN, NAN), MPM_ERR_UNPHYSICAL);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
  /* geometric growth: 1.5 per step passes time.energy_growth = 1000 over half the run */
  guard_with(&g, &cfg, NULL);
  double e = E0;
  long failed = 0;
  for (long k = 1; k <= 200 && !failed; ++k) {
    e *= 1.5;
    if (mpm_guard_check(&g, (double)k * H0, k, H0, 0, e, K0) != 0) failed = k;
  }
  assert_true(failed > 20 && failed < 60);
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
}

/* ---- the kinetic energy (time.kinetic_growth) -------------------------------------------- */

/* Kinetic energy sequences over steps k = 1, 2, ..., with the total energy E0 flat (the gas's
 * internal energy pays for the motion) unless a load feeds it (power_law). */
static double geometric(long k) { /* a particle-scale mode: x1.1 per step from the acoustic level */
  return K0 * pow(1.1, (double)k);
}
static double from_roundoff(long k) { /* the same mode from roundoff, 1e-30 of the total */
  return 1e-30 * pow(1.1, (double)k);
}
static double power_law_2(long k) { /* from rest under a constant load: KE ~ t^2 */
  return 0.5 * pow((double)k / 5000, 2);
}
static double power_law_6(long k) { /* from rest under a load ramped as t^2: KE ~ t^6 */
  return 0.5 * pow((double)k / 5000, 6);
}
static double noise(long k) { /* a scene at rest: roundoff over four decades, and growing */
  const double x = 0.6180339887498949 * (double)k;
  return 1e-30 * pow(10, 4 * (x - floor(x))) + 1e-40 * pow(1.1, (double)k);
}
static double jump_then_flat(long k) { /* a release or an impact in the first steps, then flat */
  return k < 5 ? K0 : k < 1000 ? 1e-2 : 0.1;
}

/* Steps 1 .. n with kinetic energy ke(k) (from ke(0)) and total energy E0 (or E0 + ke, fed):
 * the step that failed, or 0; *k_fail: the kinetic energy there. */
static long run_kinetic(const char *const *over, double (*ke)(long), long n, int fed,
                        double *k_fail) {
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  guard_from(&g, &cfg, over, ke(0));
  long failed = 0;
  for (long k = 1; k <= n && !failed; ++k) {
    const double kin = ke(k), e = fed ? E0 + kin : E0;
    if (mpm_guard_check(&g, (double)k * H0, k, H0, 0, e, kin) != 0) failed = k, *k_fail = kin;
  }
  mpm_guard_free(&g);
  mpm_config_destroy(&cfg);
  return failed;
}

/* A mode growing x1.1 per step at a flat total energy: stopped once it has grown more than
 * time.kinetic_growth = 100 over the latest half of the steps and holds more than 100 x 1e-5
 * of the total energy, at step 97 (1.1^49 > 100, 1e-7 x 1.1^97 > 1e-3); from roundoff, not
 * before it exceeds 1e-3 of the total energy (step 653). Without the criterion (0, as before
 * it existed) neither is stopped. */
static void test_kinetic_growth_stops(void **state) {
  (void)state;
  double k_fail = 0;
  long failed = run_kinetic(NULL, geometric, 160, 0, &k_fail);
  assert_int_equal(failed, 97);
  assert_true(k_fail < 1.1e-3 * E0); /* stopped at 0.1 % of the total energy */
  failed = run_kinetic(NULL, from_roundoff, 800, 0, &k_fail);
  assert_int_equal(failed, 653);
  assert_true(k_fail > 100 * MPM_GUARD_KINETIC_FLOOR * E0 && k_fail < 1.1e-3 * E0);
  const char *const off[] = {"time.kinetic_growth=0", NULL};
  assert_int_equal(run_kinetic(off, geometric, 160, 0, &k_fail), 0);
  assert_int_equal(run_kinetic(off, from_roundoff, 800, 0, &k_fail), 0);
}

/* What must run: motion from rest under a load (t^2, and t^6 under a load ramped as t^2: 2^p
 * over half the run, 64 < 100), roundoff noise of a scene at rest (1e-30 of the total energy,
 * jumping over four decades, and a roundoff mode growing x1.1 per step to 1e-20 of it: 1e5 over the
 * latest half, stopped without the floor, but far below it), and a jump in the first steps (within
 * the 20-step grace) followed by a flat level and a tenfold jump. */
static void test_kinetic_legitimate_runs(void **state) {
  (void)state;
  double k_fail = 0;
  assert_int_equal(run_kinetic(NULL, power_law_2, 5000, 1, &k_fail), 0);
  assert_int_equal(run_kinetic(NULL, power_law_6, 5000, 1, &k_fail), 0);
  assert_int_equal(run_kinetic(NULL, noise, 480, 0, &k_fail), 0);
  assert_true(noise(480) > 1e-21 && noise(480) < 1e-3 * E0); /* x1e5 over half: the floor */
  assert_int_equal(run_kinetic(NULL, jump_then_flat, 3000, 0, &k_fail), 0);
}

/* A step of zero length (t + h == t: an edited checkpoint time of 1e17) repeats forever: it is
 * stopped at once, even with both criteria off, and as the first step of a run. */
static void test_zero_step_stops(void **state) {
  (void)state;
  mpm_guard g = {0};
  mpm_config *cfg = NULL;
  const char *const off[] = {"time.collapse_ratio=0", "time.energy_growth=0",
                             "time.kinetic_growth=0", NULL};
  guard_with(&g, &cfg, off);
  assert_int_equal(mpm_guard_check(&g, 1e17, 1, 0.0, 0, E0, K0), MPM_ERR_UNPHYSICAL);
  assert_int_equal(mpm_guard_check(&g, 1e17, 2, 0.0, 1, E0, K0), MPM_ERR_UNPHYSICAL);
  assert_int_equal(mpm_guard_check(&g, 1.0, 3, H0, 0, E0, K0), 0);
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
      cmocka_unit_test(test_kinetic_growth_stops),
      cmocka_unit_test(test_kinetic_legitimate_runs),
  };
  const int failed = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return failed;
}
