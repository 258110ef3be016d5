/* The distributed background grid: Cartesian decomposition, box layout, nodal fields and
 * the halo exchanges. mpm_grid.h states the contract (ownership, box layout); this file
 * keeps these invariants:
 *
 * - grid->comm is a Cartesian communicator, periodic along the periodic axes, made with
 *   reorder = 0, so a rank number means the same in grid->comm as in the communicator the
 *   caller passed.
 * - Along d, coordinate c owns cells [cell_split[d][c], cell_split[d][c+1]) with
 *   cell_split[d][c] = (ncells * c) / nproc, so every rank owns at least
 *   floor(ncells / nproc) >= ghost cells: a ghost layer only ever reaches the next rank
 *   (along a periodic axis the next rank may be across the face, or this rank itself).
 * - The box is [own_lo - ghost, own_hi + ghost) per direction. Directions d >= dim are
 *   degenerate (box_lo = own_lo = 0, box_n = own_hi = 1) so that loops can always run over
 *   three indices.
 * - Neighbours along d have the same owned range in every other direction, hence the same
 *   box_n there: a slab has the same size on both ends of a message.
 * - The halo exchanges go one direction at a time over slabs that span the whole box in
 *   the other directions, ghosts included. What moved along direction 0 is then carried
 *   along direction 1, and so on, so edge and corner values reach diagonal neighbours in
 *   dim steps with face neighbours only.
 * - Periodic axes need nothing special in the exchanges: the box is still own ± ghost, a
 *   slab is addressed in box-local indices, and rank 0's lower ghosts [-ghost, 0) are the
 *   images of the last rank's top owned layers [ncells - ghost, ncells), which is exactly
 *   where a box-local slab sent to the lower (wrapped) neighbour lands. */
#include "mpm_grid.h"
#include "mpm_error.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char g_axis[MPM_MAX_DIM] = {'x', 'y', 'z'};

/* Fail on an input error that every rank detects alike: one message (from rank 0), not one
 * per rank. */
#define FAIL_INPUT(...)                                                                            \
  do {                                                                                             \
    mpm_log(MPM_LOG_ERROR, __VA_ARGS__);                                                           \
    return mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT);                                 \
  } while (0)

/* Send and receive buffers of the halo exchanges, grown on demand and kept between calls
 * because the exchanges run several times per step. */
typedef struct halo_scratch {
  double *send, *recv;
  size_t cap; /* doubles in each buffer */
} halo_scratch;

/* ---- construction ---------------------------------------------------------------------- */

/* Cells per direction from the domain and dx; the domain must be a whole number of cells. */
static int count_cells(int dim, const double *lo, const double *hi, double dx, int *ncells) {
  if (dim < 1 || dim > MPM_MAX_DIM) FAIL_INPUT("grid: dimension %d is not 1-3", dim);
  if (!(dx > 0) || !isfinite(dx))
    FAIL_INPUT("grid: the cell size dx = %g must be positive and finite", dx);
  for (int d = 0; d < dim; ++d) {
    const double r = (hi[d] - lo[d]) / dx, n = nearbyint(r);
    if (r > INT_MAX / 4)
      FAIL_INPUT("grid: the domain [%g, %g] along %c holds %.6g cells of size dx = %g, more than "
                 "the %d cells per direction a grid can index; coarsen grid.dx or shrink the "
                 "domain",
                 lo[d], hi[d], g_axis[d], r, dx, INT_MAX / 4);
    if (!(n >= 1) || fabs(r - n) > 1e-9 * fabs(r))
      FAIL_INPUT("grid: the domain [%g, %g] along %c holds %.12g cells of size dx = %g; it must "
                 "hold a positive whole number of cells: change the domain bounds or dx",
                 lo[d], hi[d], g_axis[d], r, dx);
    ncells[d] = (int)n;
  }
  return 0;
}

/* Does a layout leave every rank at least `ghost` cells along each split or periodic
 * direction (see check_cells_per_rank)? */
static int layout_fits(const mpm_grid *g, const int *dims) {
  for (int d = 0; d < g->dim; ++d)
    if ((dims[d] > 1 || g->periodic[d]) && g->ncells[d] / dims[d] < g->ghost) return 0;
  return 1;
}

