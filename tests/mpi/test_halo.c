/* test_halo: the grid decomposition, ownership and halo exchanges on any rank count.
 *
 * For 2-D and 3-D, every shape kind and several splits (MPI's choice, all ranks along one
 * direction), it checks against an independent recomputation of the header's rules:
 * - layout: cell_split, owned range and box of this rank;
 * - node_is_owned: every lattice node has exactly one owner (sum over ranks is 1);
 * - owner_of: the owner of a point is the rank owning its cell, -1 outside [lo, hi) or NaN;
 * - forward: owner values reach every box node of the lattice, whatever the ghosts held;
 * - reverse: when every rank adds 1 to each lattice node of its box, an owned node ends with
 *   the number of boxes that contain it; garbage outside the lattice never leaks in.
 * It also checks the input errors of mpm_grid_new and the phase fields. */
#include "mpm_grid.h"
#include "mpm_error.h"

#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the rules, recomputed from the header ------------------------------------------- */

static int split_at(const mpm_grid *g, int d, int c) {
  return g->ncells[d] * c / g->nproc[d];
}

/* Owned node range [lo, hi) along d of rank coordinate c. */
static void owned_range(const mpm_grid *g, int d, int c, int *lo, int *hi) {
  *lo = c == 0 ? -g->pad : split_at(g, d, c);
  *hi = c == g->nproc[d] - 1 ? g->ncells[d] + 1 + g->pad : split_at(g, d, c + 1);
}

/* Number of ranks whose box contains global node gi. */
static int boxes_containing(const mpm_grid *g, const int *gi) {
  int count = 1;
  for (int d = 0; d < g->dim; ++d) {
    int along = 0;
    for (int c = 0; c < g->nproc[d]; ++c) {
      int lo, hi;
      owned_range(g, d, c, &lo, &hi);
      along += gi[d] >= lo - g->ghost && gi[d] < hi + g->ghost;
    }
    count *= along;
  }
  return count;
}

static void global_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  for (int d = 0; d < g->dim; ++d) gi[d] = g->box_lo[d] + l % g->box_n[d], l /= g->box_n[d];
}

static int in_lattice(const mpm_grid *g, const int *gi) {
  for (int d = 0; d < g->dim; ++d)
    if (gi[d] < -g->pad || gi[d] > g->ncells[d] + g->pad) return 0;
  return 1;
}

/* Index of a lattice node in a global list of all lattice nodes. */
static long lattice_index(const mpm_grid *g, const int *gi) {
  long idx = 0;
  for (int d = g->dim - 1; d >= 0; --d)
    idx = idx * (g->ncells[d] + 1 + 2 * g->pad) + (gi[d] + g->pad);
  return idx;
}

static long lattice_size(const mpm_grid *g) {
  long n = 1;
  for (int d = 0; d < g->dim; ++d) n *= g->ncells[d] + 1 + 2 * g->pad;
  return n;
}

static double value_of(const int *gi, int field) {
  const double v = gi[0] + 37.0 * gi[1] + 1013.0 * gi[2] + 0.5;
  return field == 0 ? v : -2.0 * v + 7.0;
}

/* ---- checks ---------------------------------------------------------------------------- */

static void check_layout(const mpm_grid *g) {
  int prod = 1;
  for (int d = 0; d < g->dim; ++d) {
    int lo, hi;
    prod *= g->nproc[d];
    for (int c = 0; c <= g->nproc[d]; ++c)
      CHECK(g->cell_split[d][c] == split_at(g, d, c), "split %d %d", d, c);
    owned_range(g, d, g->coord[d], &lo, &hi);
    CHECK(g->own_lo[d] == lo && g->own_hi[d] == hi, "owned range along %d", d);
    CHECK(g->box_lo[d] == lo - g->ghost && g->box_n[d] == hi - lo + 2 * g->ghost, "box %d", d);
    CHECK((g->coord[d] == 0) == (g->nbr[d][0] == MPI_PROC_NULL), "lower neighbour %d", d);
    CHECK((g->coord[d] == g->nproc[d] - 1) == (g->nbr[d][1] == MPI_PROC_NULL), "upper %d", d);
  }
  CHECK(prod == g_size && g->size == g_size && g->rank == g_rank, "ranks %d", prod);
  CHECK(g->ghost == mpm_shape_ghost_width(g->shape) && g->pad == g->ghost, "ghost width");
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    CHECK(mpm_grid_local_index(g, gi) == l, "local index of %d", (int)l);
  }
}

