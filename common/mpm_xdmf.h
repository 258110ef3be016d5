/* The XDMF index of a snapshot series (internal to the output layer; rank 0 only).
 *
 * The index is a list of entries, one per snapshot file snap_NNNNNN.h5, in the order they
 * were added. Each entry keeps its time, its index NNNNNN and its rendered XML block, so
 * that entries kept from an earlier run (read back from the file on a restart) and new
 * ones are written the same way without re-parsing every detail. mpm_xdmf_write() always
 * writes the whole list to PATH.tmp and renames it, so the file on disk is complete XML
 * at every moment.
 *
 * Layout (XDMF 2), chosen so that ParaView's three XDMF readers (XDMFReader, Xdmf3ReaderS,
 * Xdmf3ReaderT) show the same thing and keep it across time steps (verified with 5.11):
 *
 *   Temporal collection "series"
 *     Spatial collection "snap_NNNNNN" with <Time Value="t"/>, one per snapshot
 *       Temporal collection NAME (one per particle phase or grid phase), holding
 *         one Uniform grid NAME with <Time TimeType="Single" Value="t"/>
 *
 * - Block names: both readers rename every uniform grid to a name unique over the whole
 *   file (solid, solid[1], ... one per step), so a block could not be hidden once for all
 *   steps. The one-grid temporal collection around each grid gives the block its place:
 *   XDMFReader names it after the collection ("solid" in every step), Xdmf3ReaderT keeps
 *   its position (Block0, Block1, ...), and Xdmf3ReaderS merges all blocks into one
 *   partitioned dataset anyway. The grid's own Time keeps Xdmf3 from inventing time 0 for
 *   it; TimeType is spelled out so that each entry holds exactly one `<Time Value=` (the
 *   snapshot's), which mpm_rundir.c's scan of series.xmf relies on.
 * - Particles: a Polyvertex topology of N one-point cells whose connectivity 0 .. N-1 is
 *   the dataset /MPM_XDMF_VERTICES/<phase> of the snapshot. Without it Xdmf3 makes no cells
 *   and ParaView's default Surface representation draws nothing.
 * - Colouring: ParaView colours a new source by the active scalars, and the readers make the
 *   first Scalar attribute active. So a phase lists its colour field first (the first of
 *   mpm_xdmf.c's colour fields it has: `rho`) as the only Scalar attribute; its other
 *   one-component fields (and id) are one-column Matrix attributes, which ParaView reads the
 *   same but never makes active, and the velocity follows. Every phase must have it:
 *   Xdmf3ReaderS, which OpenDataFile picks, gives the phases as pieces of one dataset, and
 *   ParaView's geometry filter merges them keeping only the fields every piece has. With rho
 *   in the gas only it was dropped and the whole picture drawn in one colour, white (checked
 *   by tests/verification/test_paraview.py). The output layer therefore writes a solid's
 *   density too (mpm_output.c); at t = 0 the bar (1000 kg/m^3) then stands out from the air.
 *   What XDMF cannot carry (a colour range, a map, the solid drawn on top) is in view.py,
 *   which every run writes beside the index (tools/paraview_view.py).
 * - Tensors: dim x dim fields are row-major (T_xx T_xy T_yx T_yy in 2-D), and ParaView numbers
 *   the components 0 .. ncomp-1 in that order. 9 components are a Tensor (3-D), other counts
 *   (2-D tensors) a Matrix. Each component is also listed by name (F_xx ..., and for
 *   solid_j2.c's history hist: Cp_inv_xx yy zz xy yz xz, eps_p_eq) as a one-column Matrix
 *   whose DataItem is an XDMF HyperSlab of the field's dataset (nothing is stored twice).
 *   XDMFReader reads these; VTK's Xdmf3 readers skip them (they print "Skipping unrecognized
 *   array type" on the terminal, nothing in the GUI) and keep the numbered field. Xdmf3's own
 *   subset syntax (file:/path|start:stride:count:dims) is read by Xdmf3 but is an error in
 *   XDMFReader, so it is not used.
 * - Grid phases are a 3DCoRectMesh (a 2-D lattice one node thick, because VTK's XDMF 2
 *   reader places a 2DCoRectMesh in the y-z plane and mis-sizes the selection of its
 *   2-component node vectors). The output layer keeps them in an index of their own
 *   (grid.xmf): in the particle index the lattice's surface covers the particles, and
 *   Xdmf3ReaderS merges it with them so that no particle field can colour them.
 * - Refinement levels: a refined run's grid.xmf has, per grid phase, a block NAME_grid (level
 *   0) and one NAME_grid_l<l> per finer level, each its own 3DCoRectMesh over that level's
 *   box with m, v and the level's masks active and own (UChar) as attributes; ParaView shows
 *   them as separate blocks of the snapshot's spatial collection (threshold own = 1 to see
 *   each level where it holds the points). */
#ifndef MPM_XDMF_H
#define MPM_XDMF_H

#include <stdint.h>

typedef struct mpm_xdmf mpm_xdmf;

typedef struct mpm_xdmf_field {
  const char *name;
  int ncomp;
} mpm_xdmf_field;

/* Where the output layer writes the Polyvertex connectivity of each phase: the int64
 * dataset /MPM_XDMF_VERTICES/<phase> [n] holding 0 .. n-1. */
#define MPM_XDMF_VERTICES "xdmf"

/* One particle phase of a snapshot: n particles in all; field[0] is the position x. */
typedef struct mpm_xdmf_phase {
  const char *name;
  int64_t n;
  int nfields;
  const mpm_xdmf_field *field;
} mpm_xdmf_phase;

/* Where the output layer writes a refinement hierarchy's levels: the group /MPM_XDMF_LEVELS/<l>
 * holds level l's masks (uint8 active, own) and, for l >= 1, its grid phases. */
#define MPM_XDMF_LEVELS "levels"

/* Nodal mass m and velocity v of one grid phase: n[d] nodes along d (x first; n[2] = 1 in
 * 2-D), node (0,0,0) at origin, uniform spacing. Level 0 is /grid/<name> (block NAME_grid), a
 * finer level l /levels/<l>/<name> (block NAME_grid_l<l>); with masks set, the level's masks
 * /levels/<l>/active and own are attributes too. */
typedef struct mpm_xdmf_mesh {
  const char *name;
  int n[3];
  double origin[3], spacing;
  int level, masks;
} mpm_xdmf_mesh;

int mpm_xdmf_new(mpm_xdmf **x, int dim);
void mpm_xdmf_destroy(mpm_xdmf **x);

/* Read the entries of an existing index at path, keeping those with time <= t_max.
 * *found is 0 if there is no file (not an error). A file that is not an index this module
 * wrote is an input error naming it. */
int mpm_xdmf_load(mpm_xdmf *x, const char *path, double t_max, int *found);

/* Append the entry of snapshot `index` (file snap_NNNNNN.h5 beside the index). Phases with
 * no particles are left out, since an empty Polyvertex grid upsets readers (Xdmf3ReaderT's
 * block positions after it shift for that step). */
int mpm_xdmf_add(mpm_xdmf *x, double time, int index, const mpm_xdmf_phase *phase, int nphases,
                 const mpm_xdmf_mesh *mesh, int nmeshes);

/* Write the index atomically (path.tmp, then rename). */
int mpm_xdmf_write(const mpm_xdmf *x, const char *path);

int mpm_xdmf_count(const mpm_xdmf *x);
/* One past the largest index listed, or 0 when empty. */
int mpm_xdmf_next_index(const mpm_xdmf *x);

#endif
