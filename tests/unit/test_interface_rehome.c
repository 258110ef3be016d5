/* test_interface_rehome: the partitioned schemes' owed momentum after a solid advance
 * (mpm_interface_rehome, coupler/mpm_interface.h), on any number of ranks.
 *
 * The solid's nodal mass rises with the node's global index, m = 1 + i + 10 j on the lattice
 * (0 elsewhere, and 0 on the lattice's first node, which is no node's heaviest neighbour), so the
 * heaviest node of the 3 x 3 block around (i, j) is (i + 1, j + 1), clipped to the lattice. Every
 * owned lattice node owes a distinct impulse. The rule, recomputed here on the global lattice:
 *  - where the mass is not below its value at the start of the advance and not zero, the
 *    impulse stays, bit for bit;
 *  - elsewhere it moves whole to that heaviest node (on another rank too), unless that is the
 *    node itself;
 *  - the total owed momentum is unchanged (to roundoff: the moves are sums);
 *  - with no mass fallen anywhere (and none zero) nothing changes at all.
 * The result must not depend on the decomposition: each rank checks the gathered lattice. */
#include "mpm_error.h"
#include "mpm_grid.h"
#include "mpm_interface.h"

#include "mpm_testing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NX = 16, NY = 8 }; /* cells */

static void global_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  for (int d = 0; d < g->dim; ++d) gi[d] = g->box_lo[d] + (int)(l % g->box_n[d]), l /= g->box_n[d];
}

/* The lattice: global nodes -pad .. ncells + pad along each axis. */
static int lattice_n(const mpm_grid *g, int d) {
  return g->ncells[d] + 1 + 2 * g->pad;
}
static long lattice_index(const mpm_grid *g, const int *gi) {
  for (int d = 0; d < 2; ++d)
    if (gi[d] < -g->pad || gi[d] > g->ncells[d] + g->pad) return -1;
  return (long)(gi[1] + g->pad) * lattice_n(g, 0) + (gi[0] + g->pad);
}

/* zero: the lattice's first node has no mass. */
static double mass_at(const mpm_grid *g, const int *gi, int zero) {
  if (lattice_index(g, gi) < 0 || (zero && gi[0] == -g->pad && gi[1] == -g->pad)) return 0.0;
  return 1.0 + (gi[0] + g->pad) + 10.0 * (gi[1] + g->pad);
}
/* Did the mass fall during the advance here? (every third node, by the global index) */
static int fell(const int *gi) {
  return ((gi[0] + 2 * gi[1]) % 3 + 3) % 3 == 0;
}
static double impulse_at(const int *gi, int d) {
  return d == 0 ? 1.0 + 0.01 * gi[0] + 0.37 * gi[1] : -2.0 + 0.13 * gi[0] - 0.05 * gi[1];
}

/* Set up the interface's fields; fall: the every-third-node pattern and the massless node, else
 * no node fell and every lattice node has mass. */
static void setup(mpm_grid *g, int phase, mpm_interface *ifc, const unsigned char *owned,
                  int fall) {
  double *m = g->phase[phase].m_i;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[2];
    global_of(g, l, gi);
    m[l] = mass_at(g, gi, fall);
    ifc->m_start[l] = m[l] + (fall && fell(gi) ? 1.0 : 0.0);
    for (int d = 0; d < 2; ++d)
      ifc->impulse[d][l] = owned[l] && lattice_index(g, gi) >= 0 ? impulse_at(gi, d) : 0.0;
  }
}

