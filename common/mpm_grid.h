/* The shared background grid: a Cartesian node lattice split over an MPI Cartesian
 * communicator into boxes, with per-phase nodal fields.
 *
 * Geometry. The domain [lo, hi] holds ncells[d] cells of size dx; node i sits at
 * lo + i dx. Global node indices run over [-pad, ncells + pad]: the pad layers outside the
 * domain exist so that a particle anywhere inside the domain finds every node of its stencil
 * (wall conditions act on them later).
 *
 * Ownership. Rank coordinate c along d owns cells [cell_lo, cell_hi) and the nodes of
 * those cells' lower faces; the last rank along d also owns node ncells, and the first and
 * last ranks own the pad layers on their side. Every node has exactly one owner.
 *
 * Periodic axes. Along a periodic axis the lattice wraps: node i and node i + ncells are
 * the same node, so there are ncells distinct nodes, owned as above except that nobody
 * owns node ncells or pad layers (they are images of nodes near the other face). The
 * ghosts beyond either face are such images: the halo exchanges treat the two faces like a
 * boundary between ranks (with one rank along the axis, a rank exchanges with itself), so
 * a particle near or slightly beyond a periodic face deposits and reads as it would on an
 * unbounded lattice. Positions stay in [lo, hi): mpm_grid_wrap() maps a point that left
 * through a periodic face back in, which migration does before it decides ownership.
 *
 * Box. A rank stores its owned nodes plus `ghost` layers on every side (as wide as the
 * shape function reaches); the local array of one field spans global nodes
 * [box_lo[d], box_lo[d] + box_n[d]) with x fastest. P2G adds into ghost nodes;
 * mpm_grid_halo_reverse() sums ghosts into owners, mpm_grid_halo_forward() copies owners
 * into ghosts. A box is the unit a refinement level will later add over part of a level. */
#ifndef MPM_GRID_H
#define MPM_GRID_H

#include "mpm_shape.h"
#include "mpm_types.h"

#define MPM_GRID_MAX_PHASES 8

/* Nodal fields of one phase (one module), each an array of box nodes. */
typedef struct mpm_grid_phase {
  char name[32];
  double *m_i;               /* mass */
  double *mv_i[MPM_MAX_DIM]; /* momentum */
  double *f_i[MPM_MAX_DIM];  /* force (internal + external) */
  double *v_i[MPM_MAX_DIM];  /* velocity */
  double *a_i[MPM_MAX_DIM];  /* acceleration */
  /* Mass gradient sum_p m_p grad S_i(x_p), deposited by P2G only when `normals` is set (a
   * coupling scheme asks for it). It points out of the phase's material: node i's shape
   * function falls towards the particles beyond it (it is minus the derivative of m_i with
   * respect to the node's position). */
  double *normal_i[MPM_MAX_DIM];
  int normals;
  double m_max;          /* the last nodal solve's largest nodal mass over the whole grid */
  double m_empty;        /* it treated nodes with m_i <= m_empty as empty */
  double empty_fraction; /* m_empty / m_max: 1e-14 (roundoff) unless the module sets it */
  /* A module may also treat as empty the nodes lighter than light_fraction times the mean
   * nodal mass of the phase (over the owned nodes that hold any of it; 0: off). The mean, not
   * the largest, so that one spuriously compressed node cannot empty the rest. */
  double light_fraction;
  double m_mean; /* that mean, at the last nodal solve (when light_fraction > 0) */
  /* Particles per cell, at the cell's lower corner node (mpm_cells.h); NULL until counted. */
  double *cell_n;
  /* Room for a copy of m, m v, f (and the mass gradient): the coupler's velocity preview works
   * on it (coupler/mpm_cycle.c); NULL until first needed. */
  double *shadow;
  /* The nodes the nodal passes visit (MPM_PHASE_FOR): every node of the box unless `narrowed`
   * (mpm_grid_phase_narrow), then the box-relative block [act_lo, act_hi), outside which every
   * nodal field of the phase is zero; held_lo/hi: the block that held mass at the narrowing. */
  int narrowed;
  int act_lo[MPM_MAX_DIM], act_hi[MPM_MAX_DIM];
  int held_lo[MPM_MAX_DIM], held_hi[MPM_MAX_DIM];
} mpm_grid_phase;

