/* test_split_ranks: the gas's split and merge (fluid/fluid_split.h) do not depend on the rank
 * layout, 2-D and 3-D, on any number of ranks.
 *
 * The same random gas (ids 0 .. N-1) is split twice: on a grid of this rank alone holding all
 * of it (the reference, computed on every rank), and on the grid over all ranks, each rank
 * holding the particles of its cells. The parents are those with id % 3 == 0, one of them placed
 * just below a rank boundary, so that some children land in another rank's cells. After the
 * distributed split and a migration, the particles of all ranks, gathered and ordered by id,
 * must equal the reference's bit for bit: the same ids (new ones included), positions and
 * every other field; id_next the same on every rank; no id twice (mpm_particles_find_duplicate).
 * Then each rank merges its particles by parent slot (fluid_merge_groups; gas on the slot
 * lattice, the slots nested in the cells so that a slot's children share a rank): the gathered
 * result must be the original gas, ids bit for bit and fields to 1e-14 relative (the tolerance
 * and its reason as in test_split.c: a merge rounds its sums, and is exact in real
 * arithmetic). */
#include "fluid_internal.h"
#include "fluid_split.h"
#include "mpm_grid.h"
#include "mpm_particles.h"

#include "mpm_random.h"
#include "mpm_testing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double g_lo[3] = {-1.0, 0.0, 0.5}, g_hi[3] = {1.0, 1.6, 2.1}, g_dx = 0.2;
enum { PPC = 2 }; /* slots per cell and axis: H = dx / PPC */

typedef struct gas {
  mpm_module m;
  fluid_content fc;
} gas;

static int gas_make(gas *s, MPI_Comm comm, int dim) {
  memset(s, 0, sizeof *s);
  int size;
  MPI_Comm_size(comm, &size);
  const int nproc[3] = {size, 1, 1}; /* 2 ranks: the boundary at x = 0 */
  if (mpm_grid_new(&s->m.grid, comm, dim, g_lo, g_hi, g_dx, MPM_SHAPE_QUADRATIC, nproc)) return 1;
  s->m.content = &s->fc;
  return fluid_particles_new(&s->m.particles, dim, &s->fc.lay, 1, 1, 1, 1);
}

static void gas_free(gas *s) {
  mpm_particles_destroy(&s->m.particles);
  mpm_grid_destroy(&s->m.grid);
}

/* The whole gas, one particle per slot at its centre (volume H^dim), other fields random; with
 * edge, particle 0 (a parent) moves to just below x = 0, the boundary of the 2-rank split, its
 * children across it. With g, only the particles of this rank's cells are kept. */
static void gas_fill(gas *s, const mpm_grid *g, int edge) {
  mpm_particles *p = s->m.particles;
  const int dim = p->dim;
  const double H = g_dx / PPC;
  int ns[3] = {1, 1, 1};
  mpm_lidx n = 1;
  for (int d = 0; d < dim; ++d) ns[d] = (int)lround((g_hi[d] - g_lo[d]) / H), n *= ns[d];
  double *data = malloc(sizeof *data * (size_t)p->ncomp * (size_t)n);
  mpm_gidx *id = malloc(sizeof *id * (size_t)n);
  unsigned char *keep = malloc((size_t)n);
  uint64_t st = 77;
  for (int q = 0; q < p->ncomp; ++q)
    for (mpm_lidx i = 0; i < n; ++i) data[(size_t)q * n + i] = 2.0 * mpm_test_uniform(&st) - 1.0;
  for (mpm_lidx i = 0; i < n; ++i) {
    mpm_lidx r = i;
    double x[3] = {0};
    for (int d = 0; d < dim; ++d) x[d] = g_lo[d] + ((double)(r % ns[d]) + 0.5) * H, r /= ns[d];
    if (edge && i == 0) x[0] = -0.01, x[1] = g_lo[1] + 0.5 * H; /* in the slot below x = 0 */
    for (int d = 0; d < dim; ++d) {
      data[(size_t)d * n + i] = x[d];
      data[(size_t)(p->offset[FLUID_V] + d) * n + i] += 300.0;
    }
    data[(size_t)p->offset[s->fc.lay.f_m] * n + i] = 0.5 + mpm_test_uniform(&st);
    data[(size_t)p->offset[s->fc.lay.f_V0] * n + i] = pow(H, dim);
    data[(size_t)p->offset[FLUID_J] * n + i] = 1.0;
    data[(size_t)p->offset[FLUID_E] * n + i] = 2e5 * (0.5 + mpm_test_uniform(&st));
    id[i] = i;
    keep[i] = !g || mpm_grid_owner_of(g, x) == g->rank;
  }
  /* Keep this rank's: append all, then drop the others. */
  CHECK(mpm_particles_edit(p, NULL, n, id, data) == 0, "fill");
  CHECK(mpm_particles_edit(p, keep, 0, NULL, NULL) == 0, "keep");
  p->id_next = n;
  free(data), free(id), free(keep);
}