/* The owned nodes' impulses on the whole lattice (summed over the ranks). */
static void gather(const mpm_grid *g, const mpm_interface *ifc, const unsigned char *owned,
                   double *out) {
  const long n = (long)lattice_n(g, 0) * lattice_n(g, 1);
  memset(out, 0, sizeof *out * 2 * (size_t)n);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[2];
    global_of(g, l, gi);
    const long k = lattice_index(g, gi);
    if (!owned[l] || k < 0) continue;
    for (int d = 0; d < 2; ++d) out[2 * k + d] = ifc->impulse[d][l];
  }
  MPI_Allreduce(MPI_IN_PLACE, out, (int)(2 * n), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_grid *g = NULL;
  const double lo[2] = {0.0, 0.0}, hi[2] = {NX * 0.25, NY * 0.25};
  const int nproc[2] = {0, 0};
  int phase = -1;
  mpm_interface *ifc = NULL;
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, hi, 0.25, MPM_SHAPE_QUADRATIC, nproc) == 0, "grid");
  CHECK(mpm_grid_add_phase(g, "solid", &phase) == 0, "phase");
  CHECK(mpm_interface_new(&ifc, g, phase) == 0, "interface");
  if (g_fail) return mpm_test_finish("test_interface_rehome");
  unsigned char *owned = malloc((size_t)g->nnodes);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) owned[l] = (unsigned char)mpm_grid_node_is_owned(g, l);
  const int nx = lattice_n(g, 0), ny = lattice_n(g, 1);
  const long n = (long)nx * ny;
  double *got = malloc(sizeof *got * 2 * (size_t)n), *want = calloc(2 * (size_t)n, sizeof *want);
  double *before = malloc(sizeof *before * 2 * (size_t)n);

  /* No mass fell: nothing moves, bit for bit. */
  setup(g, phase, ifc, owned, 0);
  gather(g, ifc, owned, before);
  CHECK(mpm_interface_rehome(ifc, owned) == 0, "rehome");
  gather(g, ifc, owned, got);
  CHECK(memcmp(got, before, sizeof *got * 2 * (size_t)n) == 0,
        "with no mass fallen the owed momentum changed");

  /* Every third node lost mass, one has none: the rule, recomputed on the lattice. */
  setup(g, phase, ifc, owned, 1);
  gather(g, ifc, owned, before);
  memcpy(want, before, sizeof *want * 2 * (size_t)n);
  int moves = 0;
  for (int j = -g->pad; j <= g->ncells[1] + g->pad; ++j)
    for (int i = -g->pad; i <= g->ncells[0] + g->pad; ++i) {
      const int s[2] = {i, j};
      if (!(fell(s) || mass_at(g, s, 1) == 0.0)) continue;
      const int t[2] = {i < g->ncells[0] + g->pad ? i + 1 : i,
                        j < g->ncells[1] + g->pad ? j + 1 : j};
      const long ks = lattice_index(g, s), kt = lattice_index(g, t);
      if (kt == ks) continue;
      for (int d = 0; d < 2; ++d)
        want[2 * kt + d] += before[2 * ks + d], want[2 * ks + d] -= before[2 * ks + d];
      ++moves;
    }
  CHECK(mpm_interface_rehome(ifc, owned) == 0, "rehome");
  gather(g, ifc, owned, got);
  double total[2] = {0, 0}, total0[2] = {0, 0}, worst = 0.0;
  for (long k = 0; k < n; ++k)
    for (int d = 0; d < 2; ++d) {
      total[d] += got[2 * k + d], total0[d] += before[2 * k + d];
      worst = fmax(worst, fabs(got[2 * k + d] - want[2 * k + d]));
    }
  CHECK(moves > 50, "the pattern moves too little to test (%d moves)", moves);
  CHECK(worst <= 1e-13, "an owed impulse differs from the rule's by %.3g", worst);
  for (int d = 0; d < 2; ++d)
    CHECK(fabs(total[d] - total0[d]) <= 1e-12 * fabs(total0[d]),
          "total owed momentum %d changed: %.17g -> %.17g", d, total0[d], total[d]);
  if (g_rank == 0)
    printf("%d moves on a %d x %d lattice; largest difference from the rule %.3g; total owed "
           "(%.6g, %.6g) -> (%.6g, %.6g)\n",
           moves, nx, ny, worst, total0[0], total0[1], total[0], total[1]);

  free(got), free(want), free(before), free(owned);
  mpm_interface_destroy(&ifc);
  mpm_grid_destroy(&g);
  const int rc = mpm_test_finish("test_interface_rehome");
  MPI_Finalize();
  return rc != 0;
}
