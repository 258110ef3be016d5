/* A refinement hierarchy over the shared grid and its conservative composite basis (the
 * truncated hierarchical B-splines of DESIGN.md section 9), for quadratic B-splines.
 *
 * Levels. Level 0 is the shared grid (not owned here). Level l + 1 halves the spacing,
 * h_{l+1} = h_l / 2, and puts its nodes on the nested dual lattice: its origin is
 * o_{l+1} = o_l - h_{l+1} / 2 (o_0 = grid->lo), node j sits at o_{l+1} + j h_{l+1}. A quadratic
 * B-spline's knot spans are the dual cells of the nodes: span i of level l is
 * [o_l + (i - 1/2) h_l, o_l + (i + 1/2) h_l], indexed like node i, and it is exactly spans 2i and
 * 2i + 1 of level l + 1, so the knot vectors nest and level l's B-splines are combinations of
 * level l + 1's (the two-scale relation: coarse node i = 1/4, 3/4, 3/4, 1/4 of fine nodes
 * 2i - 1 .. 2i + 2 per axis; a fine node j = 2m + r has parents m (3/4) and m - 1 + 2r (1/4)).
 *
 * Regions. The region of level l >= 1, Omega_l, is a union of level l - 1 spans; Omega_0 is
 * everything. Omega_{l+1} lies inside Omega_l eroded by `buffer` level-l spans (proper nesting).
 * A point belongs to the finest level whose region contains it (mpm_hier_level_of).
 *
 * Composite basis. Node j of level l is active when its support (spans j - 1 .. j + 1 per axis)
 * lies in Omega_l (always at level 0) and not in Omega_{l+1}. The basis is the active nodes'
 * B-splines, each truncated: written in level l + 1's B-splines (two-scale relation), it loses
 * those whose support lies in Omega_{l+1} (active there, or refined further), and the rest are
 * truncated in turn by the next level. It is never formed: a particle deposits on its own
 * level's lattice with the unchanged kernels (mpm_kernels.h); mpm_hier_restrict() then moves,
 * from the finest level down, every inactive node's value onto its parents with the two-scale
 * weights and zeroes it; the nodal solve runs on the active nodes of every level;
 * mpm_hier_prolong(), the transpose, fills every inactive node from its parents, from level 1
 * up; a particle's G2P reads its own level. The weights are a partition of unity, non-negative
 * and C1 across the interface between levels; the grid's mass and momentum equal the
 * particles' to roundoff, summed over the active nodes of all levels.
 *
 * Storage. Level l >= 1 is one box of nodes per rank, an mpm_grid made by mpm_grid_box_new()
 * (no communicator), so the P2G/G2P kernels run on it unchanged. Its box holds every node
 * whose support meets Omega_l plus one layer. The quadratic B-spline only: mpm_hier_new()
 * refuses anything else with a reason.
 *
 * Ranks. Level 0 is split over the ranks (mpm_grid.h); every rank stores each finer level's
 * whole box, and a rank's particles are those owning their position, as without refinement.
 * The finer levels are kept alike on every rank: after a deposit they hold the rank's own share
 * (mpm_hier_own_share), and the restriction first sums each finer level over the ranks (one
 * MPI_Allreduce per level and field over its box), then restricts; onto a finer level l - 1
 * only rank 0 adds (the level's own sum follows), onto level 0 it goes through the parents box
 * (the level-0 nodes that are parents of level 1's box, alike on every rank) and lands on the
 * level-0 nodes the rank owns (a node's image in [0, ncells) along a periodic axis), so every
 * contribution is added once over the ranks, before level 0's halo sums its ghosts. The
 * prolongation onto level 1 reads the parents box filled by the owners and summed over the
 * ranks, so level 1's inactive nodes are whole on every rank (never read outside level 0's
 * box); the finer prolongations and the nodal solve then run alike on every rank. A rank's
 * level-0 masks cover its box; beyond it, level 0's refined spans are read from level 1's
 * covered mask, so every rank finds the level of any point. On one rank none of this runs.
 *
 * Periodic axes. Along a periodic axis d of the grid, level l's lattice wraps with a period of
 * N_l = ncells[d] 2^l nodes (and spans), and a region may touch, cross or span the periodic
 * faces (a box may then reach up to a period outside the domain along d). The regions and
 * masks are periodic: a span or node index is looked up at its image in [0, N_l). A level whose
 * region comes within two of its nodes of a periodic face (in particular a band spanning the
 * whole period) stores the whole period along d: period[d] = N_l, its box is
 * [-1, N_l + 2^(l-1) + 2] along d, which holds the stencil of every position of the domain, and
 * its nodes outside [0, N_l) are images of those inside, like level 0's ghosts: the restriction
 * first folds (adds) every image into its node and zeroes it, and restricts the nodes in
 * [0, N_l) only; the prolongation fills those and then copies every node into its images.
 * Particles on such a level deposit and read with their position wrapped into the domain along
 * d. Level 0 always has period[d] = ncells[d] along its periodic axes (its halo folds it).
 * Elsewhere period[d] = 0, and nothing changes: a hierarchy that stays clear of the periodic
 * faces computes bit for bit what it did before they were carried.
 *
 * Walls (slip and no-slip faces, given to mpm_hier_new_walled; both phases fold and mirror
 * their nodes there, and a solid's clamps add their own pads, solid/solid_constraints.c). The
 * levels' lattices are symmetric about a wall face: on level 0 the face is a node (node 0, or
 * ncells[d]) and the middle of span 0 (or ncells[d]); on a level l >= 1 it is a knot between two
 * nodes, so node (and span) j mirrors 2^l - 1 - j at the low face and 2 N_l + 2^l - 1 - j at the
 * high face (level 0 alike: -j and 2 ncells[d] - j). The masks are looked up at the mirror for
 * every span beyond a wall, so the regions, masks and composite basis are symmetric about it and a
 * region may touch it (it then reaches past it by half a level-0 span, span 0 straddling the face):
 * the composite basis of the constrained velocity is the even (tangential) or odd (normal)
 * extension across the wall, restricted to the domain. mpm_hier_walls_fold() then adds every
 * finer level's nodes beyond a wall into their mirrors after the restriction, as level 0's wall
 * rules fold its pad nodes, and mpm_hier_walls_apply() sets them from their mirrors after the
 * solve; the prolongation keeps the symmetry (the reflection maps each level's B-splines onto
 * each other). Without walls nothing changes.
 *
 * Masks (one byte per box node of a level, indexed like its nodal fields): covered[l][i] is 1
 * when span i of level l lies in Omega_l, refined[l][i] when it lies in Omega_{l+1}, active[l][i]
 * when node i is active. */
