/* The ARKODE driver on its own, with a test module whose RHS is known exactly:
 * free flight, dx/dt = v, dv/dt = g, so x(t) = x0 + v0 t + g t^2/2, which a third-order
 * pair integrates to roundoff. It checks, on any number of ranks:
 *  - two modules joined in one MPIManyVector, each with its own particle count;
 *  - migration and injection in the middle of a run, followed by Resize;
 *  - the recoverable-error path: the module rejects any stage that moves a particle more
 *    than `limit` from its last accepted position, so large steps fail and the driver must
 *    retry with smaller ones and still reach the exact answer;
 *  - the final failure: with limit = 0 no step can succeed, and the driver stops with
 *    MPM_ERR_UNPHYSICAL on every rank after time.max_retries retries;
 *  - the classic update at output stops (run_classic). */
#include "mpm_config.h"
#include "mpm_error.h"
#include "mpm_integrator.h"
#include "mpm_module.h"

#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double G[2] = {0.0, -1.0};

typedef struct {
  double limit;  /* largest move of a particle within one step */
  double *x_acc; /* positions at the last accepted step (component-major, n per axis) */
  mpm_lidx n_acc;
} flight;

static int fl_nop_p2g(mpm_module *m, double t, const double *y) {
  return (void)m, (void)t, (void)y, 0;
}
static int fl_nop_grid(mpm_module *m, double t, double h, mpm_pass pass) {
  return (void)m, (void)t, (void)h, (void)pass, 0;
}

static int fl_g2p(mpm_module *m, double t, const double *y, double *ydot, double h) {
  (void)t, (void)h;
  const mpm_lidx n = m->particles->n;
  for (int d = 0; d < 2; ++d)
    for (mpm_lidx i = 0; i < n; ++i) {
      ydot[(size_t)d * n + i] = y[(size_t)(2 + d) * n + i];
      ydot[(size_t)(2 + d) * n + i] = G[d];
    }
  return 0;
}

static double fl_stable(const mpm_module *m, const double *y) {
  return (void)m, (void)y, HUGE_VAL;
}

static int fl_check(const mpm_module *m, const double *y, mpm_fault *f) {
  const flight *fl = m->content;
  const mpm_lidx n = m->particles->n;
  if (n != fl->n_acc) return 0;
  for (mpm_lidx i = 0; i < n; ++i)
    for (int d = 0; d < 2; ++d)
      if (fabs(y[(size_t)d * n + i] - fl->x_acc[(size_t)d * n + i]) > fl->limit) {
        f->set = 1, f->id = m->particles->id[i];
        f->x[0] = y[i], f->x[1] = y[n + i];
        snprintf(f->cause, sizeof f->cause, "moved more than %g in one step", fl->limit);
        return 1;
      }
  return 0;
}

static void fl_sums(const mpm_module *m, mpm_module_sums *s) {
  (void)m, memset(s, 0, sizeof *s);
}

static void fl_destroy(mpm_module *m) {
  flight *fl = m->content;
  free(fl->x_acc);
  free(fl);
  mpm_particles_destroy(&m->particles);
}

static const mpm_module_ops flight_ops = {.p2g = fl_nop_p2g,
                                          .forces = fl_nop_grid,
                                          .constrain = fl_nop_grid,
                                          .g2p = fl_g2p,
                                          .stable_dt = fl_stable,
                                          .check = fl_check,
                                          .sums = fl_sums,
                                          .destroy = fl_destroy};

static void accept_positions(mpm_module *m) {
  flight *fl = m->content;
  const mpm_particles *p = m->particles;
  free(fl->x_acc);
  fl->x_acc = malloc(sizeof(double) * 2 * (size_t)(p->n + 1));
  memcpy(fl->x_acc, p->data, sizeof(double) * 2 * (size_t)p->n);
  fl->n_acc = p->n;
}

/* Initial state of particle id (deterministic, so every rank count gives the same set). */
static void initial(mpm_gidx id, double *x, double *v) {
  x[0] = 3.0 + fmod(0.37 * (double)id, 4.0);
  x[1] = 5.0 + fmod(0.61 * (double)id, 3.0);
  v[0] = fmod(0.13 * (double)id, 1.0) - 0.5;
  v[1] = fmod(0.29 * (double)id, 1.0) - 0.5;
}

