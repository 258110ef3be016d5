/* Output: parallel HDF5 snapshots with an XDMF index, and atomic checkpoints.
 *
 * Snapshot OUTDIR/snap_NNNNNN.h5 (written collectively, to a temporary name, then renamed):
 *   /                 attributes time (double), step (int64), dim (int), config (string:
 *                     the resolved case text), version (string)
 *   /<phase>/id       int64 [N]
 *   /<phase>/<field>  double [N][ncomp] for every particle field (x is [N][dim])
 *   /grid/<phase>/m, /grid/<phase>/v  (optional) nodal mass [Nz][Ny][Nx] and velocity
 *                     [Nz][Ny][Nx][dim] over the global node lattice including pad layers
 *   /xdmf/<phase>     int64 [N] = 0 .. N-1, the connectivity of the phase's Polyvertex
 *                     grid in series.xmf (phase names 'grid' and 'xdmf' are reserved)
 * With a refinement hierarchy (mpm_output_set_hier; nothing of this otherwise):
 *   /<phase>/level    double [N][1], the level of each particle's position (mpm_hier_level_of)
 *   /levels/<l>       (with the grid fields) for l = 0 .. nlevels - 1: attributes level (int),
 *                     origin (double [dim], the position of the datasets' first node) and
 *                     spacing; masks active (node l is active) and own (its span lies in
 *                     level l's region and no finer one's: the points of level l), uint8
 *                     [Nz][Ny][Nx]. Level 0's lattice is /grid's; a finer level's is its box.
 *   /levels/<l>/<phase>/m, v  (l >= 1) that level's nodal mass and velocity, as /grid's
 *                     ('levels' is then a reserved phase name, 'level' a reserved field)
 * OUTDIR/series.xmf indexes the particles of every snapshot written so far, OUTDIR/grid.xmf
 * the grid fields of those that have them (absent when none has; with a hierarchy, one block
 * per phase and level); mpm_xdmf.h gives their layout. Both are rewritten atomically after each
 * snapshot, so they are valid XML at every moment.
 *
 * Checkpoint (any path; written to PATH.tmp, then renamed by rank 0 once complete):
 *   /  attributes format ("mpmfsi checkpoint 2"), config (string), text_hash (uint64, FNV-1a
 *      of format and config), nranks (int), and named double attributes from the caller
 *   /<phase>/id int64 [N], /<phase>/data double [ncomp][N] (component-major, rank order),
 *   /<phase>/counts int64 [nranks] particles per writing rank, /<phase> attributes dim,
 *   field_names, field_ncomp, text_hash (of field_names), id_next.
 *   HDF5 1.10 file format (checksummed superblock, object headers and chunk indexes); every
 *   non-empty dataset chunked with the Fletcher32 filter. A reader refuses altered bytes and
 *   invalid contents (non-finite values, a negative step or h_next, ids repeated or not
 *   below id_next, fields outside their module's ranges) as MPM_ERR_INPUT with one line
 *   naming the file; format-1 files (no checksums) are still read and validated. */
#ifndef MPM_OUTPUT_H
#define MPM_OUTPUT_H

#include "mpm_grid.h"
#include "mpm_hier.h"
#include "mpm_particles.h"

typedef struct mpm_output mpm_output;

/* Prepare output into dir (created by rank 0 if missing). config_text is stored in every
 * file. Collective. If append is set (a restart), the XDMF index keeps the snapshots listed
 * in an existing series.xmf with time <= t_restart. */
int mpm_output_new(mpm_output **out, MPI_Comm comm, const char *dir, const char *config_text,
                   int dim, int append, double t_restart);
void mpm_output_destroy(mpm_output **out);

/* Write one snapshot of nphases particle sets; grid may be NULL (no grid fields); the grid
 * phases written are those whose names match a particle phase. Collective. */
int mpm_output_snapshot(mpm_output *out, double t, long step, const mpm_particles *const *phases,
                        const char *const *names, int nphases, const mpm_grid *grid);

/* Number of snapshots written (or kept from an earlier run); the next gets this index. */
int mpm_output_count(const mpm_output *out);

/* Write the refinement hierarchy h (NULL: none, the default) with every later snapshot: the
 * particles' level and, beside the grid fields, the levels (layout above). h must outlive
 * the output's use of it; on more than one rank it is refused (MPM_ERR_INTERNAL). */
int mpm_output_set_hier(mpm_output *out, const mpm_hier *h);

/* Write a checkpoint atomically. Collective. */
int mpm_checkpoint_write(MPI_Comm comm, const char *path, const char *config_text,
                         const char *const *attr_names, const double *attr_values, int nattr,
                         const mpm_particles *const *phases, const char *const *names, int nphases);

typedef struct mpm_checkpoint mpm_checkpoint;

/* Open a checkpoint for reading (collective); a missing, foreign or damaged file is an input
 * error naming the path. Checks the root: format, the strings' hash, every real attribute
 * finite, "step" a whole number >= 0, "h_next" >= 0. HDF5's error printing stays off until
 * mpm_checkpoint_close. */
int mpm_checkpoint_open(mpm_checkpoint **ck, MPI_Comm comm, const char *path);
void mpm_checkpoint_close(mpm_checkpoint **ck);
const char *mpm_checkpoint_config(const mpm_checkpoint *ck);
int mpm_checkpoint_attr(const mpm_checkpoint *ck, const char *name, double *value);
/* The same for a value older checkpoints may lack: 1 if read, 0 if absent (no message). */
int mpm_checkpoint_attr_optional(const mpm_checkpoint *ck, const char *name, double *value);
/* Fill p (already created with the fields of the phase) with the stored particles: on the
 * same number of ranks each rank gets exactly what it wrote, in the same order; otherwise
 * the ranks get even chunks and the caller migrates. Sets p->id_next. Data that fails its
 * checksum or validation (p's field ranges, ids unique over all ranks) is an input error on
 * every rank, explained once. Collective. */
int mpm_checkpoint_read_particles(mpm_checkpoint *ck, const char *phase, mpm_particles *p);

#endif