#ifndef MPM_HIER_H
#define MPM_HIER_H

#include "mpm_grid.h"
#include "mpm_kernels.h"
#include "mpm_particles.h"

#include <stddef.h>

#define MPM_HIER_MAX_LEVELS 5   /* level 0 and up to 4 finer levels */
#define MPM_HIER_MIXED      255 /* mpm_hier.leaf: no one level over the span: ask its children */
#define MPM_HIER_WALK       254 /* mpm_hier.leaf: beside a wall: walk down the masks */

/* A refined box: Omega_level (level >= 1) includes every level - 1 span that meets the open
 * box (lo, hi) (the box is snapped outwards to level - 1 spans). */
typedef struct mpm_hier_box {
  int level;
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM];
} mpm_hier_box;

typedef struct mpm_hier_level {
  mpm_grid *grid; /* level 0: the shared grid (not owned); finer levels: owned box grids */
  double inv_h;   /* 1 / grid->dx, for the level lookups (a hot path) */
  unsigned char *covered, *refined, *active;
  int period[MPM_MAX_DIM]; /* nodes per period where the box holds the whole period, else 0 */
  /* Per axis, the indices [plain[d][0], plain[d][1]] in the box that are neither beyond a wall
   * nor images: a span there is its own mirror and image (the masks' lookups, a hot path). */
  int plain[MPM_MAX_DIM][2];
  /* Levels >= 1 with a period: the box nodes that are images (image[k], a box index) and the
   * node in [0, N_l) each is an image of (canon[k]); is_image[n] marks them (NULL: none). */
  mpm_lidx nimage, *image, *canon;
  unsigned char *is_image;
  /* Levels >= 1: the inactive nodes, images left out, within one node of a span of the
   * level's own points (Omega_l less Omega_{l+1}) or within three level-0 cells of a wall (the
   * only ones a deposit on the level reaches), and the parents of level l + 1's (what it
   * restricts onto and prolongs from), in box order, and
   * their 2^dim parents on the lattice the restriction writes (level l - 1's box, or the
   * parents box for level 1 on more than one rank): box indices near_idx[2^dim k ..] and
   * two-scale weights near_w[2^dim k ..]. The restriction and prolongation visit these alone:
   * the other inactive nodes (under a finer level, or between the parts of a region that has
   * several) stay zero. */
  mpm_lidx nnear, *near, *near_idx;
  double *near_w;
} mpm_hier_level;