static mpm_module *flight_new(mpm_grid *grid, const char *name, mpm_gidx id0, int count,
                              double limit) {
  const mpm_field_desc fields[2] = {{"x", 2}, {"v", 2}};
  mpm_module *m = calloc(1, sizeof *m);
  flight *fl = calloc(1, sizeof *fl);
  snprintf(m->name, sizeof m->name, "%s", name);
  m->ops = &flight_ops, m->content = fl, m->grid = grid;
  fl->limit = limit;
  mpm_particles_new(&m->particles, 2, fields, 2, 2);
  mpm_grid_add_phase(grid, name, &m->phase);
  /* Rank 0 creates every particle; migration hands them to their owners. */
  const int n = g_rank == 0 ? count : 0;
  double *data = calloc((size_t)4 * (size_t)(n + 1), sizeof(double));
  mpm_gidx *ids = calloc((size_t)(n + 1), sizeof(mpm_gidx));
  for (int i = 0; i < n; ++i) {
    double x[2], v[2];
    ids[i] = id0 + i;
    initial(ids[i], x, v);
    for (int d = 0; d < 2; ++d)
      data[(size_t)d * n + i] = x[d], data[(size_t)(2 + d) * n + i] = v[d];
  }
  mpm_particles_edit(m->particles, NULL, n, ids, data);
  m->particles->id_next = id0 + count;
  free(data), free(ids);
  mpm_particles_migrate(m->particles, grid, NULL);
  accept_positions(m);
  return m;
}

/* Largest |x - exact| over the particles of m at time t (t0: injection time per id). */
static double error_of(const mpm_module *m, double t, mpm_gidx first_injected, double t_inject) {
  const mpm_particles *p = m->particles;
  double err = 0.0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double x0[2], v0[2];
    initial(p->id[i], x0, v0);
    const double s = p->id[i] >= first_injected ? t - t_inject : t;
    for (int d = 0; d < 2; ++d) {
      const double exact = x0[d] + v0[d] * s + 0.5 * G[d] * s * s;
      err = fmax(err, fabs(p->data[(size_t)d * p->n + i] - exact));
    }
  }
  return err;
}

static mpm_config *make_config(const char *method, const char *extra) {
  mpm_config *cfg = NULL;
  char text[512];
  snprintf(text, sizeof text, "[time]\nt_end = 1\nmethod = %s\nrtol = 1e-10\natol = 1e-12\n%s",
           method, extra);
  mpm_config_new(&cfg, MPI_COMM_WORLD);
  mpm_config_add_schema(cfg, mpm_integrator_keys, mpm_integrator_nkeys);
  if (mpm_config_read_string(cfg, text, "test", ".") || mpm_config_validate(cfg))
    CHECK(0, "config did not validate");
  return cfg;
}

/* Inject 3 particles on every rank into m (ids continue after id_next). */
static mpm_gidx inject(mpm_module *m) {
  const mpm_gidx first = m->particles->id_next;
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int k = 3;
  double data[4 * 3];
  for (int j = 0; j < k; ++j) {
    double x[2], v[2];
    initial(first + (mpm_gidx)rank * k + j, x, v);
    for (int d = 0; d < 2; ++d) data[d * k + j] = x[d], data[(2 + d) * k + j] = v[d];
  }
  mpm_particles_inject(m->particles, MPI_COMM_WORLD, k, data);
  return first;
}

