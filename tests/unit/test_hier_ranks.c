/* The refinement hierarchy refuses a grid split over ranks (mpm_hier.h: one rank for now), on
 * every rank alike, with MPM_ERR_INPUT, no hierarchy and a reason that says what to do; the
 * same boxes on a one-rank grid are accepted, so the refusal is the rank count's. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>
#include <mpi.h>

#include "mpm_error.h"
#include "mpm_hier.h"

static void test_ranks(void **state) {
  (void)state;
  const double lo[2] = {0, 0}, hi[2] = {2, 2};
  const int nproc[2] = {0, 0};
  const mpm_hier_box box = {1, {0.4, 0.4}, {1.6, 1.6}};
  mpm_grid *g, *one;
  mpm_hier *h = NULL;
  char why[256] = "";
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc), 0);
  assert_true(g->size > 1);
  assert_int_equal(mpm_hier_new(&h, g, 2, &box, 1, 1, why, sizeof why), MPM_ERR_INPUT);
  assert_null(h);
  assert_non_null(strstr(why, "run on one rank"));
  assert_int_equal(mpm_grid_new(&one, MPI_COMM_SELF, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc),
                   0);
  assert_int_equal(mpm_hier_new(&h, one, 2, &box, 1, 1, why, sizeof why), 0);
  mpm_hier_destroy(&h);
  mpm_grid_destroy(&one);
  mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_ranks)};
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