/* On more than one rank (mpm_hier.h, ranks): level 0's nodes that level 1's nodes have as
 * parents, a box [lo, lo + n) of level 0's lattice, with, for each of its nodes, the level-0
 * box index of the node (or its periodic image) this rank owns, or -1. */
typedef struct mpm_hier_parents_box {
  mpm_grid *grid;  /* the box, as a box grid of level 0's lattice (mpm_grid_box_new) */
  mpm_lidx *owned; /* level-0 box index of the owned node, -1: another rank's */
  double *buf;     /* room for 1 + 3 MPM_MAX_DIM fields over the box */
} mpm_hier_parents_box;

typedef struct mpm_hier {
  int dim, nlevels, buffer;
  /* The ranks of level 0's grid (1: the one-rank code paths, unchanged) and this one's. */
  int nranks, rank;
  mpm_hier_parents_box pbox; /* nranks > 1 only */
  /* nranks > 1: a phase's finer levels hold this rank's own deposit, not yet summed over the
   * ranks (set by mpm_hier_p2g, cleared by mpm_hier_restrict's sum), or hold the sum. */
  unsigned char pending[MPM_GRID_MAX_PHASES], summed[MPM_GRID_MAX_PHASES];
  double *sum_buf; /* nranks > 1: room for the fields a restriction sums (grown, kept) */
  size_t sum_cap;
  /* Components a wall on face [d][side] constrains (bit e: component e flips in the mirror;
   * 0: no wall, the face is not mirrored). */
  unsigned char wall[MPM_MAX_DIM][2];
  int wraps; /* some level >= 1 stores a whole period (mpm_hier_level.period) */
  mpm_hier_level level[MPM_HIER_MAX_LEVELS];
  /* Per level and box span of that level: the level mpm_hier_level_of gives every point
   * inside the span, MPM_HIER_MIXED where it differs within the span (its children on the
   * next level decide), or MPM_HIER_WALK beside a wall (the walk decides there). Lookups in place
   * of the walk: a hot path (every particle, every step). */
  unsigned char *leaf[MPM_HIER_MAX_LEVELS];
  void *scratch; /* private to mpm_hier_transfer.c: levels, their grouping, levels vouched for */
  void *census;  /* private to mpm_hier_census.c: the points mpm_hier_levels saw last */
} mpm_hier;

/* One composite weight of a point: node `node` (box index) of level `level`, its weight and
 * its gradient (physical units, 1/length). */
typedef struct mpm_hier_weight {
  int level;
  mpm_lidx node;
  double w, dw[MPM_MAX_DIM];
} mpm_hier_weight;

/* Build the hierarchy over grid with nlevels levels (1 .. MPM_HIER_MAX_LEVELS; 1 is the grid
 * alone) from nbox boxes, with `buffer` >= 1 level-l spans between Omega_{l+1} and the edge of
 * Omega_l. Mirrors the grid's phases (mpm_hier_add_phases). On bad input returns MPM_ERR_INPUT
 * and writes one sentence into why[why_len] naming the box (by its index in `box`) and what is
 * wrong: a level outside 1 .. nlevels - 1, a box empty or outside the domain, a level without a
 * box, a box not inside the coarser level's region by `buffer` spans or a shape other than the
 * quadratic B-spline. Logs nothing: the caller names the key. On several ranks every rank
 * calls it with the same boxes, and so builds the same finer levels. */
int mpm_hier_new(mpm_hier **h, mpm_grid *grid, int nlevels, const mpm_hier_box *box, int nbox,
                 int buffer, char *why, size_t why_len);
/* The same with walls: wall[d][side] as mpm_hier.wall (NULL: none). A box may then touch a
 * walled face. */
int mpm_hier_new_walled(mpm_hier **h, mpm_grid *grid, int nlevels, const mpm_hier_box *box,
                        int nbox, int buffer, const unsigned char (*wall)[2], char *why,
                        size_t why_len);