/* The halo a layout exchanges: the cut faces, in cells (periodic axes are cut once more). */
static double layout_cost(const mpm_grid *g, const int *dims) {
  double cost = 0;
  for (int d = 0; d < g->dim; ++d) {
    double face = 1;
    for (int e = 0; e < g->dim; ++e)
      if (e != d) face *= g->ncells[e];
    cost += (dims[d] - 1 + (g->periodic[d] && dims[d] > 1)) * face;
  }
  return cost;
}

/* Every layout with the given counts fixed whose product is size: keep the one that fits with
 * the smallest halo (ties: the earlier axis gets more ranks, as MPI_Dims_create orders). */
static void layout_search(const mpm_grid *g, int size, const int *fixed, int d, int *dims,
                          int *best, double *best_cost) {
  if (d == g->dim) {
    if (size != 1 || !layout_fits(g, dims)) return;
    const double c = layout_cost(g, dims);
    if (c < *best_cost) {
      *best_cost = c;
      for (int e = 0; e < g->dim; ++e) best[e] = dims[e];
    }
    return;
  }
  for (int n = size; n >= 1; --n) {
    if (size % n != 0 || (fixed[d] > 0 && n != fixed[d])) continue;
    dims[d] = n;
    layout_search(g, size / n, fixed, d + 1, dims, best, best_cost);
  }
}

/* Ranks per direction: the caller's where given; elsewhere the layout with the smallest halo
 * among those that leave every rank enough cells, so any rank count that can run the grid
 * does. If none fits, MPI's balanced choice goes on to check_cells_per_rank, which says why. */
static int choose_nproc(mpm_grid *g, int size, const int *nproc) {
  int given = 1, all = 1, fixed[MPM_MAX_DIM] = {0, 0, 0}, dims[MPM_MAX_DIM] = {1, 1, 1};
  for (int d = 0; d < g->dim; ++d) {
    fixed[d] = nproc ? nproc[d] : 0;
    if (fixed[d] < 0) FAIL_INPUT("grid: %d ranks along %c", fixed[d], g_axis[d]);
    if (fixed[d] > 0) given *= fixed[d];
    all = all && fixed[d] > 0;
  }
  if (all ? given != size : size % given != 0)
    FAIL_INPUT("grid: the requested ranks per direction (product %d) do not fit the %d rank%s "
               "of the run; give counts whose product is the number of ranks, or 0 to let MPI "
               "choose",
               given, size, size == 1 ? "" : "s");
  double cost = HUGE_VAL;
  layout_search(g, size, fixed, 0, dims, g->nproc, &cost);
  if (cost < HUGE_VAL) return 0;
  /* None fits: name the most ranks that do (with the counts the caller fixed, if any). */
  int fit = 0, best[MPM_MAX_DIM] = {1, 1, 1}, free_fixed[MPM_MAX_DIM] = {0, 0, 0};
  const int *keep = given > 1 ? fixed : free_fixed;
  for (int r = size - 1; r >= 1 && !fit; --r) {
    layout_search(g, r, keep, 0, dims, best, &cost);
    if (cost < HUGE_VAL) fit = r;
  }
  if (fit)
    FAIL_INPUT("grid: no layout of %d ranks leaves every rank the %d cells per split direction "
               "that the %s shape needs (the grid has %d x %d%s cells); run on at most %d rank%s "
               "(grid.ranks = %d %d%s), or refine the grid",
               size, g->ghost, mpm_shape_name(g->shape), g->ncells[0], g->ncells[1],
               g->dim == 3 ? " x ..." : "", fit, fit == 1 ? "" : "s", best[0], best[1],
               g->dim == 3 ? " ..." : "");
  for (int d = 0; d < g->dim; ++d) g->nproc[d] = fixed[d];
  MPM_CALL_MPI(MPI_Dims_create(size, g->dim, g->nproc)); /* check_cells_per_rank says why */
  return 0;
}

/* Along a split direction every rank needs at least `ghost` cells, so that a halo slab
 * comes from the next rank only (see the file comment). An unsplit direction has no halo,
 * unless it is periodic: then the one rank's ghosts are images of its own owned layers,
 * which must exist. */
