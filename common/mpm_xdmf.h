/* The XDMF index of a snapshot series (internal to the output layer; rank 0 only).
 *
 * The index is a list of entries, one per snapshot file snap_NNNNNN.h5, in the order they
 * were added. Each entry keeps its time, its index NNNNNN and its rendered XML block, so
 * that entries kept from an earlier run (read back from series.xmf on a restart) and new
 * ones are written the same way without re-parsing every detail. mpm_xdmf_write() always
 * writes the whole list to PATH.tmp and renames it, so the file on disk is complete XML
 * at every moment.
 *
 * Layout (XDMF 2, which ParaView's default reader handles): a temporal collection of
 * spatial collections, one per snapshot, holding a Polyvertex grid per particle phase and a
 * CoRectMesh per grid phase. A 2-D lattice is written as a 3DCoRectMesh one node thick,
 * because VTK's XDMF 2 reader places a 2DCoRectMesh in the y-z plane and mis-sizes the
 * selection of its 2-component node vectors. */
#ifndef MPM_XDMF_H
#define MPM_XDMF_H

#include <stdint.h>

typedef struct mpm_xdmf mpm_xdmf;

typedef struct mpm_xdmf_field {
  const char *name;
  int ncomp;
} mpm_xdmf_field;

/* One particle phase of a snapshot: n particles in all; field[0] is the position x. */
typedef struct mpm_xdmf_phase {
  const char *name;
  int64_t n;
  int nfields;
  const mpm_xdmf_field *field;
} mpm_xdmf_phase;

/* Nodal mass m and velocity v of one grid phase: n[d] nodes along d (x first; n[2] = 1 in
 * 2-D), node (0,0,0) at origin, uniform spacing. */
typedef struct mpm_xdmf_mesh {
  const char *name;
  int n[3];
  double origin[3], spacing;
} mpm_xdmf_mesh;

int mpm_xdmf_new(mpm_xdmf **x, int dim);
void mpm_xdmf_destroy(mpm_xdmf **x);

/* Read the entries of an existing index at path, keeping those with time <= t_max.
 * *found is 0 if there is no file (not an error). A file that is not an index this module
 * wrote is an input error naming it. */
int mpm_xdmf_load(mpm_xdmf *x, const char *path, double t_max, int *found);

/* Append the entry of snapshot `index` (file snap_NNNNNN.h5 beside the index). Phases with
 * no particles are left out, since an empty Polyvertex grid upsets readers. */
int mpm_xdmf_add(mpm_xdmf *x, double time, int index, const mpm_xdmf_phase *phase, int nphases,
                 const mpm_xdmf_mesh *mesh, int nmeshes);

/* Write the index atomically (path.tmp, then rename). */
int mpm_xdmf_write(const mpm_xdmf *x, const char *path);

int mpm_xdmf_count(const mpm_xdmf *x);
/* One past the largest index listed, or 0 when empty. */
int mpm_xdmf_next_index(const mpm_xdmf *x);

#endif