/* The particles with id % 3 == 0. */
static mpm_lidx parents(const mpm_particles *p, mpm_lidx *idx) {
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < p->n; ++i)
    if (p->id[i] % 3 == 0) idx[k++] = i;
  return k;
}

/* Rows (id, then the non-derived components) of every rank's particles, ordered by id, into
 * *rows (from malloc); returns their number. */
typedef struct row {
  mpm_gidx id;
  double v[64];
} row;

static int row_cmp(const void *a, const void *b) {
  const row *x = a, *y = b;
  return (x->id > y->id) - (x->id < y->id);
}

static int ncomp_moved(const mpm_particles *p) {
  return p->offset[p->nfields - 6]; /* the six output fields come last */
}

static mpm_lidx gather(const mpm_particles *p, MPI_Comm comm, row **rows) {
  const int nc = ncomp_moved(p), size_row = (int)sizeof(row);
  row *mine = calloc((size_t)p->n + 1, sizeof *mine);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    mine[i].id = p->id[i];
    for (int q = 0; q < nc; ++q) mine[i].v[q] = p->data[(size_t)q * p->n + i];
  }
  int size, n = (int)p->n * size_row, total = 0;
  MPI_Comm_size(comm, &size);
  int *counts = malloc(sizeof *counts * (size_t)size),
      *displs = malloc(sizeof *displs * (size_t)size);
  MPI_Allgather(&n, 1, MPI_INT, counts, 1, MPI_INT, comm);
  for (int r = 0; r < size; ++r) displs[r] = total, total += counts[r];
  *rows = malloc((size_t)total + 1);
  MPI_Allgatherv(mine, n, MPI_BYTE, *rows, counts, displs, MPI_BYTE, comm);
  qsort(*rows, (size_t)(total / size_row), sizeof(row), row_cmp);
  free(mine), free(counts), free(displs);
  return total / size_row;
}

