/* Every particle layout the modules can build fits the particle store (common/mpm_particles.h),
 * in 2-D and 3-D, built through the modules' own layout builders:
 *  - the gas (fluid_particles_new): every combination of APIC, viscosity, the riemann
 *    viscosity's limiter and the place of the lagged strain rate (in the state: usl, musl; or
 *    committed from the pending copy: the ERK pairs and ssprk2), 16 in all. Some are refused
 *    by the case keys today (APIC needs the classic update), but a layout the store cannot
 *    hold must not be what keeps them refused;
 *  - the solid (solid_particles_new): every combination of a rate-form model, APIC, a bulk
 *    viscosity (none, its rate in the state, or pending: the method of lines), clamps and
 *    tractions, with no history or with the largest history of any registered model, 96 in all;
 *  - the coupler's interface state (mpm_interface_particles_new), with and without predictor.
 * Each built set must hold its fields under their names, with the sizes the layout gives, and
 * every field that holds the gas's or the solid's pending strain rate must be scratch (a checkpoint
 * need not hold it). Every failing combination is printed before the test fails, so one run lists
 * them all. Exact: no tolerance (counts and names).
 *
 * Shown to fail on the old store (16 fields, a single "pending" field of 1 + dim^2 + 1
 * components): the six 3-D gas layouts with viscosity and a pending copy. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <mpi.h>

#include "fluid_internal.h"
#include "mpm_interface.h"
#include "solid_internal.h"
#include "solid_material.h"

/* Is field `name` present in p with ncomp components? */
static int has(const mpm_particles *p, int f, const char *name, int ncomp) {
  return f >= 0 && f < p->nfields && strcmp(p->field[f].name, name) == 0 &&
         p->field[f].ncomp == ncomp;
}

static const char *const g_why[] = {"", "does not build", "is not the layout it should be"};

/* The gas layout {apic, viscous, limiter, lag}: 0 if it builds and is consistent, 1 if it does
 * not build, 2 if it is inconsistent. */
static int gas_layout_check(int dim, const int *o) {
  mpm_particles *p = NULL;
  fluid_layout lay;
  memset(&lay, 0, sizeof lay);
  if (fluid_particles_new(&p, dim, &lay, o[0], o[1], o[2], o[3])) return 1;
  const int d2 = dim * dim;
  int ok = has(p, FLUID_X, "x", dim) && has(p, FLUID_V, "v", dim) && has(p, FLUID_J, "J", 1) &&
           has(p, FLUID_E, "e", 1) && has(p, lay.f_divv, "divv", 1);
  ok = ok && (o[0] ? has(p, lay.f_C, "C", d2) : lay.f_C < 0);
  ok = ok && (o[1] ? has(p, lay.f_D, "D", d2) : lay.f_D < 0);
  ok = ok && (o[2] ? has(p, lay.f_psi, "psi", 1) : lay.f_psi < 0);
  ok = ok && (o[3] ? lay.f_pending < 0 : has(p, lay.f_pending, "pending_divv", 1));
  if (ok && !o[3]) { /* the pending copy mirrors divv, D, psi field by field, all scratch */
    const int npend = lay.f_divv - lay.f_pending;
    ok = npend == 1 + o[1] + o[2];
    for (int k = 0; ok && k < npend; ++k) {
      const int f = lay.f_pending + k;
      char want[40];
      snprintf(want, sizeof want, "pending_%s", p->field[f + npend].name);
      ok = has(p, f, want, p->field[f + npend].ncomp) && (p->scratch >> f & 1u);
    }
  }
  mpm_particles_destroy(&p);
  return ok ? 0 : 2;
}

static void test_gas(void **state) {
  (void)state;
  int bad = 0;
  for (int dim = 2; dim <= 3; ++dim)
    for (int k = 0; k < 16; ++k) {
      const int o[4] = {k & 1, k >> 1 & 1, k >> 2 & 1, k >> 3 & 1};
      const int why = gas_layout_check(dim, o);
      if (!why) continue;
      ++bad;
      printf("gas layout %s: %d-D apic %d viscous %d limiter %d lag_in_state %d\n", g_why[why], dim,
             o[0], o[1], o[2], o[3]);
    }
  assert_int_equal(bad, 0);
}