/* Run to t_end = 1 with two modules; inject into the second at t = 0.5. */
static void run_two_modules(double limit, const char *label) {
  const double lo[2] = {0, 0}, hi[2] = {10, 10};
  const int nproc[3] = {0, 0, 0};
  mpm_grid *grid = NULL;
  mpm_grid_new(&grid, MPI_COMM_WORLD, 2, lo, hi, 0.5, MPM_SHAPE_LINEAR, nproc);
  mpm_module *mods[2] = {flight_new(grid, "a", 0, 40, limit),
                         flight_new(grid, "b", 1000, 25, limit)};
  mpm_config *cfg = make_config("bs32", "max_retries = 12\n");
  mpm_integrator *it = NULL;
  const mpm_cycle cyc = {.grid = grid, .mod = mods, .nmod = 2};
  CHECK(mpm_integrator_new(&it, cfg, &cyc) == 0, "integrator_new");
  mpm_integrator_start(it, 0.0, 0.0);
  double t = 0.0, h;
  mpm_gidx first = 1 << 30;
  int injected = 0, rc = 0;
  while (t < 1.0 - 1e-14 && rc == 0) {
    const double tstop = injected ? 1.0 : 0.5;
    rc = mpm_integrator_step(it, tstop, &t, &h);
    int changed = 0, c;
    for (int k = 0; k < 2; ++k) {
      mpm_particles_migrate(mods[k]->particles, grid, &c);
      changed |= c;
    }
    if (!injected && t >= 0.5 - 1e-14) {
      first = inject(mods[1]);
      injected = changed = 1;
    }
    if (changed) mpm_integrator_resize(it, t);
    for (int k = 0; k < 2; ++k) accept_positions(mods[k]);
  }
  CHECK(rc == 0, "%s: integration failed (%d)", label, rc);
  double err = fmax(error_of(mods[0], t, 1 << 30, 0.5), error_of(mods[1], t, first, 0.5)), gerr;
  MPI_Allreduce(&err, &gerr, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  mpm_gidx n[2] = {0, 0};
  mpm_particles_global_count(mods[0]->particles, MPI_COMM_WORLD, &n[0]);
  mpm_particles_global_count(mods[1]->particles, MPI_COMM_WORLD, &n[1]);
  int size;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  long steps, rhs, fails, retries;
  mpm_integrator_counts(it, &steps, &rhs, &fails, &retries);
  CHECK(gerr <= 1e-12, "%s: max error %.3e (tolerance 1e-12)", label, gerr);
  CHECK(n[0] == 40 && n[1] == 25 + 3 * size, "%s: particle counts %lld %lld", label,
        (long long)n[0], (long long)n[1]);
  if (limit < 1e9) CHECK(retries > 0, "%s: the step limit never triggered a retry", label);
  if (g_rank == 0)
    printf("%s: t = %.3g, max error %.2e, %ld steps, %ld rhs, %ld retries\n", label, t, gerr, steps,
           rhs, retries);
  mpm_integrator_destroy(&it);
  for (int k = 0; k < 2; ++k) mpm_module_destroy(&mods[k]);
  mpm_config_destroy(&cfg);
  mpm_grid_destroy(&grid);
}

/* With limit 0 every stage that moves is rejected: the driver must give up cleanly. */
static void run_hopeless(void) {
  const double lo[2] = {0, 0}, hi[2] = {10, 10};
  const int nproc[3] = {0, 0, 0};
  mpm_grid *grid = NULL;
  mpm_grid_new(&grid, MPI_COMM_WORLD, 2, lo, hi, 0.5, MPM_SHAPE_LINEAR, nproc);
  mpm_module *m = flight_new(grid, "a", 0, 10, 0.0);
  mpm_config *cfg = make_config("bs32", "max_retries = 3\n");
  mpm_integrator *it = NULL;
  const mpm_cycle cyc = {.grid = grid, .mod = &m, .nmod = 1};
  mpm_integrator_new(&it, cfg, &cyc);
  mpm_integrator_start(it, 0.0, 0.0);
  double t, h;
  const int rc = mpm_integrator_step(it, 1.0, &t, &h);
  long steps, rhs, fails, retries;
  mpm_integrator_counts(it, &steps, &rhs, &fails, &retries);
  CHECK(rc == MPM_ERR_UNPHYSICAL, "hopeless run returned %d, expected MPM_ERR_UNPHYSICAL", rc);
  CHECK(retries == 3, "hopeless run retried %ld times, expected 3", retries);
  mpm_integrator_destroy(&it);
  mpm_module_destroy(&m);
  mpm_config_destroy(&cfg);
  mpm_grid_destroy(&grid);
}

/* The classic update (usl) is forward Euler with the driver's fixed steps: here h = 1/32
 * from time.dt_max (the flight module has no stability limit), with stops at 0.25, 0.3, 0.5,
 * 0.75 and 1 (0.3 is not on the step lattice). Checks:
 *  - the state returned at each stop is the state the steps reached, against forward Euler
 *    recomputed here with the returned steps (tolerance 1e-12: rounding over 32 steps of
 *    O(1) values; returning ARKODE's degree-0 dense output instead, the mean of the last two
 *    states, misses by h |v| / 2 ~ 1e-2);
 *  - f from the end of a step is reused when the next stop is a step away: one RHS
 *    evaluation per step, plus one at the start and at most one after each Resize. */
static void run_classic(void) {
  enum { NP = 30 };
  const double lo[2] = {0, 0}, hi[2] = {10, 10}, stops[] = {0.25, 0.3, 0.5, 0.75, 1.0};
  const int nproc[3] = {0, 0, 0};
  mpm_grid *grid = NULL;
  mpm_grid_new(&grid, MPI_COMM_WORLD, 2, lo, hi, 0.5, MPM_SHAPE_LINEAR, nproc);
  mpm_module *m = flight_new(grid, "a", 0, NP, 1e30);
  mpm_config *cfg = make_config("usl", "dt_max = 0.03125\n");
  mpm_integrator *it = NULL;
  const mpm_cycle cyc = {.grid = grid, .mod = &m, .nmod = 1};
  CHECK(mpm_integrator_new(&it, cfg, &cyc) == 0, "integrator_new");
  mpm_integrator_start(it, 0.0, 0.0);
  double xr[NP][2], vr[NP][2], t = 0.0, h;
  for (int i = 0; i < NP; ++i) initial(i, xr[i], vr[i]);
  long resizes = 0;
  int rc = 0;
  for (size_t k = 0; k < sizeof stops / sizeof stops[0] && rc == 0; ++k)
    while (t < stops[k] - 1e-14 && rc == 0) {
      rc = mpm_integrator_step(it, stops[k], &t, &h);
      for (int i = 0; i < NP; ++i)
        for (int d = 0; d < 2; ++d) xr[i][d] += h * vr[i][d], vr[i][d] += h * G[d];
      int changed;
      mpm_particles_migrate(m->particles, grid, &changed);
      if (changed) mpm_integrator_resize(it, t), resizes++;
    }
  CHECK(rc == 0, "classic update: integration failed (%d)", rc);
  const mpm_particles *p = m->particles;
  double err = 0.0, gerr;
  for (mpm_lidx i = 0; i < p->n; ++i)
    for (int d = 0; d < 2; ++d) {
      err = fmax(err, fabs(p->data[(size_t)d * p->n + i] - xr[p->id[i]][d]));
      err = fmax(err, fabs(p->data[(size_t)(2 + d) * p->n + i] - vr[p->id[i]][d]));
    }
  MPI_Allreduce(&err, &gerr, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  long steps, rhs, fails, retries;
  mpm_integrator_counts(it, &steps, &rhs, &fails, &retries);
  CHECK(gerr <= 1e-12, "classic update: max deviation from forward Euler %.3e", gerr);
  CHECK(rhs <= steps + 1 + resizes, "classic update: %ld rhs for %ld steps and %ld resizes", rhs,
        steps, resizes);
  if (g_rank == 0)
    printf("classic update: t = %.3g, max deviation from forward Euler %.2e, %ld steps, %ld rhs, "
           "%ld resizes on rank 0\n",
           t, gerr, steps, rhs, resizes);
  mpm_integrator_destroy(&it);
  mpm_module_destroy(&m);
  mpm_config_destroy(&cfg);
  mpm_grid_destroy(&grid);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_WARN, 0);
  run_two_modules(1e30, "two modules, no step limit");
  run_two_modules(0.02, "two modules, moves limited to 0.02 per step");
  run_hopeless();
  run_classic();
  const int total = mpm_test_finish("test_integrator");
  MPI_Finalize();
  return total ? 1 : 0;
}