void mpm_hier_destroy(mpm_hier **h);

/* The walls on the finer levels (mpm_hier_walls.c): fold adds every node beyond a wall (m, m v
 * and f of the phase, the components the wall constrains negated) into its mirror and zeroes
 * it, after the restriction; apply sets every node beyond a wall to its mirror's v and a (so
 * negated), after the solve. Axis by axis, so a corner node goes through both walls. Level 0's
 * own rules (mpm_bc.h) do the same there. No-ops without walls. */
void mpm_hier_walls_fold(mpm_hier *h, int phase);
void mpm_hier_walls_apply(mpm_hier *h, int phase);
/* The mirror across a wall of axis d of box node n of finer level l (its box index), or -1 when
 * n is not beyond a wall of d or its mirror leaves the box. */
mpm_lidx mpm_hier_wall_mirror(const mpm_hier *h, int l, int d, mpm_lidx n);

/* Give every finer level the phases the grid has and it lacks (after a module adds one). */
int mpm_hier_add_phases(mpm_hier *h);

/* The finest level whose region contains x (wrapped into the domain along the periodic axes
 * when the hierarchy wraps). */
int mpm_hier_level_of(const mpm_hier *h, const double *x);
/* The same, asking level `hint` first (a point's level before it moved: most points stay on
 * it, and then one table lookup answers); any hint, or -1 for none, gives the same answer. */
int mpm_hier_level_from(const mpm_hier *h, const double *x, int hint);
/* The same found by walking down the levels' masks, without mpm_hier.leaf (what the table
 * must reproduce; for tests). */
int mpm_hier_level_walk(const mpm_hier *h, const double *x);

/* The level (mpm_hier_level_of) of each of n points x[d][i], in an array of h's that holds
 * them until the next call (NULL when out of memory). h remembers the points of the last few
 * sets, each by the address x[0], with their levels and a box about each in which every point
 * has that level: a point still inside the box the set's last call had at its index takes the
 * level found then, so a caller asking again at positions that did not move pays one
 * comparison of the arrays, and one that moved them a little a few comparisons per point,
 * whatever other sets were asked about in between (mpm_hier_census.c). */
const unsigned char *mpm_hier_levels(mpm_hier *h, const double *const *x, mpm_lidx n);

/* The set of n points remembered under the address from (its x[0]) was edited and now lives at
 * to: compacted to the points with keep[i] != 0 (n flags, in order, as mpm_particles_edit keeps
 * a set; NULL: every point kept, any added after them). The memory of mpm_hier_levels follows,
 * so that the next call at to looks up only the points that moved or were added. An edit moves
 * a particle set's arrays (their stride is the count), so without this the next call would
 * look every point up again. Forgets the set when it did not hold n points. */
void mpm_hier_levels_keep(mpm_hier *h, const double *from, const double *to,
                          const unsigned char *keep, mpm_lidx n);
/* The level of every particle of p (mpm_hier_level_of at its field "x") into level[p->n]
 * (mpm_hier_census.c). */
void mpm_hier_particle_levels(const mpm_hier *h, const mpm_particles *p, double *level);
/* Add the number of p's particles on level l to count[l], l = 0 .. nlevels - 1 (through
 * mpm_hier_levels). */
void mpm_hier_count_levels(mpm_hier *h, const mpm_particles *p, double *count);

/* The composite basis at x: writes the nonzero weights (each active node once) into w[max]
 * and returns their number (at most 3^dim times the number of levels); -1 if max is too small
 * or x lies so far outside the domain that its stencil leaves level 0's box. */
int mpm_hier_eval(const mpm_hier *h, const double *x, mpm_hier_weight *w, int max);

/* Levels the caller vouches for: until the next call, a composite transfer (mpm_hier_p2g,
 * mpm_hier_g2p) whose positions are the array x0 (its x[0]) with n particles takes level[i]
 * (mpm_hier_level_of of particle i's position, kept by the caller) instead of finding it again.
 * x0 NULL forgets them. The caller calls again, or forgets, before those positions change. */
void mpm_hier_levels_known(mpm_hier *h, const double *x0, mpm_lidx n, const unsigned char *level);
/* The levels vouched for now (x0 NULL: none), to restore after another set's transfers. */
void mpm_hier_levels_vouched(const mpm_hier *h, const double **x0, mpm_lidx *n,
                             const unsigned char **level);

