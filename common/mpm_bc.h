/* Wall conditions on the faces of the domain, for any phase's nodal fields.
 *
 * A face is open (none: a particle crossing it is an error), a slip wall (the normal
 * velocity and acceleration vanish on it), a no-slip wall (all components vanish),
 * periodic (the lattice wraps to the opposite face, which must be periodic too; the grid
 * handles it, so it has no rules here), or one of the gas's open faces (inflow, outflow,
 * subsonic_inflow, subsonic_outflow, farfield; the fluid module applies them). Nodes on a wall face
 * are held; the pad nodes beyond it mirror the nodes inside (see mpm_node_constraints). Rules are
 * built once for a grid; clamps append held nodes. */
#ifndef MPM_BC_H
#define MPM_BC_H

#include "mpm_config.h"
#include "mpm_grid.h"

typedef enum {
  MPM_WALL_NONE,
  MPM_WALL_SLIP,
  MPM_WALL_NO_SLIP,
  MPM_WALL_PERIODIC,
  /* Open faces of the gas (fluid/fluid_boundary.c); for every other phase they are open
   * (none): no node rules here. */
  MPM_WALL_INFLOW,           /* supersonic inflow: the free stream enters */
  MPM_WALL_OUTFLOW,          /* supersonic outflow: the gas leaves */
  MPM_WALL_SUBSONIC_INFLOW,  /* characteristic subsonic inflow */
  MPM_WALL_SUBSONIC_OUTFLOW, /* characteristic subsonic outflow at a back pressure */
  MPM_WALL_FARFIELD,         /* non-reflecting far field */
  MPM_WALL_COUNT
} mpm_wall;

/* The case-file name of a face kind ("slip", "farfield", ...). */
const char *mpm_wall_name(mpm_wall k);
/* Is k one of the gas's open faces (inflow ... farfield)? */
static inline int mpm_wall_is_open_gas(mpm_wall k) {
  return k >= MPM_WALL_INFLOW && k < MPM_WALL_COUNT;
}

typedef struct mpm_walls {
  mpm_wall face[MPM_MAX_DIM][2]; /* [axis][lower, upper] */
} mpm_walls;

/* Keys of the [boundary] section: x_lo, x_hi, y_lo, y_hi, z_lo, z_hi. */
extern const mpm_key_spec mpm_bc_keys[];
extern const int mpm_bc_nkeys;

/* Read the faces; a periodic face whose opposite face is not periodic is an input error. */
int mpm_walls_from_config(mpm_walls *w, const mpm_config *cfg, int dim);
/* periodic[d] = 1 where both faces of axis d are periodic, for d < MPM_MAX_DIM. */
void mpm_walls_periodic(const mpm_walls *w, int *periodic);

/* Node constraints on a grid, applied after every nodal update:
 *  - held nodes (clamps, wall faces): the masked velocity components are set to zero;
 *  - mirrored nodes (pad nodes beyond a wall): the node copies its mirror image inside the
 *    domain, with the sign flipped in the masked components (v_n(-k) = -v_n(k) at a slip
 *    wall, v(-k) = -v(k) at a no-slip wall) and kept in the others. An odd reflection makes
 *    the interpolated velocity vanish at the wall to second order, where zeroing the pad
 *    nodes would shift the wall by a fraction of a cell.
 * Mirror rules are applied axis by axis, so corner nodes mirror through both walls. Mask
 * bit d selects velocity component d. */
typedef struct mpm_node_constraints {
  mpm_lidx count, cap;
  mpm_lidx *node;
  mpm_lidx *source; /* mirror node, or -1 for a held node */
  unsigned char *mask;
} mpm_node_constraints;

/* Hold the masked components of node l at zero. */
int mpm_constraints_add(mpm_node_constraints *c, mpm_lidx l, unsigned char mask);
/* Make pad node l the mirror of node source, the masked components negated. */
int mpm_constraints_add_mirror(mpm_node_constraints *c, mpm_lidx l, mpm_lidx source,
                               unsigned char mask);
/* Add the wall rules of every wall face of w on grid (none and periodic faces have none). */
int mpm_constraints_add_walls(mpm_node_constraints *c, const mpm_walls *w, const mpm_grid *grid);
/* Before the nodal update: fold what particles deposited on mirrored pad nodes into their
 * mirror nodes, as the mirror images of those particles would have deposited it (mass with
 * sign +1, momentum and force with -1 in the masked components and +1 in the others), and
 * clear the pad nodes. Without this the nodes next to a wall miss part of their stencil and
 * the wall costs a first-order error. */
void mpm_constraints_fold(const mpm_node_constraints *c, mpm_grid *grid, int phase);
/* The same fold on mass and momentum arrays of the grid's box (copies of a phase's). */
void mpm_constraints_fold_momentum(const mpm_node_constraints *c, const mpm_grid *grid, double *m,
                                   double *const *mv);
/* After the nodal update: hold and mirror v and a of one phase. */
void mpm_constraints_apply(const mpm_node_constraints *c, mpm_grid *grid, int phase);
void mpm_constraints_free(mpm_node_constraints *c);

/* Global node index of box node l, per axis. */
void mpm_grid_node_global(const mpm_grid *grid, mpm_lidx l, int *gi);

#endif