typedef struct mpm_grid {
  MPI_Comm comm; /* Cartesian communicator (owned) */
  int rank, size;
  int dim;
  int nproc[MPM_MAX_DIM];  /* ranks per direction */
  int coord[MPM_MAX_DIM];  /* this rank's coordinates */
  int nbr[MPM_MAX_DIM][2]; /* lower, upper neighbour (MPI_PROC_NULL at non-periodic faces) */
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM], dx;
  int ncells[MPM_MAX_DIM];
  int periodic[MPM_MAX_DIM]; /* 1 if the lattice wraps along d (0 beyond dim) */
  mpm_shape_kind shape;
  int ghost, pad;
  int *cell_split[MPM_MAX_DIM]; /* nproc[d]+1 cell offsets: rank c owns [split[c], split[c+1]) */
  int own_lo[MPM_MAX_DIM], own_hi[MPM_MAX_DIM]; /* owned nodes [lo, hi), global indices */
  int box_lo[MPM_MAX_DIM], box_n[MPM_MAX_DIM];  /* stored nodes, owned + ghosts */
  mpm_lidx nnodes;                              /* product of box_n */
  int nphases;
  mpm_grid_phase phase[MPM_GRID_MAX_PHASES];
  void *scratch; /* private to mpm_grid.c: halo message buffers, reused between calls */
} mpm_grid;

/* Build the grid over comm. nproc[d] = 0 lets MPI choose the split. The domain [lo, hi] must
 * be a whole number of cells of size dx (to 1e-9 relative); each rank needs at least `ghost`
 * cells along a split direction, and along a periodic one even when it is not split.
 * periodic[d] != 0 makes axis d periodic; NULL means no periodic axis. Collective. */
int mpm_grid_new_periodic(mpm_grid **grid, MPI_Comm comm, int dim, const double *lo,
                          const double *hi, double dx, mpm_shape_kind shape, const int *nproc,
                          const int *periodic);
/* mpm_grid_new_periodic() with no periodic axis. */
int mpm_grid_new(mpm_grid **grid, MPI_Comm comm, int dim, const double *lo, const double *hi,
                 double dx, mpm_shape_kind shape, const int *nproc);
/* A grid without a communicator (comm = MPI_COMM_NULL, size 1, rank 0) that stores the nodes
 * [box_lo[d], box_lo[d] + box_n[d]) of the lattice with node i at origin + i dx: lo = origin,
 * every stored node is owned, no ghost layers, no neighbours. A refinement level's box
 * (mpm_hier.h): the kernels run on it unchanged; the halo exchanges refuse it
 * (MPM_ERR_INTERNAL). */
int mpm_grid_box_new(mpm_grid **g, int dim, const double *origin, double dx, mpm_shape_kind shape,
                     const int *box_lo, const int *box_n);
void mpm_grid_destroy(mpm_grid **grid);

/* Add a set of nodal fields for a phase; returns its index in *index. */
int mpm_grid_add_phase(mpm_grid *grid, const char *name, int *index);

/* Zero m, mv and f (and the mass gradient, if the phase deposits it) of one phase on every box
 * node. */
void mpm_grid_phase_zero(mpm_grid *grid, int phase);

/* A phase's nodal passes over its active block only (a body of 200 particles substepping in a
 * grid of 20,000 nodes, coupling.time = multirate). narrow sets the block to the nodes holding
 * the phase's mass now or at the last narrowing (whose velocities the solve must clear), two
 * nodes wider on every side, found in one pass over the box; the first narrowing after a
 * widening (whose deposit was zeroed on the whole box) takes the nodes where the last solve
 * left a velocity or an acceleration too. Until it is widened again nothing may write the phase
 * outside the block; the passes that honour it are zero, the nodal solve, and the coupler's load,
 * captures and books (coupler/mpm_cycle.c narrows a loaded solid's phase in its substeps). */
