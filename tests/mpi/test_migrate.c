/* test_migrate: particle storage under MPI, in 2-D and 3-D.
 *
 * - edit: removal keeps order, additions go to the end, data travel with ids;
 * - derived fields: with a field marked derived (not moved), edits and sorts still carry every
 *   other field, the derived one lying between them in the block;
 * - inject: ids are numbered in rank order from id_next, which ends equal on every rank;
 * - sort: cell keys (x fastest) are nondecreasing, ties keep their order, data follow ids;
 * - migrate: a few thousand particles seeded anywhere do 50 steps of a random walk of up to
 *   1.5 cells (reflected at the walls) and migrate after each. After every step the global
 *   count, the id multiset (sum of ids and of their squares), ownership of every particle and
 *   every value (a function of the id; the position is recomputed from the walk) are checked,
 *   and at the end rank 0 checks that the gathered ids are exactly 0 .. N-1;
 * - deferred edit: an edit left to the next migration (mpm_particles_edit_deferred) gives the
 *   same set, particle for particle and bit for bit, as the edit followed by the migration,
 *   whether or not anything moves between ranks; any other edit or a sort while one is
 *   pending fails;
 * - a particle outside the domain makes migrate fail with MPM_ERR_UNPHYSICAL on every rank.
 * The walk is a hash of (id, step), so it does not depend on where a particle lives. */
#include "mpm_particles.h"
#include "mpm_error.h"

#include "mpm_random.h"
#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { NPART = 3000, NSTEPS = 50, NQ = 4 };

static const mpm_field_desc g_fields[4] = {{"x", 0}, {"v", 0}, {"q", NQ}, {"s", 1}};

/* ---- deterministic functions of the id ------------------------------------------------- */

/* Uniform in [0, 1) from (id, step, d). */
static double uniform(mpm_gidx id, int step, int d) {
  return (double)(mpm_test_mix(mpm_test_mix(mpm_test_mix((uint64_t)id) + (uint64_t)step) +
                               (uint64_t)d) >>
                  11) *
         0x1.0p-53;
}

/* Value of component c of field f (not x) for particle id. */
static double value_of(mpm_gidx id, int f, int c) {
  return (double)id * 0.75 + 10.0 * f + c;
}

/* Reflect a coordinate into [lo, hi); a step is shorter than the domain. */
static double reflect(double x, double lo, double hi) {
  if (x < lo) x = 2.0 * lo - x;
  if (x >= hi) x = 2.0 * hi - x;
  return x >= hi ? nextafter(hi, lo) : x;
}

static double walk_step(const mpm_grid *g, mpm_gidx id, int step, int d, double x) {
  if (step == 0)
    return reflect(g->lo[d] + uniform(id, 0, d) * (g->hi[d] - g->lo[d]), g->lo[d], g->hi[d]);
  return reflect(x + (2.0 * uniform(id, step, d) - 1.0) * 1.5 * g->dx, g->lo[d], g->hi[d]);
}

/* Position of particle id after `steps` steps of the walk. */
static void walk_position(const mpm_grid *g, mpm_gidx id, int steps, double *x) {
  for (int d = 0; d < g->dim; ++d) {
    x[d] = walk_step(g, id, 0, d, 0.0);
    for (int s = 1; s <= steps; ++s) x[d] = walk_step(g, id, s, d, x[d]);
  }
}

/* Set every value of particle i from its id, the position after `steps` steps. */
static void set_particle(mpm_particles *p, const mpm_grid *g, mpm_lidx i, int steps) {
  double x[3];
  walk_position(g, p->id[i], steps, x);
  for (int d = 0; d < p->dim; ++d) mpm_particles_comp(p, 0, d)[i] = x[d];
  for (int f = 1; f < p->nfields; ++f)
    for (int c = 0; c < p->field[f].ncomp; ++c)
      mpm_particles_comp(p, f, c)[i] = value_of(p->id[i], f, c);
}

static int particle_ok(const mpm_particles *p, const mpm_grid *g, mpm_lidx i, int steps) {
  double x[3];
  walk_position(g, p->id[i], steps, x);
  for (int d = 0; d < p->dim; ++d)
    if (mpm_particles_comp(p, 0, d)[i] != x[d]) return 0;
  for (int f = 1; f < p->nfields; ++f)
    if (!(p->derived >> f & 1u)) /* a derived field's values are undefined after an edit */
      for (int c = 0; c < p->field[f].ncomp; ++c)
        if (mpm_particles_comp(p, f, c)[i] != value_of(p->id[i], f, c)) return 0;
  return 1;
}

