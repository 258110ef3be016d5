/* test_periodic_migrate: particle migration across periodic faces (run on 2 and 4 ranks).
 *
 * On grids periodic along some axes (2-D: x; x and y; x with x unsplit. 3-D: all; y and z),
 * a few thousand particles start anywhere and do 60 steps of a random walk of up to 1.5
 * cells per axis: along a periodic axis the step is taken as it comes, so particles leave
 * through the periodic faces, while along the other axes it is reflected at the faces.
 * Migration after each step must wrap and deliver them. After every step:
 * - the global count and the id multiset (sums of ids and of their squares) are unchanged;
 * - every particle lies on the rank owning its cell (so inside [lo, hi));
 * - every other value is still the function of the id it was set to;
 * - along a periodic axis the position equals the unwrapped walk (summed here from the same
 *   hash) modulo the period, within 1e-12 m: the wrapped position carries the roundoff of
 *   at most 60 additions and wraps of numbers below 4, about 1e-14; along the other axes it
 *   is bitwise the reflected walk, as in test_migrate.
 * At the end the gathered ids are exactly 0 .. N-1, and the walk must have crossed the
 * periodic faces many times. Also: a wrap alone (no rank change) reports `changed`;
 * mpm_grid_wrap's edge cases; a particle more than a period beyond a periodic face, or
 * beyond a non-periodic one, fails migration with MPM_ERR_UNPHYSICAL on every rank. */
#include "mpm_error.h"
#include "mpm_particles.h"

#include "mpm_random.h"
#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { NPART = 3000, NSTEPS = 60, NQ = 3 };

typedef struct config {
  int dim, periodic[3], nproc[3];
} config;

static const config g_configs[] = {
    {2, {1, 0, 0}, {0, 0, 0}}, {2, {1, 1, 0}, {0, 0, 0}}, {2, {1, 0, 0}, {1, 0, 0}},
    {3, {1, 1, 1}, {0, 0, 0}}, {3, {0, 1, 1}, {0, 0, 0}},
};

/* ---- deterministic functions of the id ------------------------------------------------- */

static double uniform(mpm_gidx id, int step, int d) {
  return (double)(mpm_test_mix(mpm_test_mix(mpm_test_mix((uint64_t)id) + (uint64_t)step) +
                               (uint64_t)d) >>
                  11) *
         0x1.0p-53;
}

static double value_of(mpm_gidx id, int f, int c) {
  return (double)id * 0.5 + 10.0 * f + c;
}

/* Step `step` >= 1 of the walk along d. */
static double step_of(const mpm_grid *g, mpm_gidx id, int step, int d) {
  return (2.0 * uniform(id, step, d) - 1.0) * 1.5 * g->dx;
}

static double reflect(double x, double lo, double hi) {
  if (x < lo) x = 2.0 * lo - x;
  if (x >= hi) x = 2.0 * hi - x;
  return x >= hi ? nextafter(hi, lo) : x;
}

/* Coordinate d of particle id after `steps` steps: unwrapped along a periodic axis. */
static double walk_coord(const mpm_grid *g, mpm_gidx id, int steps, int d) {
  double x = g->lo[d] + uniform(id, 0, d) * (g->hi[d] - g->lo[d]);
  for (int s = 1; s <= steps; ++s)
    x = g->periodic[d] ? x + step_of(g, id, s, d)
                       : reflect(x + step_of(g, id, s, d), g->lo[d], g->hi[d]);
  return x;
}

/* Distance between a and b along d, modulo the period on a periodic axis. */
static double distance(const mpm_grid *g, int d, double a, double b) {
  const double len = g->hi[d] - g->lo[d], e = a - b;
  return g->periodic[d] ? fabs(e - len * nearbyint(e / len)) : fabs(e);
}

/* ---- set-up ---------------------------------------------------------------------------- */

static mpm_particles *new_set(int dim) {
  const mpm_field_desc fields[4] = {{"x", dim}, {"v", dim}, {"q", NQ}, {"s", 1}};
  mpm_particles *p = NULL;
  CHECK(mpm_particles_new(&p, dim, fields, 4, 2) == 0, "particles_new");
  return p;
}

static mpm_grid *new_grid(const config *c) {
  const double lo[3] = {-0.5, 0.0, 0.2}, hi2[3] = {1.5, 1.5, 0}, hi3[3] = {0.5, 0.8, 0.8};
  mpm_grid *g = NULL;
  CHECK(mpm_grid_new_periodic(&g, MPI_COMM_WORLD, c->dim, lo, c->dim == 2 ? hi2 : hi3,
                              c->dim == 2 ? 0.125 : 0.1, MPM_SHAPE_QUADRATIC, c->nproc,
                              c->periodic) == 0,
        "grid_new_periodic");
  return g;
}

/* n fresh particles on every rank, numbered in rank order, each at the walk's start with
 * its values set from the id. */