static void check_partition(const mpm_grid *g) {
  const long n = lattice_size(g);
  int *owned = calloc((size_t)n, sizeof *owned);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0}, mine = 1;
    global_of(g, l, gi);
    for (int d = 0; d < g->dim; ++d) mine = mine && gi[d] >= g->own_lo[d] && gi[d] < g->own_hi[d];
    CHECK(mpm_grid_node_is_owned(g, l) == mine, "node_is_owned(%d)", (int)l);
    CHECK(!mine || in_lattice(g, gi), "owned node %d outside the lattice", (int)l);
    if (mine && in_lattice(g, gi)) owned[lattice_index(g, gi)]++;
  }
  MPI_Allreduce(MPI_IN_PLACE, owned, (int)n, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  for (long k = 0; k < n; ++k) CHECK(owned[k] == 1, "lattice node %ld has %d owners", k, owned[k]);
  free(owned);
}

static void fill_forward(const mpm_grid *g, double *const *f) {
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    const int own = mpm_grid_node_is_owned(g, l);
    for (int k = 0; k < 2; ++k) f[k][l] = own ? value_of(gi, k) : NAN;
  }
}

static void check_forward(mpm_grid *g, double *const *f) {
  fill_forward(g, f);
  CHECK(mpm_grid_halo_forward(g, f, 2) == 0, "forward");
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    if (!in_lattice(g, gi)) continue;
    for (int k = 0; k < 2; ++k)
      CHECK(f[k][l] == value_of(gi, k), "forward node (%d, %d, %d) field %d: %g", gi[0], gi[1],
            gi[2], k, f[k][l]);
  }
}

/* Every rank adds 1 (and 2) to each lattice node of its box; garbage elsewhere. */
static void check_reverse(mpm_grid *g, double *const *f) {
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    f[0][l] = in_lattice(g, gi) ? 1.0 : 1e6;
    f[1][l] = in_lattice(g, gi) ? 2.0 : -1e6;
  }
  CHECK(mpm_grid_halo_reverse(g, f, 2) == 0, "reverse");
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    if (!mpm_grid_node_is_owned(g, l)) continue;
    const int want = boxes_containing(g, gi);
    CHECK(f[0][l] == want && f[1][l] == 2.0 * want, "reverse node (%d, %d, %d): %g, %g, want %d",
          gi[0], gi[1], gi[2], f[0][l], f[1][l], want);
  }
  /* Reverse then forward: every lattice node of the box shows its owner's sum. */
  CHECK(mpm_grid_halo_forward(g, f, 2) == 0, "forward after reverse");
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[3] = {0, 0, 0};
    global_of(g, l, gi);
    if (in_lattice(g, gi))
      CHECK(f[0][l] == boxes_containing(g, gi), "round trip (%d, %d, %d)", gi[0], gi[1], gi[2]);
  }
}

/* The cell of x along d as the header defines it, and whether this rank owns it. */
static int owns_point(const mpm_grid *g, const double *x) {
  for (int d = 0; d < g->dim; ++d) {
    int c = (int)floor((x[d] - g->lo[d]) / g->dx);
    if (c >= g->ncells[d]) c = g->ncells[d] - 1;
    if (c < g->cell_split[d][g->coord[d]] || c >= g->cell_split[d][g->coord[d] + 1]) return 0;
  }
  return 1;
}

/* Sample k: cell centres for k < cells, lower cell corners for k < 2 cells, then the top
 * corner just below hi. */