static mpm_particles *new_set(int dim) {
  mpm_field_desc fields[4];
  memcpy(fields, g_fields, sizeof fields);
  fields[0].ncomp = fields[1].ncomp = dim;
  mpm_particles *p = NULL;
  CHECK(mpm_particles_new(&p, dim, fields, 4, 2) == 0, "particles_new");
  return p;
}

static mpm_grid *new_grid(int dim) {
  const double lo2[3] = {0, 0, 0}, hi2[3] = {2.0, 1.5, 0};        /* 16 x 12 cells */
  const double lo3[3] = {-0.5, 0, 0.2}, hi3[3] = {0.5, 0.8, 0.8}; /* 10 x 8 x 6 */
  const int nproc[3] = {0, 0, 0};
  mpm_grid *g = NULL;
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, dim, dim == 2 ? lo2 : lo3, dim == 2 ? hi2 : hi3,
                     dim == 2 ? 0.125 : 0.1, MPM_SHAPE_QUADRATIC, nproc) == 0,
        "grid_new");
  return g;
}

/* ---- local operations ------------------------------------------------------------------ */

/* n particles with ids first, first + 1, ..., at the walk's start. */
static void append_local(mpm_particles *p, const mpm_grid *g, mpm_gidx first, mpm_lidx n) {
  mpm_gidx *id = calloc((size_t)n, sizeof *id);
  double *data = calloc((size_t)n * (size_t)p->ncomp, sizeof *data);
  const mpm_lidx n0 = p->n;
  for (mpm_lidx i = 0; i < n; ++i) id[i] = first + i;
  CHECK(mpm_particles_edit(p, NULL, n, id, data) == 0, "edit append");
  for (mpm_lidx i = n0; i < p->n; ++i) set_particle(p, g, i, 0);
  free(id), free(data);
}

static void test_edit(int dim) {
  mpm_particles *p = new_set(dim);
  mpm_grid *g = new_grid(dim);
  CHECK(mpm_particles_find(p, "q") == 2 && mpm_particles_find(p, "nope") == -1, "find");
  CHECK(p->ncomp == 2 * dim + NQ + 1 && p->nstate == 2 * dim && p->offset[3] == 2 * dim + NQ,
        "layout");
  append_local(p, g, 100, 10);
  unsigned char keep[10] = {1, 0, 1, 1, 0, 1, 1, 1, 1, 0};
  mpm_gidx add_id[2] = {500, 501};
  double add_data[2 * (2 * 3 + NQ + 1)] = {0};
  CHECK(mpm_particles_edit(p, keep, 2, add_id, add_data) == 0, "edit");
  const mpm_gidx want[9] = {100, 102, 103, 105, 106, 107, 108, 500, 501};
  CHECK(p->n == 9, "n = %d", (int)p->n);
  for (mpm_lidx i = 0; i < p->n && i < 9; ++i) {
    CHECK(p->id[i] == want[i], "id %d", (int)i);
    if (i < 7)
      CHECK(particle_ok(p, g, i, 0), "data of %d after edit", (int)i);
    else
      CHECK(mpm_particles_comp(p, 2, 0)[i] == 0.0, "added data");
  }
  memset(keep, 0, sizeof keep);
  CHECK(mpm_particles_edit(p, keep, 0, NULL, NULL) == 0 && p->n == 0, "remove all");
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
  CHECK(!p, "destroy clears the pointer");
}

/* Field q (between v and s) derived: an edit with removals and additions, then a sort, carry
 * x, v and s of every particle. */
static void test_derived(int dim) {
  mpm_particles *p = new_set(dim);
  mpm_grid *g = new_grid(dim);
  mpm_particles_set_derived(p, 2);
  CHECK(p->derived == 4u, "derived mask %u", p->derived);
  append_local(p, g, 100, 200);
  unsigned char keep[200];
  for (int i = 0; i < 200; ++i) keep[i] = i % 7 != 3;
  mpm_gidx add_id[3] = {900, 901, 902};
  double add_data[3 * (2 * 3 + NQ + 1)] = {0};
  CHECK(mpm_particles_edit(p, keep, 3, add_id, add_data) == 0, "edit");
  const mpm_lidx kept = p->n - 3;
  for (mpm_lidx i = kept; i < p->n; ++i) set_particle(p, g, i, 0);
  int bad = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) bad += !particle_ok(p, g, i, 0);
  CHECK(kept == 200 - 29 && bad == 0, "edit with a derived field: %d kept, %d wrong", (int)kept,
        bad);
  CHECK(mpm_particles_sort(p, g) == 0, "sort");
  for (mpm_lidx i = 0; i < p->n; ++i) bad += !particle_ok(p, g, i, 0);
  CHECK(bad == 0, "sort with a derived field: %d wrong", bad);
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