static void seed(mpm_particles *p, const mpm_grid *g, mpm_lidx n) {
  double *data = calloc((size_t)n * (size_t)p->ncomp + 1, sizeof *data);
  CHECK(mpm_particles_inject(p, MPI_COMM_WORLD, n, data) == 0, "inject");
  free(data);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    for (int d = 0; d < p->dim; ++d) mpm_particles_comp(p, 0, d)[i] = walk_coord(g, p->id[i], 0, d);
    for (int f = 1; f < p->nfields; ++f)
      for (int c = 0; c < p->field[f].ncomp; ++c)
        mpm_particles_comp(p, f, c)[i] = value_of(p->id[i], f, c);
  }
}

/* ---- checks ---------------------------------------------------------------------------- */

static void id_sums(const mpm_particles *p, uint64_t sums[3]) {
  sums[0] = sums[1] = 0, sums[2] = (uint64_t)p->n;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const uint64_t id = (uint64_t)p->id[i];
    sums[0] += id, sums[1] += id * id;
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
}

/* Largest position error of this rank's particles; counts failures of the other checks. */
static double check_particles(const mpm_particles *p, const mpm_grid *g, int step) {
  double worst = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double x[3] = {0, 0, 0};
    for (int d = 0; d < p->dim; ++d) {
      x[d] = mpm_particles_comp(p, 0, d)[i];
      const double want = walk_coord(g, p->id[i], step, d), e = distance(g, d, x[d], want);
      if (g->periodic[d])
        worst = fmax(worst, e);
      else
        CHECK(e == 0, "step %d: particle %ld off the reflected walk along %d", step, (long)p->id[i],
              d);
    }
    CHECK(mpm_grid_owner_of(g, x) == g_rank, "step %d: particle %ld at (%g, %g, %g) on rank %d",
          step, (long)p->id[i], x[0], x[1], x[2], g_rank);
    int same = 1;
    for (int f = 1; f < p->nfields; ++f)
      for (int c = 0; c < p->field[f].ncomp; ++c)
        same &= mpm_particles_comp(p, f, c)[i] == value_of(p->id[i], f, c);
    CHECK(same, "step %d: data of particle %ld", step, (long)p->id[i]);
  }
  return worst;
}