/* The most history components of any registered model in dim. */
static int max_history(int dim) {
  int nh = 0;
  for (int k = 0; k < solid_material_count(); ++k) {
    const solid_material_ops *ops = solid_material_ops_at(k);
    if (ops->nhistory && ops->nhistory(dim) > nh) nh = ops->nhistory(dim);
  }
  return nh;
}

/* The solid layout {rate, apic, bulkq (SOLID_BULKQ_*), history, fixed, fext}: as
 * gas_layout_check. */
static int solid_layout_check(int dim, const int *o) {
  mpm_particles *p = NULL;
  solid_layout lay;
  memset(&lay, 0, sizeof lay);
  const int nh = o[3] ? max_history(dim) : 0, d2 = dim * dim;
  if (solid_particles_new(&p, dim, &lay, o[0], o[1], o[2], nh, o[4], o[5])) return 1;
  int ok = has(p, F_X, "x", dim) && has(p, F_V, "v", dim) && has(p, F_F, "F", d2) &&
           has(p, lay.f_m, "m", 1) && has(p, lay.f_V0, "V0", 1) && has(p, lay.f_body, "body", 1);
  ok = ok && (o[0] ? has(p, lay.f_sigma, "sigma", d2) : lay.f_sigma < 0);
  ok = ok && (o[1] ? has(p, lay.f_C, "C", d2) : lay.f_C < 0);
  ok = ok && (o[2] ? has(p, lay.f_divv, "divv", 1) : lay.f_divv < 0);
  ok = ok && (o[2] == SOLID_BULKQ_STATE) == (lay.f_divv >= 0 && lay.f_divv < p->nstate_fields);
  ok = ok && (o[2] == SOLID_BULKQ_PENDING
                  ? has(p, lay.f_pending, "pending_divv", 1) && (p->scratch >> lay.f_pending & 1u)
                  : lay.f_pending < 0);
  ok = ok && (nh ? has(p, lay.f_hist, "hist", nh) : lay.f_hist < 0);
  ok = ok && (o[4] ? has(p, lay.f_fixed, "fixed", 1) : lay.f_fixed < 0);
  ok = ok && (o[5] ? has(p, lay.f_fext, "fext", dim) : lay.f_fext < 0);
  mpm_particles_destroy(&p);
  return ok ? 0 : 2;
}

static void test_solid(void **state) {
  (void)state;
  int bad = 0;
  assert_true(max_history(3) > 0); /* J2 has history: the "with history" layouts are real */
  for (int dim = 2; dim <= 3; ++dim)
    for (int k = 0; k < 96; ++k) {
      int o[6];
      for (int b = 0; b < 5; ++b) o[b < 2 ? b : b + 1] = k >> b & 1;
      o[2] = k >> 5; /* 0, 1, 2 */
      const int why = solid_layout_check(dim, o);
      if (!why) continue;
      ++bad;
      printf("solid layout %s: %d-D rate %d apic %d bulkq %d history %d fixed %d fext %d\n",
             g_why[why], dim, o[0], o[1], o[2], o[3], o[4], o[5]);
    }
  assert_int_equal(bad, 0);
}

static void test_interface(void **state) {
  (void)state;
  for (int dim = 2; dim <= 3; ++dim)
    for (int pred = 0; pred <= 1; ++pred) {
      mpm_particles *p = NULL;
      assert_int_equal(mpm_interface_particles_new(&p, dim, pred), 0);
      assert_true(has(p, 0, "x", dim) && has(p, 1, "v", dim));
      mpm_particles_destroy(&p);
    }
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_gas),
      cmocka_unit_test(test_solid),
      cmocka_unit_test(test_interface),
  };
  const int rc = cmocka_run_group_tests(tests, NULL, NULL);
  MPI_Finalize();
  return rc;
}