static int check_cells_per_rank(const mpm_grid *g) {
  for (int d = 0; d < g->dim; ++d) {
    if (!(g->nproc[d] > 1 || g->periodic[d]) || g->ncells[d] / g->nproc[d] >= g->ghost) continue;
    if (g->nproc[d] == 1)
      FAIL_INPUT("grid: the periodic axis %c has %d cells, fewer than the %d ghost layers of the "
                 "%s shape; a periodic axis needs at least %d cells: use a finer grid, a longer "
                 "domain or a narrower shape",
                 g_axis[d], g->ncells[d], g->ghost, mpm_shape_name(g->shape), g->ghost);
    FAIL_INPUT("grid: %d cells along %c over %d ranks leave %d cells on some rank, fewer than "
               "the %d ghost layers of the %s shape; use fewer ranks or a finer grid",
               g->ncells[d], g_axis[d], g->nproc[d], g->ncells[d] / g->nproc[d], g->ghost,
               mpm_shape_name(g->shape));
  }
  return 0;
}

static int make_comm(mpm_grid *g, MPI_Comm comm) {
  int periods[MPM_MAX_DIM] = {0, 0, 0};
  for (int d = 0; d < g->dim; ++d) periods[d] = g->periodic[d];
  /* reorder = 0: rank numbers stay those of comm, which callers rely on. */
  MPM_CALL_MPI(MPI_Cart_create(comm, g->dim, g->nproc, periods, 0, &g->comm));
  MPM_CALL_MPI(MPI_Comm_rank(g->comm, &g->rank));
  MPM_CALL_MPI(MPI_Comm_size(g->comm, &g->size));
  MPM_CALL_MPI(MPI_Cart_coords(g->comm, g->rank, g->dim, g->coord));
  for (int d = 0; d < g->dim; ++d)
    MPM_CALL_MPI(MPI_Cart_shift(g->comm, d, 1, &g->nbr[d][0], &g->nbr[d][1]));
  return 0;
}

/* cell_split, owned range and box of this rank, per the header's ownership rule: the ends
 * of a non-periodic axis own the pad layers (and node ncells), those of a periodic one
 * do not. */
static int make_layout(mpm_grid *g) {
  double nnodes = 1; /* a double: the product of huge extents must not overflow */
  for (int d = 0; d < g->dim; ++d) {
    const int np = g->nproc[d], c = g->coord[d];
    MPM_ALLOC(g->cell_split[d], np + 1);
    for (int k = 0; k <= np; ++k) g->cell_split[d][k] = (int)((long long)g->ncells[d] * k / np);
    const int ends = !g->periodic[d];
    g->own_lo[d] = ends && c == 0 ? -g->pad : g->cell_split[d][c];
    g->own_hi[d] = ends && c == np - 1 ? g->ncells[d] + 1 + g->pad : g->cell_split[d][c + 1];
    g->box_lo[d] = g->own_lo[d] - g->ghost;
    g->box_n[d] = g->own_hi[d] - g->own_lo[d] + 2 * g->ghost;
    nnodes *= g->box_n[d];
  }
  if (nnodes > INT32_MAX)
    MPM_FAIL(MPM_ERR_INPUT,
             "grid: %.6g nodes on one rank exceed the local index range (%d); use more ranks or "
             "a coarser grid.dx",
             nnodes, INT32_MAX);
  g->nnodes = (mpm_lidx)nnodes;
  return 0;
}

/* Directions beyond dim: one node, owned, no neighbours. */
static void set_unused_dims(mpm_grid *g) {
  for (int d = 0; d < MPM_MAX_DIM; ++d) {
    g->nbr[d][0] = g->nbr[d][1] = MPI_PROC_NULL;
    g->nproc[d] = 1;
    g->box_n[d] = g->own_hi[d] = 1;
  }
}

static int grid_setup(mpm_grid *g, MPI_Comm comm, const double *lo, const double *hi, double dx,
                      const int *nproc) {
  int size;
  MPM_CALL(count_cells(g->dim, lo, hi, dx, g->ncells));
  MPM_CALL_MPI(MPI_Comm_size(comm, &size));
  MPM_CALL(choose_nproc(g, size, nproc));
  MPM_CALL(check_cells_per_rank(g));
  for (int d = 0; d < g->dim; ++d) g->lo[d] = lo[d], g->hi[d] = hi[d];
  g->dx = dx;
  MPM_CALL(make_comm(g, comm));
  int rc = make_layout(g);
  if (!rc && !(g->scratch = calloc(1, sizeof(halo_scratch))))
    rc = mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_MEMORY);
  /* A failure from here on may be local: agree on it, so no rank keeps a grid alone. */
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &rc, 1, MPI_INT, MPI_MAX, g->comm));
  MPM_CALL(rc);
  return 0;
}