static void check_all_ids(const mpm_particles *p) {
  int n = (int)p->n, total = 0, *counts = calloc((size_t)g_size, sizeof *counts);
  int *displs = calloc((size_t)g_size, sizeof *displs);
  MPI_Allreduce(&n, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  mpm_gidx *all = calloc((size_t)total + 1, sizeof *all);
  MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (int r = 1; r < g_size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  MPI_Gatherv(p->id, n, MPM_MPI_GIDX, all, counts, displs, MPM_MPI_GIDX, 0, MPI_COMM_WORLD);
  if (g_rank == 0) {
    char *seen = calloc(NPART, 1);
    CHECK(total == NPART, "gathered %d ids", total);
    for (int k = 0; k < total; ++k) {
      const int ok = all[k] >= 0 && all[k] < NPART && !seen[all[k]];
      CHECK(ok, "id %ld", (long)all[k]);
      if (ok) seen[all[k]] = 1;
    }
    free(seen);
  }
  free(counts), free(displs), free(all);
}

/* One step of the walk on this rank's particles; returns how many left through a periodic
 * face. */
static long walk(mpm_particles *p, const mpm_grid *g, int step) {
  long out = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    int left = 0;
    for (int d = 0; d < p->dim; ++d) {
      double *x = &mpm_particles_comp(p, 0, d)[i];
      *x = g->periodic[d] ? *x + step_of(g, p->id[i], step, d)
                          : reflect(*x + step_of(g, p->id[i], step, d), g->lo[d], g->hi[d]);
      left |= g->periodic[d] && !(*x >= g->lo[d] && *x < g->hi[d]);
    }
    out += left;
  }
  return out;
}

static void run_walk(int ic) {
  const config *c = &g_configs[ic];
  mpm_grid *g = new_grid(c);
  mpm_particles *p = new_set(c->dim);
  if (!g || !p) return;
  seed(p, g, NPART / g_size + (g_rank < NPART % g_size));
  int changed = -1;
  CHECK(mpm_particles_migrate(p, g, &changed) == 0 && changed == (g_size > 1), "first migrate");
  double worst = check_particles(p, g, 0);
  long crossings = 0;
  const uint64_t n = NPART;
  for (int step = 1; step <= NSTEPS; ++step) {
    crossings += walk(p, g, step);
    CHECK(mpm_particles_migrate(p, g, &changed) == 0, "migrate at step %d", step);
    if (step % 15 == 0) CHECK(mpm_particles_sort(p, g) == 0, "sort at step %d", step);
    uint64_t sums[3];
    id_sums(p, sums);
    CHECK(sums[2] == n && sums[0] == n * (n - 1) / 2 && sums[1] == (n - 1) * n * (2 * n - 1) / 6,
          "step %d: %lu particles, id sums", step, (unsigned long)sums[2]);
    worst = fmax(worst, check_particles(p, g, step));
  }
  check_all_ids(p);
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &crossings, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  CHECK(worst <= 1e-12, "config %d: position off the wrapped walk by %.3e m", ic, worst);
  CHECK(crossings >= NPART / 10, "config %d: only %ld periodic crossings", ic, crossings);
  if (g_rank == 0)
    printf("%d-D periodic %d%d%d split %dx%dx%d: %ld periodic crossings, max position error "
           "%.2e m\n",
           c->dim, c->periodic[0], c->periodic[1], c->periodic[2], g->nproc[0], g->nproc[1],
           g->nproc[2], crossings, worst);
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

/* x unsplit: a particle beyond x_hi wraps on its own rank, and migrate must still say so. */
static void check_wrap_in_place(void) {
  const config c = {2, {1, 0, 0}, {1, 0, 0}};
  mpm_grid *g = new_grid(&c);
  mpm_particles *p = new_set(2);
  if (!g || !p) return;
  seed(p, g, 1);
  const double beyond = g->hi[0] + 0.3 * g->dx, len = g->hi[0] - g->lo[0];
  mpm_particles_comp(p, 0, 0)[0] = beyond;
  mpm_particles_comp(p, 0, 1)[0] = g->lo[1] + (g->cell_split[1][g->coord[1]] + 0.5) * g->dx;
  int changed = -1;
  CHECK(mpm_particles_migrate(p, g, &changed) == 0 && changed == 1 && p->n == 1,
        "a wrap in place: changed = %d, n = %d", changed, (int)p->n);
  CHECK(fabs(mpm_particles_comp(p, 0, 0)[0] - (beyond - len)) <= 1e-15, "wrapped to %.17g",
        mpm_particles_comp(p, 0, 0)[0]);
  CHECK(mpm_particles_migrate(p, g, &changed) == 0 && changed == 0, "nothing left to wrap");
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

static void check_wrap_edges(void) {
  const config c = {2, {1, 0, 0}, {0, 0, 0}};
  mpm_grid *g = new_grid(&c);
  if (!g) return;
  const double lo = g->lo[0], hi = g->hi[0], len = hi - lo, ymid = 0.5 * (g->lo[1] + g->hi[1]);
  double x[3] = {hi, ymid, 0};
  CHECK(mpm_grid_wrap(g, x) == 1 && x[0] == lo && x[1] == ymid, "hi wraps to lo: %.17g", x[0]);
  x[0] = nextafter(lo, -INFINITY);
  CHECK(mpm_grid_wrap(g, x) == 1 && x[0] >= lo && x[0] < hi && distance(g, 0, x[0], lo) < 1e-15,
        "just below lo: %.17g", x[0]);
  x[0] = lo + 0.25 * len;
  CHECK(mpm_grid_wrap(g, x) == 0 && x[0] == lo + 0.25 * len, "inside: unchanged");
  const double far[4] = {hi + 1.5 * len, lo - 1.5 * len, NAN, INFINITY};
  for (int k = 0; k < 4; ++k) {
    x[0] = far[k];
    CHECK(mpm_grid_wrap(g, x) == 0 && (x[0] == far[k] || (isnan(x[0]) && isnan(far[k]))),
          "a point %g is not wrapped", far[k]);
  }
  x[0] = lo + 0.5 * len, x[1] = g->hi[1] + 0.01;
  CHECK(mpm_grid_wrap(g, x) == 0 && x[1] == g->hi[1] + 0.01, "a non-periodic axis is not wrapped");
  mpm_grid_destroy(&g);
}

/* One rank holds a particle at coordinate `axis` = bad; every rank must get the error. */
static void expect_unphysical(int axis, double bad) {
  const config c = {2, {1, 0, 0}, {0, 0, 0}};
  mpm_grid *g = new_grid(&c);
  mpm_particles *p = new_set(2);
  if (!g || !p) return;
  seed(p, g, 10);
  if (g_rank == g_size - 1) mpm_particles_comp(p, 0, axis)[5] = bad;
  int changed = -1;
  const int rc = mpm_particles_migrate(p, g, &changed);
  CHECK(rc == MPM_ERR_UNPHYSICAL && changed == 0 && p->n == 10, "migrate returned %d", rc);
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  for (int ic = 0; ic < (int)(sizeof g_configs / sizeof g_configs[0]); ++ic) run_walk(ic);
  check_wrap_in_place();
  check_wrap_edges();
  if (g_rank == 0) fprintf(stderr, "expected errors follow:\n");
  expect_unphysical(0, 5.0);  /* x: more than a period beyond x_hi */
  expect_unphysical(1, -0.3); /* y: beyond a non-periodic face */
  MPI_Barrier(MPI_COMM_WORLD);
  mpm_test_finish("test_periodic_migrate");
  MPI_Finalize();
  return g_fail != 0;
}