static long sample_count(const mpm_grid *g) {
  long cells = 1;
  for (int d = 0; d < g->dim; ++d) cells *= g->ncells[d];
  return 2 * cells + 1;
}

static void sample_point(const mpm_grid *g, long k, double *x) {
  const long cells = (sample_count(g) - 1) / 2;
  long c = k % cells;
  for (int d = 0; d < g->dim; ++d) {
    const double off = k < cells ? 0.5 : 0.0;
    x[d] = g->lo[d] + ((double)(c % g->ncells[d]) + off) * g->dx;
    if (k == 2 * cells) x[d] = nextafter(g->hi[d], g->lo[d]);
    c /= g->ncells[d];
  }
}

static void check_owner_of(const mpm_grid *g) {
  const long n = sample_count(g);
  int *claims = calloc((size_t)n, sizeof *claims), *lo = calloc((size_t)n, sizeof *lo);
  int *hi = calloc((size_t)n, sizeof *hi);
  double x[3];
  for (long k = 0; k < n; ++k) {
    sample_point(g, k, x);
    const int owner = mpm_grid_owner_of(g, x);
    claims[k] = owner == g_rank, lo[k] = hi[k] = owner;
    CHECK(owner >= 0 && owner < g_size, "owner %d of sample %ld", owner, k);
    CHECK(claims[k] == owns_point(g, x), "owner of sample %ld is %d", k, owner);
  }
  MPI_Allreduce(MPI_IN_PLACE, claims, (int)n, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, lo, (int)n, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, hi, (int)n, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  for (long k = 0; k < n; ++k)
    CHECK(claims[k] == 1 && lo[k] == hi[k], "sample %ld: %d ranks claim it", k, claims[k]);
  free(claims), free(lo), free(hi);
}

/* Points outside [lo, hi) along one direction, or not numbers, have no owner. */
static void check_owner_outside(const mpm_grid *g) {
  const double bad[4] = {NAN, -INFINITY, 0.0, 1e300};
  double x[3];
  for (int d = 0; d < g->dim; ++d) {
    for (int e = 0; e < g->dim; ++e) x[e] = 0.5 * (g->lo[e] + g->hi[e]);
    for (int b = 0; b < 4; ++b) {
      x[d] = b == 2 ? g->hi[d] : bad[b];
      CHECK(mpm_grid_owner_of(g, x) == -1, "point outside along %d (%g)", d, x[d]);
    }
    x[d] = nextafter(g->lo[d], -INFINITY);
    CHECK(mpm_grid_owner_of(g, x) == -1, "point just below lo along %d", d);
  }
}

static void check_phases(mpm_grid *g) {
  for (int k = 0; k < MPM_GRID_MAX_PHASES; ++k) {
    int idx = -1;
    CHECK(mpm_grid_add_phase(g, k ? "solid" : "fluid", &idx) == 0 && idx == k, "phase %d", k);
  }
  if (g_rank == 0) fprintf(stderr, "expected error follows:\n");
  CHECK(mpm_grid_add_phase(g, "extra", NULL) == MPM_ERR_INPUT, "one phase too many");
  mpm_grid_phase *ph = &g->phase[1];
  CHECK(strcmp(ph->name, "solid") == 0, "phase name");
  for (int d = 0; d < MPM_MAX_DIM; ++d)
    CHECK((ph->mv_i[d] && ph->f_i[d] && ph->v_i[d] && ph->a_i[d] && ph->normal_i[d]) ==
              (d < g->dim),
          "phase arrays along %d", d);
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    ph->m_i[l] = ph->mv_i[0][l] = ph->f_i[g->dim - 1][l] = ph->v_i[0][l] = 1.0;
  mpm_grid_phase_zero(g, 1);
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    CHECK(ph->m_i[l] == 0 && ph->mv_i[0][l] == 0 && ph->f_i[g->dim - 1][l] == 0 &&
              ph->v_i[0][l] == 1.0,
          "phase_zero at %d", (int)l);
}

/* ---- driver ---------------------------------------------------------------------------- */

static void run_case(int dim, mpm_shape_kind shape, const int *nproc, int phases) {
  const double lo[3] = {-0.3, 0.1, 1.0}, dx = 0.1;
  const int ncells[3] = {14, 13, 12}; /* >= 3 cells per rank on 4 ranks along any direction */
  double hi[3];
  mpm_grid *g = NULL;
  for (int d = 0; d < 3; ++d) hi[d] = lo[d] + ncells[d] * dx;
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, dim, lo, hi, dx, shape, nproc) == 0, "grid_new");
  if (!g) return;
  for (int d = 0; d < dim; ++d) {
    CHECK(g->ncells[d] == ncells[d], "ncells[%d] = %d", d, g->ncells[d]);
    CHECK(!nproc[d] || g->nproc[d] == nproc[d], "nproc[%d] = %d", d, g->nproc[d]);
  }
  double *f[2] = {calloc((size_t)g->nnodes, sizeof(double)),
                  calloc((size_t)g->nnodes, sizeof(double))};
  check_layout(g);
  check_partition(g);
  check_owner_of(g);
  check_owner_outside(g);
  check_forward(g, f);
  check_reverse(g, f);
  if (phases) check_phases(g);
  free(f[0]), free(f[1]);
  mpm_grid_destroy(&g);
  CHECK(g == NULL, "destroy clears the pointer");
}