void mpm_grid_phase_narrow(mpm_grid *grid, int phase);
void mpm_grid_phase_widen(mpm_grid *grid, int phase);

/* The span of a phase's passes along axis d: [lo, hi) box-relative (one row beyond dim). */
static inline int mpm_phase_lo(const mpm_grid *g, const mpm_grid_phase *ph, int d) {
  return d < g->dim && ph->narrowed ? ph->act_lo[d] : 0;
}
static inline int mpm_phase_hi(const mpm_grid *g, const mpm_grid_phase *ph, int d) {
  return d >= g->dim ? 1 : ph->narrowed ? ph->act_hi[d] : g->box_n[d];
}
/* The box index of row (j, k)'s first node in the span. */
static inline mpm_lidx mpm_phase_row(const mpm_grid *g, const mpm_grid_phase *ph, int j, int k) {
  const mpm_lidx ny = g->dim > 1 ? g->box_n[1] : 1;
  return ((mpm_lidx)k * ny + j) * g->box_n[0] + mpm_phase_lo(g, ph, 0);
}
/* MPM_PHASE_FOR(g, ph, l) { ... }: every node l of phase ph's span, row by row in index order
 * (`continue` goes to the next node). */
#define MPM_PHASE_FOR(g, ph, l)                                                                    \
  for (int l##_k = mpm_phase_lo(g, ph, 2); l##_k < mpm_phase_hi(g, ph, 2); ++l##_k)                \
    for (int l##_j = mpm_phase_lo(g, ph, 1); l##_j < mpm_phase_hi(g, ph, 1); ++l##_j)              \
      for (mpm_lidx l = mpm_phase_row(g, ph, l##_j, l##_k),                                        \
                    l##_e = l + mpm_phase_hi(g, ph, 0) - mpm_phase_lo(g, ph, 0);                   \
           l < l##_e; ++l)

/* Local (box) index of global node (i, j, k); the caller guarantees it is in the box. */
static inline mpm_lidx mpm_grid_local_index(const mpm_grid *g, const int *gi) {
  mpm_lidx l = gi[g->dim - 1] - g->box_lo[g->dim - 1];
  for (int d = g->dim - 2; d >= 0; --d) l = l * g->box_n[d] + (gi[d] - g->box_lo[d]);
  return l;
}

/* Is box node l owned by this rank? */
int mpm_grid_node_is_owned(const mpm_grid *g, mpm_lidx l);

/* Rank (in grid->comm) that owns the cell containing x; -1 if x is outside [lo, hi). */
int mpm_grid_owner_of(const mpm_grid *g, const double *x);

/* Nodes of a point's stencil at most (the cubic shape in 3-D). */
#define MPM_GRID_STENCIL_MAX (MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT)
/* The stencil of the point x: its nodes (box indices) and shape weights, and with dw non-NULL
 * each weight's derivative along each axis per unit of xi (over dx for a physical gradient);
 * their count, or 0 if the stencil leaves the box. */
int mpm_grid_point_stencil(const mpm_grid *g, const double *x, mpm_lidx *node, double *w,
                           double (*dw)[MPM_MAX_DIM]);

/* Map x back into [lo, hi) along every periodic axis where it lies at most one period
 * outside (a farther point is left alone, for the caller to report). Returns the number of
 * coordinates changed. */
int mpm_grid_wrap(const mpm_grid *g, double *x);

/* Sum ghost contributions into their owners, for nfields box arrays (collective). */
int mpm_grid_halo_reverse(mpm_grid *grid, double *const *fields, int nfields);
/* Copy owner values into the ghosts, for nfields box arrays (collective). */
int mpm_grid_halo_forward(mpm_grid *grid, double *const *fields, int nfields);

#endif