/* Composite P2G of one phase: each particle deposits (a's fields, with the unchanged kernel) on
 * the level mpm_hier_level_of gives for its position; adds, as the kernel does. Follow it with
 * mpm_hier_restrict before the solve. a's index list and wrap (mpm_kernels.h) stay unset: the
 * hierarchy sets them per level (likewise for G2P). */
int mpm_hier_p2g(mpm_hier *h, int phase, const mpm_p2g_args *a);

/* Per-level nodal scalars for a composite G2P: s_i[l][j] is scalar j on level l (level 0's
 * entries are the g2p args' own s_i). */
typedef struct mpm_hier_scalars {
  const double *s_i[MPM_HIER_MAX_LEVELS][MPM_KERNELS_MAX_SCALARS];
} mpm_hier_scalars;

/* Composite G2P: a's v_i and a_i are NULL or the level-0 arrays of `phase` (each level then
 * reads its own); with a->nscalar > 0, s gives every level's scalars (MPM_ERR_INTERNAL if not).
 * Each particle reads the level of its position; the outputs land in a's arrays. Run after
 * mpm_hier_prolong. */
int mpm_hier_g2p(mpm_hier *h, int phase, const mpm_g2p_args *a, const mpm_hier_scalars *s);

/* A nodal velocity of the caller's on every level: v_i[l][d] on level l (level 0's too). */
typedef struct mpm_hier_nodal {
  const double *v_i[MPM_HIER_MAX_LEVELS][MPM_MAX_DIM];
} mpm_hier_nodal;

/* mpm_hier_g2p reading v (v and L_out interpolate it) in place of the phase's v_i on every
 * level (v NULL: mpm_hier_g2p); a_i stays as there. The caller's v must be a composite field:
 * every inactive node the prolongation of its parents (as the phase's v_i after
 * mpm_hier_prolong), so that the particles read the composite basis. */
int mpm_hier_g2p_from(mpm_hier *h, int phase, const mpm_g2p_args *a, const mpm_hier_nodal *v,
                      const mpm_hier_scalars *s);

/* Restrict the deposit of a phase (m, m v, f and the mass gradient where deposited), finest
 * level first; every inactive node ends at zero. */
void mpm_hier_restrict(mpm_hier *h, int phase);
/* Before a deposit of a phase onto the finer levels (mpm_hier_p2g calls it; a caller adding its
 * own per-particle shares calls it too): on more than one rank the finer levels must hold this
 * rank's share alone, for the next mpm_hier_restrict to sum them; a rank other than 0 zeroes a
 * sum they already hold (rank 0 keeps it, so the sum adds it once). No-op on one rank. */
void mpm_hier_own_share(mpm_hier *h, int phase);
/* Prolong a phase's v and a into every inactive node, level 1 first. */
void mpm_hier_prolong(mpm_hier *h, int phase);
/* The same for nf arrays of the caller: fine[k] on level l (>= 1), coarse[k] on level l - 1.
 * On more than one rank the fine arrays hold this rank's share (the restriction sums them over
 * the ranks; a caller computing a finer level's values alike on every rank gives them on rank 0
 * alone, zeros elsewhere), the restriction onto level 0 lands on the nodes this rank owns (call
 * level 0's halo_reverse after it), and the prolongation onto level 1 reads level 0's owned
 * nodes (collective over the grid's communicator). */
void mpm_hier_restrict_level(mpm_hier *h, int l, double *const *fine, double *const *coarse,
                             int nf);
void mpm_hier_prolong_level(mpm_hier *h, int l, const double *const *coarse, double *const *fine,
                            int nf);

/* The nodal solve of one phase on every level (mpm_grid_phase_update's rule, with the largest
 * nodal mass taken over all levels): v = m v / m, a = f / m, v += h a on nodes heavier than the
 * empty threshold, zero elsewhere (inactive nodes, being empty, are filled by the prolongation).
 * Collective over the grid's communicator. */
int mpm_hier_phase_update(mpm_hier *h, int phase, double hstep);

/* Zero a phase's deposit on every level (mpm_grid_phase_zero on each). */
void mpm_hier_phase_zero(mpm_hier *h, int phase);

#endif