static void check_input_errors(void) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, one_cell[3] = {0.1, 1, 1};
  const int auto_split[3] = {0, 0, 0}, too_many[3] = {g_size + 1, 0, 0};
  mpm_grid dummy, *g = &dummy; /* mpm_grid_new must reset it to NULL on failure */
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, hi, 0.3, MPM_SHAPE_LINEAR, auto_split) ==
                MPM_ERR_INPUT &&
            !g,
        "non-integer cell count");
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, hi, -0.1, MPM_SHAPE_LINEAR, auto_split) ==
            MPM_ERR_INPUT,
        "negative dx");
  /* Too few cells for the ghost layers is an error only along a direction that is split:
   * the automatic layout then splits the other direction, an explicit split fails. */
  const int split_x[3] = {g_size, 0, 0};
  const int thin =
      mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, one_cell, 0.1, MPM_SHAPE_QUADRATIC, split_x);
  CHECK(thin == (g_size > 1 ? MPM_ERR_INPUT : 0), "fewer cells than ghost layers: %d", thin);
  mpm_grid_destroy(&g);
  const int along_y =
      mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, one_cell, 0.1, MPM_SHAPE_QUADRATIC, auto_split);
  const int fits = 10 / g_size >= mpm_shape_ghost_width(MPM_SHAPE_QUADRATIC); /* 10 cells in y */
  CHECK(fits ? along_y == 0 && g && g->nproc[0] == 1 && g->nproc[1] == g_size
             : along_y == MPM_ERR_INPUT,
        "one cell along x: the automatic layout splits y where it can (%d)", along_y);
  mpm_grid_destroy(&g);
  CHECK(mpm_grid_new(&g, MPI_COMM_WORLD, 2, lo, hi, 0.1, MPM_SHAPE_LINEAR, too_many) ==
            MPM_ERR_INPUT,
        "more ranks than the run has");
  if (g != &dummy) mpm_grid_destroy(&g);
  mpm_grid_destroy(NULL);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  for (int dim = 2; dim <= 3; ++dim)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) {
      int splits[4][3] = {{0, 0, 0}, {g_size, 1, 1}, {1, g_size, 1}, {1, 1, g_size}};
      for (int k = 0; k < dim + 1; ++k) run_case(dim, (mpm_shape_kind)s, splits[k], !s && !k);
    }
  if (g_rank == 0) fprintf(stderr, "expected input errors follow:\n");
  check_input_errors();
  mpm_test_finish("test_halo");
  MPI_Finalize();
  return g_fail != 0;
}