/* Cell key with x fastest, as the header defines the sort order. */
static long cell_key(const mpm_particles *p, const mpm_grid *g, mpm_lidx i) {
  long key = 0;
  for (int d = p->dim - 1; d >= 0; --d) {
    const int c = (int)floor((mpm_particles_comp(p, 0, d)[i] - g->lo[d]) / g->dx);
    key = key * g->ncells[d] + MPM_MIN(c, g->ncells[d] - 1);
  }
  return key;
}

static void test_sort(int dim) {
  mpm_particles *p = new_set(dim);
  mpm_grid *g = new_grid(dim);
  append_local(p, g, 1000 * g_rank, 2000); /* about 10 per cell: many ties */
  CHECK(mpm_particles_sort(p, g) == 0, "sort");
  CHECK(p->n == 2000, "n after sort");
  for (mpm_lidx i = 0; i < p->n; ++i) {
    CHECK(particle_ok(p, g, i, 0), "data of %d after sort", (int)i);
    if (i == 0) continue;
    const long a = cell_key(p, g, i - 1), b = cell_key(p, g, i);
    CHECK(a < b || (a == b && p->id[i - 1] < p->id[i]), "order at %d: keys %ld %ld", (int)i, a, b);
  }
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

/* ---- collective operations ------------------------------------------------------------- */

static int same_on_all_ranks(mpm_gidx v) {
  mpm_gidx lo = v, hi = v;
  MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPM_MPI_GIDX, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPM_MPI_GIDX, MPI_MAX, MPI_COMM_WORLD);
  return lo == hi;
}

/* Inject n particles with zero data; returns the first id this rank should get. */
static mpm_gidx inject(mpm_particles *p, mpm_lidx n) {
  mpm_gidx mine = n, before = 0;
  MPI_Exscan(&mine, &before, 1, MPM_MPI_GIDX, MPI_SUM, MPI_COMM_WORLD);
  if (g_rank == 0) before = 0;
  const mpm_gidx first = p->id_next + before;
  double *zero = calloc((size_t)n * (size_t)p->ncomp + 1, sizeof *zero);
  CHECK(mpm_particles_inject(p, MPI_COMM_WORLD, n, zero) == 0, "inject");
  free(zero);
  return first;
}

static void test_inject(int dim) {
  mpm_particles *p = new_set(dim);
  mpm_gidx total = 0;
  for (int round = 0; round < 3; ++round) {
    const mpm_lidx n = (g_rank + round) % 3, n0 = p->n; /* some ranks add none */
    const mpm_gidx first = inject(p, n);
    for (mpm_lidx i = 0; i < n; ++i) CHECK(p->id[n0 + i] == first + i, "injected id");
    mpm_gidx added = n;
    MPI_Allreduce(MPI_IN_PLACE, &added, 1, MPM_MPI_GIDX, MPI_SUM, MPI_COMM_WORLD);
    total += added;
    CHECK(p->id_next == total && same_on_all_ranks(p->id_next), "id_next %ld", (long)p->id_next);
  }
  mpm_gidx count = -1;
  CHECK(mpm_particles_global_count(p, MPI_COMM_WORLD, &count) == 0 && count == total, "count");
  mpm_particles_destroy(&p);
}

/* Sum of ids and of their squares over all ranks (unsigned: garbage ids must not overflow). */
static void id_sums(const mpm_particles *p, uint64_t sums[2]) {
  sums[0] = sums[1] = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const uint64_t id = (uint64_t)p->id[i];
    sums[0] += id, sums[1] += id * id;
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
}