int mpm_grid_new_periodic(mpm_grid **grid, MPI_Comm comm, int dim, const double *lo,
                          const double *hi, double dx, mpm_shape_kind shape, const int *nproc,
                          const int *periodic) {
  mpm_grid *g;
  *grid = NULL;
  if ((unsigned)shape >= MPM_SHAPE_COUNT)
    FAIL_INPUT("grid: unknown shape function kind %d", (int)shape);
  MPM_ALLOC(g, 1);
  g->comm = MPI_COMM_NULL;
  set_unused_dims(g);
  g->dim = dim;
  for (int d = 0; periodic && d < dim && d < MPM_MAX_DIM; ++d) g->periodic[d] = periodic[d] != 0;
  g->shape = shape;
  g->ghost = g->pad = mpm_shape_ghost_width(shape);
  const int rc = grid_setup(g, comm, lo, hi, dx, nproc);
  if (rc) {
    mpm_grid_destroy(&g);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *grid = g;
  return 0;
}

int mpm_grid_new(mpm_grid **grid, MPI_Comm comm, int dim, const double *lo, const double *hi,
                 double dx, mpm_shape_kind shape, const int *nproc) {
  return mpm_grid_new_periodic(grid, comm, dim, lo, hi, dx, shape, nproc, NULL);
}

/* The box grid's lattice: the stored nodes are owned; lo is node 0, hi and ncells the last
 * stored node (at least 1), and one split per axis, so the ownership queries answer rank 0. */
static int box_setup(mpm_grid *g, const double *origin, double dx, const int *box_lo,
                     const int *box_n) {
  double nnodes = 1;
  for (int d = 0; d < g->dim; ++d) {
    if (box_n[d] < 1)
      MPM_FAIL(MPM_ERR_INPUT, "grid: a box of %d nodes along %c is empty", box_n[d], g_axis[d]);
    g->lo[d] = origin[d];
    g->ncells[d] = MPM_MAX(1, box_lo[d] + box_n[d] - 1);
    g->hi[d] = origin[d] + g->ncells[d] * dx;
    MPM_ALLOC(g->cell_split[d], 2);
    g->cell_split[d][0] = 0, g->cell_split[d][1] = g->ncells[d];
    g->box_lo[d] = g->own_lo[d] = box_lo[d];
    g->box_n[d] = box_n[d];
    g->own_hi[d] = box_lo[d] + box_n[d];
    nnodes *= box_n[d];
  }
  if (nnodes > INT32_MAX)
    MPM_FAIL(MPM_ERR_INPUT, "grid: a box of %.6g nodes exceeds the local index range (%d)", nnodes,
             INT32_MAX);
  g->nnodes = (mpm_lidx)nnodes;
  return 0;
}

int mpm_grid_box_new(mpm_grid **grid, int dim, const double *origin, double dx,
                     mpm_shape_kind shape, const int *box_lo, const int *box_n) {
  mpm_grid *g;
  *grid = NULL;
  if ((unsigned)shape >= MPM_SHAPE_COUNT)
    FAIL_INPUT("grid: unknown shape function kind %d", (int)shape);
  if (dim < 1 || dim > MPM_MAX_DIM) FAIL_INPUT("grid: dimension %d is not 1-3", dim);
  if (!(dx > 0) || !isfinite(dx))
    FAIL_INPUT("grid: the cell size dx = %g must be positive and finite", dx);
  MPM_ALLOC(g, 1);
  g->comm = MPI_COMM_NULL;
  set_unused_dims(g);
  g->size = 1;
  g->dim = dim;
  g->shape = shape;
  g->dx = dx;
  const int rc = box_setup(g, origin, dx, box_lo, box_n);
  if (rc) {
    mpm_grid_destroy(&g);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *grid = g;
  return 0;
}

static void phase_free(mpm_grid_phase *ph) {
  free(ph->m_i);
  for (int d = 0; d < MPM_MAX_DIM; ++d) {
    free(ph->mv_i[d]), free(ph->f_i[d]), free(ph->v_i[d]);
    free(ph->a_i[d]), free(ph->normal_i[d]);
  }
  free(ph->cell_n);
  free(ph->shadow);
  memset(ph, 0, sizeof *ph);
}

void mpm_grid_destroy(mpm_grid **grid) {
  if (!grid || !*grid) return;
  mpm_grid *g = *grid;
  for (int p = 0; p < g->nphases; ++p) phase_free(&g->phase[p]);
  for (int d = 0; d < MPM_MAX_DIM; ++d) free(g->cell_split[d]);
  halo_scratch *s = g->scratch;
  if (s) free(s->send), free(s->recv), free(s);
  if (g->comm != MPI_COMM_NULL) MPI_Comm_free(&g->comm);
  free(g);
  *grid = NULL;
}

/* ---- nodal fields ---------------------------------------------------------------------- */

static int phase_alloc(mpm_grid_phase *ph, int dim, mpm_lidx n) {
  MPM_ALLOC(ph->m_i, n);
  for (int d = 0; d < dim; ++d) {
    MPM_ALLOC(ph->mv_i[d], n);
    MPM_ALLOC(ph->f_i[d], n);
    MPM_ALLOC(ph->v_i[d], n);
    MPM_ALLOC(ph->a_i[d], n);
    MPM_ALLOC(ph->normal_i[d], n);
  }
  return 0;
}

int mpm_grid_add_phase(mpm_grid *grid, const char *name, int *index) {
  if (grid->nphases >= MPM_GRID_MAX_PHASES)
    FAIL_INPUT("grid: cannot add phase '%s': at most %d phases", name ? name : "",
               MPM_GRID_MAX_PHASES);
  mpm_grid_phase *ph = &grid->phase[grid->nphases];
  const int rc = phase_alloc(ph, grid->dim, grid->nnodes);
  if (rc) {
    phase_free(ph);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  snprintf(ph->name, sizeof ph->name, "%s", name ? name : "");
  ph->empty_fraction = 1e-14;
  if (index) *index = grid->nphases;
  grid->nphases++;
  return 0;
}

/* Zero n nodes from l of the deposit's arrays. */
static void zero_rows(mpm_grid_phase *ph, int dim, mpm_lidx l, mpm_lidx n) {
  const size_t bytes = (size_t)n * sizeof(double);
  memset(ph->m_i + l, 0, bytes);
  for (int d = 0; d < dim; ++d) memset(ph->mv_i[d] + l, 0, bytes), memset(ph->f_i[d] + l, 0, bytes);
  for (int d = 0; ph->normals && d < dim; ++d) memset(ph->normal_i[d] + l, 0, bytes);
}

void mpm_grid_phase_zero(mpm_grid *grid, int phase) {
  mpm_grid_phase *ph = &grid->phase[phase];
  if (!ph->narrowed) {
    zero_rows(ph, grid->dim, 0, grid->nnodes);
    return;
  }
  const mpm_lidx n = ph->act_hi[0] - ph->act_lo[0];
  if (n <= 0) return; /* (an empty block: none of the phase on this rank) */
  for (int k = mpm_phase_lo(grid, ph, 2); k < mpm_phase_hi(grid, ph, 2); ++k)
    for (int j = mpm_phase_lo(grid, ph, 1); j < mpm_phase_hi(grid, ph, 1); ++j)
      zero_rows(ph, grid->dim, mpm_phase_row(grid, ph, j, k), n);
}

/* The smallest block holding both a and b (box-relative [lo, hi) pairs; lo >= hi is empty). */
static void block_union(int dim, const int *alo, const int *ahi, const int *blo, const int *bhi,
                        int *lo, int *hi) {
  int aempty = 0, bempty = 0;
  for (int d = 0; d < dim; ++d) aempty |= alo[d] >= ahi[d], bempty |= blo[d] >= bhi[d];
  for (int d = 0; d < dim; ++d) {
    lo[d] = aempty ? blo[d] : bempty ? alo[d] : alo[d] < blo[d] ? alo[d] : blo[d];
    hi[d] = aempty ? bhi[d] : bempty ? ahi[d] : ahi[d] > bhi[d] ? ahi[d] : bhi[d];
  }
}

/* The block [lo, hi) of the box nodes where any of the n arrays is not zero, widened by pad
 * nodes on every side within the box (lo >= hi on some axis: none). */
static void nonzero_block(const mpm_grid *grid, const double *const *arr, int n, int pad, int *lo,
                          int *hi) {
  const int dim = grid->dim, nx = grid->box_n[0];
  const int ny = dim > 1 ? grid->box_n[1] : 1, nz = dim > 2 ? grid->box_n[2] : 1;
  int c[3];
  for (int d = 0; d < dim; ++d) lo[d] = grid->box_n[d], hi[d] = 0;
  for (c[2] = 0; c[2] < nz; ++c[2])
    for (c[1] = 0; c[1] < ny; ++c[1]) {
      const mpm_lidx r = ((mpm_lidx)c[2] * ny + c[1]) * nx;
      int first = -1, last = -1;
      for (int k = 0; k < n; ++k) {
        const double *row = arr[k] + r;
        for (int i = 0; i < nx; ++i)
          if (row[i] != 0.0) last = i > last ? i : last, first = first < 0 || i < first ? i : first;
      }
      if (first < 0) continue;
      c[0] = first;
      for (int d = 0; d < dim; ++d) lo[d] = c[d] < lo[d] ? c[d] : lo[d];
      c[0] = last;
      for (int d = 0; d < dim; ++d) hi[d] = c[d] + 1 > hi[d] ? c[d] + 1 : hi[d];
    }
  for (int d = 0; d < dim; ++d)
    if (lo[d] < hi[d]) {
      lo[d] = lo[d] - pad > 0 ? lo[d] - pad : 0;
      hi[d] = hi[d] + pad < grid->box_n[d] ? hi[d] + pad : grid->box_n[d];
    }
}

void mpm_grid_phase_narrow(mpm_grid *grid, int phase) {
  mpm_grid_phase *ph = &grid->phase[phase];
  const int dim = grid->dim, pad = 2;
  int lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
  /* the block of the nodes holding mass (over the whole box: a particle may have left the
   * block since the last narrowing) */
  const double *m = ph->m_i;
  nonzero_block(grid, &m, 1, pad, lo, hi);
  if (!ph->narrowed) {
    /* The first narrowing after a widening. The deposit before it was zeroed on the whole box,
     * so m, m v and f hold nothing outside the mass block; the solve's v and a may, where the
     * phase held mass at its last solve: the block takes those nodes too (one pass over the
     * box, against every pass of this cycle over the whole box). */
    const double *va[2 * MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) va[d] = ph->v_i[d], va[dim + d] = ph->a_i[d];
    int vlo[MPM_MAX_DIM], vhi[MPM_MAX_DIM];
    nonzero_block(grid, va, 2 * dim, pad, vlo, vhi);
    block_union(dim, vlo, vhi, lo, hi, ph->act_lo, ph->act_hi);
  } else {
    block_union(dim, ph->held_lo, ph->held_hi, lo, hi, ph->act_lo, ph->act_hi);
  }
  for (int d = 0; d < dim; ++d) ph->held_lo[d] = lo[d], ph->held_hi[d] = hi[d];
  ph->narrowed = 1;
}

void mpm_grid_phase_widen(mpm_grid *grid, int phase) {
  grid->phase[phase].narrowed = 0;
}

/* ---- ownership ------------------------------------------------------------------------- */

int mpm_grid_node_is_owned(const mpm_grid *g, mpm_lidx l) {
  for (int d = 0; d < g->dim; ++d) {
    const int gi = g->box_lo[d] + (int)(l % g->box_n[d]);
    l /= g->box_n[d];
    if (gi < g->own_lo[d] || gi >= g->own_hi[d]) return 0;
  }
  return 1;
}

/* Rank coordinate owning cell c: the last k with split[k] <= c (split is increasing). */
static int coord_of_cell(const int *split, int np, int c) {
  int a = 0, b = np;
  while (b - a > 1) {
    const int m = (a + b) / 2;
    if (split[m] <= c)
      a = m;
    else
      b = m;
  }
  return a;
}

int mpm_grid_owner_of(const mpm_grid *g, const double *x) {
  int coords[MPM_MAX_DIM], rank, own = 1;
  for (int d = 0; d < g->dim; ++d) {
    if (!(x[d] >= g->lo[d] && x[d] < g->hi[d])) return -1; /* also rejects NaN */
    int c = (int)((x[d] - g->lo[d]) / g->dx);              /* the floor: the quotient is >= 0 */
    if (c >= g->ncells[d]) c = g->ncells[d] - 1;           /* x just below hi may round up */
    const int *split = g->cell_split[d], mine = g->coord[d];
    const int in = c >= split[mine] && c < split[mine + 1]; /* most particles stay */
    coords[d] = in ? mine : coord_of_cell(split, g->nproc[d], c);
    own &= in;
  }
  if (own) return g->rank; /* most particles stay: no MPI call for them */
  if (MPI_Cart_rank(g->comm, coords, &rank) != MPI_SUCCESS) return -1;
  return rank;
}

/* One period at most: a point farther out is a runaway particle, for migration to report
 * rather than to hide. Roundoff may land a wrapped point on the excluded face hi, which
 * is the same point as lo; or just below lo, which is lo up to roundoff. */
static int wrap_coord(double *x, double lo, double hi) {
  const double len = hi - lo, x0 = *x;
  if (x0 >= hi && x0 < hi + len)
    *x = fmax(x0 - len, lo);
  else if (x0 < lo && x0 >= lo - len)
    *x = x0 + len < hi ? x0 + len : lo;
  else
    return 0;
  return 1;
}

int mpm_grid_wrap(const mpm_grid *g, double *x) {
  int n = 0;
  for (int d = 0; d < g->dim; ++d)
    if (g->periodic[d]) n += wrap_coord(&x[d], g->lo[d], g->hi[d]);
  return n;
}

/* ---- halo exchange --------------------------------------------------------------------- */

/* Box-local index ranges of a slab: [start, start + ghost) along d, the whole box across. */
typedef struct slab {
  int lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
} slab;

static slab slab_along(const mpm_grid *g, int d, int start) {
  slab s;
  for (int e = 0; e < MPM_MAX_DIM; ++e) s.lo[e] = 0, s.hi[e] = g->box_n[e];
  s.lo[d] = start, s.hi[d] = start + g->ghost;
  return s;
}

static size_t slab_nodes(const slab *s) {
  size_t n = 1;
  for (int e = 0; e < MPM_MAX_DIM; ++e) n *= (size_t)(s->hi[e] - s->lo[e]);
  return n;
}

/* Start of the x-row (j, k) of a box array. */
static double *box_row(const mpm_grid *g, double *f, int j, int k) {
  return f + ((size_t)k * (size_t)g->box_n[1] + (size_t)j) * (size_t)g->box_n[0];
}

static void slab_pack(const mpm_grid *g, const slab *s, double *const *fields, int nfields,
                      double *buf) {
  const size_t nx = (size_t)(s->hi[0] - s->lo[0]);
  for (int f = 0; f < nfields; ++f)
    for (int k = s->lo[2]; k < s->hi[2]; ++k)
      for (int j = s->lo[1]; j < s->hi[1]; ++j, buf += nx)
        memcpy(buf, box_row(g, fields[f], j, k) + s->lo[0], nx * sizeof *buf);
}

/* Write a packed slab into the fields: added (reverse) or copied (forward). */
static void slab_unpack(const mpm_grid *g, const slab *s, double *const *fields, int nfields,
                        const double *buf, int add) {
  const size_t nx = (size_t)(s->hi[0] - s->lo[0]);
  for (int f = 0; f < nfields; ++f)
    for (int k = s->lo[2]; k < s->hi[2]; ++k)
      for (int j = s->lo[1]; j < s->hi[1]; ++j, buf += nx) {
        double *row = box_row(g, fields[f], j, k) + s->lo[0];
        if (add)
          for (size_t i = 0; i < nx; ++i) row[i] += buf[i];
        else
          memcpy(row, buf, nx * sizeof *buf);
      }
}

/* Make room for the largest message of an exchange of nfields arrays. */
static int scratch_reserve(mpm_grid *g, int nfields) {
  halo_scratch *s = g->scratch;
  size_t need = 0;
  for (int d = 0; d < g->dim; ++d) {
    const slab sl = slab_along(g, d, 0);
    need = MPM_MAX(need, slab_nodes(&sl) * (size_t)nfields);
  }
  if (need > INT_MAX)
    MPM_FAIL(MPM_ERR_INPUT, "grid: a halo message of %zu values is too large for MPI", need);
  if (need <= s->cap) return 0;
  free(s->send), free(s->recv);
  s->cap = 0;
  MPM_ALLOC(s->send, need);
  MPM_ALLOC(s->recv, need);
  s->cap = need;
  return 0;
}

/* One direction of an exchange, both ways. For side 0 the slab at send_at[0] goes to the
 * lower neighbour while the upper neighbour's message lands in the slab at recv_at[0];
 * side 1 mirrors it. Beyond a non-periodic face the neighbour is MPI_PROC_NULL and Sendrecv
 * does nothing there; across a periodic face it may be this rank, which Sendrecv handles
 * (the send and receive buffers are distinct). */
static int exchange_dir(mpm_grid *g, int d, double *const *fields, int nfields,
                        const int send_at[2], const int recv_at[2], int add) {
  halo_scratch *s = g->scratch;
  for (int side = 0; side < 2; ++side) {
    const int to = g->nbr[d][side], from = g->nbr[d][1 - side], tag = 100 + 2 * d + side;
    const slab out = slab_along(g, d, send_at[side]), in = slab_along(g, d, recv_at[side]);
    const int count = (int)(slab_nodes(&out) * (size_t)nfields);
    if (to != MPI_PROC_NULL) slab_pack(g, &out, fields, nfields, s->send);
    MPM_CALL_MPI(MPI_Sendrecv(s->send, count, MPI_DOUBLE, to, tag, s->recv, count, MPI_DOUBLE, from,
                              tag, g->comm, MPI_STATUS_IGNORE));
    if (from != MPI_PROC_NULL) slab_unpack(g, &in, fields, nfields, s->recv, add);
  }
  return 0;
}

/* A box grid (mpm_grid_box_new) has no neighbours to exchange with: calling an exchange on
 * it is a bug of the caller. */
static int check_halo(const mpm_grid *grid) {
  if (grid->comm == MPI_COMM_NULL)
    MPM_FAIL(MPM_ERR_INTERNAL, "grid: a halo exchange on a box grid, which has no communicator");
  return 0;
}

int mpm_grid_halo_reverse(mpm_grid *grid, double *const *fields, int nfields) {
  const int gw = grid->ghost;
  MPM_CALL(check_halo(grid));
  MPM_CALL(scratch_reserve(grid, nfields));
  for (int d = 0; d < grid->dim; ++d) {
    const int n = grid->box_n[d];
    /* My ghosts [0, g) and [n-g, n) are the neighbours' outermost owned layers. */
    const int send_at[2] = {0, n - gw}, recv_at[2] = {n - 2 * gw, gw};
    MPM_CALL(exchange_dir(grid, d, fields, nfields, send_at, recv_at, 1));
  }
  return 0;
}

int mpm_grid_halo_forward(mpm_grid *grid, double *const *fields, int nfields) {
  const int gw = grid->ghost;
  MPM_CALL(check_halo(grid));
  MPM_CALL(scratch_reserve(grid, nfields));
  for (int d = 0; d < grid->dim; ++d) {
    const int n = grid->box_n[d];
    /* My outermost owned layers are the neighbours' ghosts. */
    const int send_at[2] = {gw, n - 2 * gw}, recv_at[2] = {n - gw, 0};
    MPM_CALL(exchange_dir(grid, d, fields, nfields, send_at, recv_at, 0));
  }
  return 0;
}

int mpm_grid_point_stencil(const mpm_grid *g, const double *x, mpm_lidx *node, double *w,
                           double (*dw)[MPM_MAX_DIM]) {
  const int dim = g->dim, sup = mpm_shape_support(g->shape);
  int base[MPM_MAX_DIM];
  double xi[MPM_MAX_DIM], wt[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT],
      dwt[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT];
  for (int d = 0; d < dim; ++d) xi[d] = (x[d] - g->lo[d]) / g->dx;
  mpm_shape_eval(g->shape, dim, xi, 0.0, base, wt, dwt);
  const int count = dim == 2 ? sup * sup : sup * sup * sup;
  for (int k = 0; k < count; ++k) {
    int gi[MPM_MAX_DIM];
    double W = 1.0;
    for (int d = 0, r = k; d < dim; r /= sup, ++d) {
      gi[d] = base[d] + r % sup;
      if (gi[d] < g->box_lo[d] || gi[d] >= g->box_lo[d] + g->box_n[d]) return 0;
      W *= wt[d][r % sup];
    }
    for (int e = 0; dw && e < dim; ++e) {
      double D = 1.0;
      for (int d = 0, r = k; d < dim; r /= sup, ++d) D *= d == e ? dwt[d][r % sup] : wt[d][r % sup];
      dw[k][e] = D;
    }
    node[k] = mpm_grid_local_index(g, gi), w[k] = W;
  }
  return count;
}