/* The split on all ranks equals the split on one, bit for bit (ids too). */
static void test_split(int dim) {
  gas ref, dist;
  CHECK(gas_make(&ref, MPI_COMM_SELF, dim) == 0 && gas_make(&dist, MPI_COMM_WORLD, dim) == 0,
        "make");
  CHECK(ncomp_moved(ref.m.particles) <= 64, "row size");
  gas_fill(&ref, NULL, 1);
  gas_fill(&dist, dist.m.grid, 1);
  const mpm_lidx n0 = ref.m.particles->n;
  mpm_lidx *idx = malloc(sizeof *idx * (size_t)n0);
  fluid_split_report r;
  CHECK(fluid_split(&ref.m, idx, parents(ref.m.particles, idx), &r) == 0, "split ref");
  CHECK(fluid_split(&dist.m, idx, parents(dist.m.particles, idx), &r) == 0, "split");
  long away = r.away;
  MPI_Allreduce(MPI_IN_PLACE, &away, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  if (g_size == 2) CHECK(away > 0, "no child crossed a rank boundary");
  CHECK(mpm_particles_migrate(dist.m.particles, dist.m.grid, NULL) == 0, "migrate");
  mpm_gidx dup = 0;
  CHECK(mpm_particles_find_duplicate(MPI_COMM_WORLD, dist.m.particles->id, dist.m.particles->n,
                                     &dup) == 0 &&
            dup == -1,
        "id %lld twice", (long long)dup);
  CHECK(dist.m.particles->id_next == ref.m.particles->id_next, "id_next");
  row *a, *b;
  const mpm_lidx na = gather(ref.m.particles, MPI_COMM_SELF, &a);
  const mpm_lidx nb = gather(dist.m.particles, MPI_COMM_WORLD, &b);
  CHECK(na == nb, "split: %d particles, reference %d", (int)nb, (int)na);
  const int nc = ncomp_moved(ref.m.particles);
  int same = na == nb;
  for (mpm_lidx i = 0; same && i < na; ++i)
    same = a[i].id == b[i].id && memcmp(a[i].v, b[i].v, sizeof(double) * (size_t)nc) == 0;
  CHECK(same, "%dD: the split depends on the rank layout", dim);
  if (g_rank == 0)
    printf("%dD on %d ranks: split of %d particles into %d as on one rank: %s (%ld children "
           "crossed a rank boundary)\n",
           dim, g_size, (int)n0, (int)nb, same ? "yes" : "no", away);
  free(idx), free(a), free(b);
  gas_free(&ref), gas_free(&dist);
}

/* Split, migrate, merge by slot on every rank: the original gas. */
static void test_round_trip(int dim) {
  gas dist;
  CHECK(gas_make(&dist, MPI_COMM_WORLD, dim) == 0, "make");
  gas_fill(&dist, dist.m.grid, 0);
  mpm_particles *p = dist.m.particles;
  row *orig;
  const mpm_lidx n = gather(p, MPI_COMM_WORLD, &orig);
  mpm_lidx *idx = malloc(sizeof *idx * ((size_t)n << dim));
  fluid_split_report r;
  CHECK(fluid_split(&dist.m, idx, parents(p, idx), &r) == 0, "split");
  CHECK(mpm_particles_migrate(p, dist.m.grid, NULL) == 0, "migrate");
  for (mpm_lidx i = 0; i < p->n; ++i) idx[i] = i;
  mpm_lidx *start = NULL, *member = NULL, ng = 0;
  CHECK(fluid_merge_groups(&dist.m, idx, p->n, g_dx / PPC, 0.0, 0, &start, &member, &ng) == 0,
        "groups");
  CHECK(fluid_merge(&dist.m, start, member, ng, &r) == 0, "merge");
  row *c;
  const mpm_lidx nm = gather(p, MPI_COMM_WORLD, &c);
  CHECK(nm == n, "merge: %d particles, %d before the split", (int)nm, (int)n);
  const int nc = ncomp_moved(p);
  double worst = 0;
  for (mpm_lidx i = 0; nm == n && i < n; ++i) {
    CHECK(c[i].id == orig[i].id, "merge: id %lld, was %lld", (long long)c[i].id,
          (long long)orig[i].id);
    for (int q = 0; q < nc; ++q)
      worst = fmax(worst, fabs(c[i].v[q] - orig[i].v[q]) / fmax(fabs(orig[i].v[q]), 1.0));
  }
  CHECK(worst < 1e-14, "%dD: split + merge changed a field by %.3g", dim, worst);
  if (g_rank == 0)
    printf("%dD on %d ranks: split + merge by slot of %d particles, worst field %.2e\n", dim,
           g_size, (int)n, worst);
  free(idx), free(orig), free(c), free(start), free(member);
  gas_free(&dist);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  for (int dim = 2; dim <= 3; ++dim) test_split(dim), test_round_trip(dim);
  const int fail = mpm_test_finish("test_split_ranks");
  MPI_Finalize();
  return fail != 0;
}