static void check_state(const mpm_particles *p, const mpm_grid *g, int step) {
  mpm_gidx count = -1;
  uint64_t sums[2];
  const uint64_t n = NPART;
  CHECK(mpm_particles_global_count(p, MPI_COMM_WORLD, &count) == 0 && count == NPART,
        "step %d: %ld particles", step, (long)count);
  id_sums(p, sums);
  CHECK(sums[0] == n * (n - 1) / 2 && sums[1] == (n - 1) * n * (2 * n - 1) / 6, "step %d: id sums",
        step);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double x[3];
    for (int d = 0; d < p->dim; ++d) x[d] = mpm_particles_comp(p, 0, d)[i];
    CHECK(mpm_grid_owner_of(g, x) == g_rank, "step %d: particle %ld on the wrong rank", step,
          (long)p->id[i]);
    CHECK(particle_ok(p, g, i, step), "step %d: data of particle %ld", step, (long)p->id[i]);
  }
}

/* Rank 0 gathers every id; they must be exactly 0 .. NPART-1. */
static void check_all_ids(const mpm_particles *p) {
  int n = (int)p->n, *counts = calloc((size_t)g_size, sizeof *counts);
  int *displs = calloc((size_t)g_size, sizeof *displs);
  mpm_gidx *all = calloc(NPART, sizeof *all);
  MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (int r = 1; r < g_size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  if (g_rank == 0) CHECK(displs[g_size - 1] + counts[g_size - 1] == NPART, "gathered count");
  MPI_Gatherv(p->id, n, MPM_MPI_GIDX, all, counts, displs, MPM_MPI_GIDX, 0, MPI_COMM_WORLD);
  if (g_rank == 0) {
    char *seen = calloc(NPART, 1);
    for (int k = 0; k < NPART; ++k) {
      CHECK(all[k] >= 0 && all[k] < NPART && !seen[all[k]], "id %ld", (long)all[k]);
      if (all[k] >= 0 && all[k] < NPART) seen[all[k]] = 1;
    }
    free(seen);
  }
  free(counts), free(displs), free(all);
}

static void walk(mpm_particles *p, const mpm_grid *g, int step) {
  for (int d = 0; d < p->dim; ++d) {
    double *x = mpm_particles_comp(p, 0, d);
    for (mpm_lidx i = 0; i < p->n; ++i) x[i] = walk_step(g, p->id[i], step, d, x[i]);
  }
}

static void test_migrate(int dim) {
  mpm_particles *p = new_set(dim);
  mpm_grid *g = new_grid(dim);
  const mpm_lidx n = NPART / g_size + (g_rank < NPART % g_size);
  int changed = -1;
  inject(p, n);
  for (mpm_lidx i = 0; i < p->n; ++i) set_particle(p, g, i, 0); /* anywhere in the domain */
  CHECK(mpm_particles_migrate(p, g, &changed) == 0 && changed == (g_size > 1), "first migrate");
  check_state(p, g, 0);
  CHECK(mpm_particles_migrate(p, g, &changed) == 0 && changed == 0, "nothing to move");
  for (int step = 1; step <= NSTEPS; ++step) {
    walk(p, g, step);
    CHECK(mpm_particles_migrate(p, g, &changed) == 0, "migrate at step %d", step);
    if (step % 10 == 0) CHECK(mpm_particles_sort(p, g) == 0, "sort at step %d", step);
    check_state(p, g, step);
  }
  check_all_ids(p);
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

/* Do a and b hold the same particles in the same order, every non-derived value equal? */
static int same_sets(const mpm_particles *a, const mpm_particles *b) {
  if (a->n != b->n) return 0;
  for (mpm_lidx i = 0; i < a->n; ++i)
    if (a->id[i] != b->id[i]) return 0;
  for (int f = 0; f < a->nfields; ++f)
    for (int c = 0; !(a->derived >> f & 1u) && c < a->field[f].ncomp; ++c)
      if (memcmp(mpm_particles_comp(a, f, c), mpm_particles_comp(b, f, c),
                 sizeof(double) * (size_t)a->n) != 0)
        return 0;
  return 1;
}

/* The edit of one step: drop every fifth particle (by id) and add three new ones, placed by
 * the walk anywhere in the domain (so some belong to other ranks). Fills keep (p->n), id and
 * data (component-major, stride 3), all from malloc. */
static void step_edit(const mpm_particles *p, const mpm_grid *g, int step, unsigned char **keep,
                      mpm_gidx **id, double **data) {
  enum { NADD = 3 };
  *keep = malloc((size_t)p->n + 1);
  *id = malloc(sizeof **id * NADD);
  *data = calloc((size_t)p->ncomp * NADD, sizeof **data);
  for (mpm_lidx i = 0; i < p->n; ++i) (*keep)[i] = p->id[i] % 5 != step % 5;
  for (int k = 0; k < NADD; ++k) {
    (*id)[k] = 100000 + 1000 * (mpm_gidx)step + 10 * (mpm_gidx)g_rank + k;
    double x[3];
    walk_position(g, (*id)[k], 0, x);
    for (int d = 0; d < p->dim; ++d) (*data)[(size_t)d * NADD + (size_t)k] = x[d];
    for (int f = 1; f < p->nfields; ++f)
      for (int c = 0; c < p->field[f].ncomp; ++c)
        (*data)[(size_t)(p->offset[f] + c) * NADD + (size_t)k] = value_of((*id)[k], f, c);
  }
}

static void test_deferred(int dim) {
  mpm_particles *a = new_set(dim), *b = new_set(dim);
  mpm_grid *g = new_grid(dim);
  mpm_particles_set_derived(a, 3), mpm_particles_set_derived(b, 3); /* s: not carried */
  const mpm_lidx n = NPART / g_size + (g_rank < NPART % g_size);
  inject(a, n), inject(b, n);
  for (mpm_lidx i = 0; i < n; ++i) set_particle(a, g, i, 0), set_particle(b, g, i, 0);
  int changed = -1;
  CHECK(mpm_particles_migrate(a, g, &changed) == 0 && mpm_particles_migrate(b, g, &changed) == 0,
        "settle");
  for (int step = 1; step <= 6; ++step) {
    /* Steps 1-3 walk (particles cross rank faces); steps 4-6 do not, so the migration moves
     * nothing and applies the deferred edit on its own (apart from the new particles). */
    if (step <= 3) walk(a, g, step), walk(b, g, step);
    unsigned char *keep;
    mpm_gidx *id;
    double *data;
    step_edit(a, g, step, &keep, &id, &data);
    CHECK(mpm_particles_edit(a, keep, 3, id, data) == 0, "edit at step %d", step);
    free(keep), free(id), free(data);
    CHECK(mpm_particles_migrate(a, g, &changed) == 0, "migrate a at step %d", step);
    step_edit(b, g, step, &keep, &id, &data);
    CHECK(mpm_particles_edit_deferred(b, keep, 3, id, data) == 0, "deferred at step %d", step);
    if (step == 2) { /* misuse while pending: an error, and the set untouched */
      const mpm_lidx n0 = b->n;
      CHECK(mpm_particles_edit(b, NULL, 0, NULL, NULL) == MPM_ERR_INTERNAL && b->n == n0,
            "edit while deferred");
      CHECK(mpm_particles_sort(b, g) == MPM_ERR_INTERNAL, "sort while deferred");
    }
    CHECK(mpm_particles_migrate(b, g, &changed) == 0 && !b->later.set, "migrate b at step %d",
          step);
    CHECK(same_sets(a, b), "step %d: deferred edit and migration differ from edit, migration",
          step);
  }
  mpm_particles_destroy(&a), mpm_particles_destroy(&b);
  mpm_grid_destroy(&g);
}

/* One rank holds a particle at x (outside the domain); every rank must get the error. */
static void expect_unphysical(int dim, int bad_rank, double bad_x) {
  mpm_particles *p = new_set(dim);
  mpm_grid *g = new_grid(dim);
  int changed = -1;
  inject(p, 20);
  for (mpm_lidx i = 0; i < p->n; ++i) set_particle(p, g, i, 0);
  if (g_rank == bad_rank) mpm_particles_comp(p, 0, 0)[p->n / 2] = bad_x;
  const int rc = mpm_particles_migrate(p, g, &changed);
  CHECK(rc == MPM_ERR_UNPHYSICAL && changed == 0 && p->n == 20, "migrate returned %d", rc);
  mpm_particles_destroy(&p);
  mpm_grid_destroy(&g);
}

static void test_errors(int dim) {
  if (g_rank == 0) fprintf(stderr, "expected errors follow (%d-D):\n", dim);
  expect_unphysical(dim, g_size - 1, 10.0);
  expect_unphysical(dim, 0, NAN);
  MPI_Barrier(MPI_COMM_WORLD); /* reached only if no rank was left in a collective */
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  for (int dim = 2; dim <= 3; ++dim) {
    test_edit(dim);
    test_derived(dim);
    test_inject(dim);
    test_sort(dim);
    test_migrate(dim);
    test_deferred(dim);
    test_errors(dim);
  }
  mpm_test_finish("test_migrate");
  MPI_Finalize();
  return g_fail != 0;
}
