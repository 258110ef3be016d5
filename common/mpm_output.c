/* Snapshots: one parallel HDF5 file per output time, plus the XDMF index series.xmf.
 * mpm_output.h gives the file layout. Invariants:
 *
 * - A snapshot appears under its final name only when complete: every rank writes into
 *   snap_NNNNNN.h5.tmp, closes it, and rank 0 renames it once all have closed. The index is
 *   rewritten only after that rename, so it never names a missing or partial file.
 * - out->next, the index of the next snapshot, is equal on every rank. It advances once the
 *   file is in place, even if the index could not be rewritten, so no file is reused.
 * - Every rank takes part in every collective HDF5 call, with an empty selection when it
 *   has nothing to write. Local failures (checks, allocations) are agreed on with an
 *   MPI_Allreduce before the next collective call, so all ranks return the same code
 *   instead of waiting; the HDF5 helpers of mpm_h5.h do the same inside each write, so
 *   every function below that writes returns the same code on every rank.
 * - Particle rows are in rank order: rank r holds rows [offset_r, offset_r + n_r) with
 *   offset_r = MPI_Exscan of the counts. Particle data is component-major in memory and
 *   row-major ([N][ncomp]) on disk, so each field is transposed through one buffer.
 * - The XDMF indexes live on rank 0 only (mpm_xdmf.c): series.xmf lists the particles of
 *   every snapshot, grid.xmf the grid fields of those that have them. grid.xmf exists only
 *   while it lists a snapshot, so it never outlives the grid fields of an earlier run.
 * - Every snapshot holds /xdmf/<phase>, int64 [N] = 0 .. N-1, the connectivity of the
 *   phase's Polyvertex topology in the index (mpm_xdmf.h). It lies outside the phase group,
 *   whose datasets are all per-particle fields in rank order. */
#define _POSIX_C_SOURCE 200809L /* mkdir, stat, access */
#include "mpm_output.h"
#include "mpm_error.h"
#include "mpm_h5.h"
#include "mpm_path.h"
#include "mpm_xdmf.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define OUTPUT_VERSION  "mpmfsi 0.1"
#define INDEX_NAME      "series.xmf"
#define GRID_INDEX_NAME "grid.xmf"

struct mpm_output {
  MPI_Comm comm; /* a duplicate, so our collectives never mix with the caller's */
  int rank, size, dim;
  char *dir, *config; /* config: rank 0's text, the same on every rank */
  int next;
  mpm_xdmf *index, *grid_index; /* rank 0 only: particles, grid fields */
};

/* Where this rank's particles of one phase go in the snapshot. */
typedef struct phase_rows {
  int64_t n, offset, total;
} phase_rows;

/* ---- particles ------------------------------------------------------------------------- */

/* Field f of p as rows [n][ncomp]. */
static void transpose(const mpm_particles *p, int f, double *buf) {
  const int nc = p->field[f].ncomp;
  for (int c = 0; c < nc; ++c) {
    const double *src = mpm_particles_comp(p, f, c);
    for (mpm_lidx i = 0; i < p->n; ++i) buf[(size_t)i * nc + c] = src[i];
  }
}

static int write_particle_fields(const mpm_h5 *h, hid_t g, const mpm_particles *p,
                                 const phase_rows *r, double *buf) {
  hsize_t fdims[2] = {(hsize_t)r->total, 0}, start[2] = {(hsize_t)r->offset, 0},
          count[2] = {(hsize_t)r->n, 0};
  MPM_CALL(mpm_h5_write_block(h, g, "id", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start, count,
                              p->id));
  for (int f = 0; f < p->nfields; ++f) {
    transpose(p, f, buf);
    fdims[1] = count[1] = (hsize_t)p->field[f].ncomp;
    MPM_CALL(mpm_h5_write_block(h, g, p->field[f].name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, fdims,
                                start, count, buf));
  }
  return 0;
}

static int write_particles(const mpm_h5 *h, hid_t file, const mpm_particles *p, const char *name,
                           const phase_rows *r, double *buf) {
  hid_t g;
  MPM_CALL(mpm_h5_group(h, file, name, &g));
  const int rc = write_particle_fields(h, g, p, r, buf);
  H5Gclose(g);
  MPM_CALL(rc);
  return 0;
}

/* The Polyvertex connectivity of each phase: row r holds r. buf holds at least n doubles,
 * and as many int64. */
static int write_vertices(const mpm_h5 *h, hid_t g, const char *name, const phase_rows *r,
                          double *buf) {
  int64_t *v = (int64_t *)buf;
  for (int64_t i = 0; i < r->n; ++i) v[i] = r->offset + i;
  hsize_t fdims[1] = {(hsize_t)r->total}, start[1] = {(hsize_t)r->offset},
          count[1] = {(hsize_t)r->n};
  MPM_CALL(
      mpm_h5_write_block(h, g, name, H5T_STD_I64LE, H5T_NATIVE_INT64, 1, fdims, start, count, v));
  return 0;
}

static int write_all_vertices(const mpm_h5 *h, hid_t file, const char *const *names, int nphases,
                              const phase_rows *rows, double *buf) {
  hid_t g;
  MPM_CALL(mpm_h5_group(h, file, MPM_XDMF_VERTICES, &g));
  int rc = 0;
  for (int k = 0; k < nphases && !rc; ++k) rc = write_vertices(h, g, names[k], &rows[k], buf);
  H5Gclose(g);
  MPM_CALL(rc);
  return 0;
}

/* ---- grid ------------------------------------------------------------------------------ */

/* Nodes per direction of the global lattice, pad layers included. */
static int lattice_nodes(const mpm_grid *g, int d) {
  return g->ncells[d] + 1 + 2 * g->pad;
}

static hsize_t owned_nodes(const mpm_grid *g) {
  hsize_t n = 1;
  for (int d = 0; d < g->dim; ++d) n *= (hsize_t)(g->own_hi[d] - g->own_lo[d]);
  return n;
}

/* The owned nodes of ncomp box arrays, x fastest, components interleaved. */
static void pack_owned(const mpm_grid *g, double *const *arrays, int ncomp, double *buf) {
  int lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, gi[3];
  for (int d = 0; d < g->dim; ++d) lo[d] = g->own_lo[d], hi[d] = g->own_hi[d];
  size_t q = 0;
  for (gi[2] = lo[2]; gi[2] < hi[2]; ++gi[2])
    for (gi[1] = lo[1]; gi[1] < hi[1]; ++gi[1])
      for (gi[0] = lo[0]; gi[0] < hi[0]; ++gi[0], ++q) {
        const mpm_lidx l = mpm_grid_local_index(g, gi);
        for (int c = 0; c < ncomp; ++c) buf[q * (size_t)ncomp + (size_t)c] = arrays[c][l];
      }
}

/* The owned block must sit inside the box and the lattice, or the writes would read or
 * write out of bounds. */
static int check_grid(const mpm_grid *g, int dim) {
  if (g->dim != dim)
    MPM_FAIL(MPM_ERR_INTERNAL, "output: the grid is %d-D but the output %d-D", g->dim, dim);
  for (int d = 0; d < dim; ++d)
    if (g->own_lo[d] < -g->pad || g->own_hi[d] > g->ncells[d] + g->pad + 1 ||
        g->own_lo[d] > g->own_hi[d] || g->own_lo[d] < g->box_lo[d] ||
        g->own_hi[d] > g->box_lo[d] + g->box_n[d])
      MPM_FAIL(MPM_ERR_INTERNAL,
               "output: owned nodes [%d, %d) along %d lie outside the box or "
               "the lattice",
               g->own_lo[d], g->own_hi[d], d);
  for (int k = 0; k < g->nphases; ++k) {
    int ok = g->phase[k].m_i != NULL;
    for (int d = 0; d < dim; ++d) ok &= g->phase[k].v_i[d] != NULL;
    if (!ok) MPM_FAIL(MPM_ERR_INTERNAL, "output: grid phase '%s' has no m or v", g->phase[k].name);
  }
  return 0;
}

static int write_grid_phase(const mpm_h5 *h, hid_t gg, const mpm_grid *g, int k, double *buf) {
  const int dim = g->dim;
  hsize_t fdims[4], start[4], count[4];
  for (int d = 0; d < dim; ++d) { /* slowest first: [Nz][Ny][Nx] */
    fdims[dim - 1 - d] = (hsize_t)lattice_nodes(g, d);
    start[dim - 1 - d] = (hsize_t)(g->own_lo[d] + g->pad);
    count[dim - 1 - d] = (hsize_t)(g->own_hi[d] - g->own_lo[d]);
  }
  fdims[dim] = count[dim] = (hsize_t)dim, start[dim] = 0;
  const mpm_grid_phase *ph = &g->phase[k];
  hid_t sub;
  MPM_CALL(mpm_h5_group(h, gg, ph->name, &sub));
  double *m[1] = {ph->m_i};
  pack_owned(g, m, 1, buf);
  int rc = mpm_h5_write_block(h, sub, "m", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dim, fdims, start,
                              count, buf);
  if (!rc) {
    pack_owned(g, ph->v_i, dim, buf);
    rc = mpm_h5_write_block(h, sub, "v", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, dim + 1, fdims, start,
                            count, buf);
  }
  H5Gclose(sub);
  MPM_CALL(rc);
  return 0;
}

static int has_name(const char *const *names, int n, const char *name) {
  for (int k = 0; k < n; ++k)
    if (strcmp(names[k], name) == 0) return 1;
  return 0;
}

static int write_grid_fields(const mpm_h5 *h, hid_t gg, const mpm_grid *g, const char *const *names,
                             int nphases, double *buf) {
  double origin[MPM_MAX_DIM];
  for (int d = 0; d < g->dim; ++d) origin[d] = g->lo[d] - g->pad * g->dx;
  MPM_CALL(mpm_h5_attr(h, gg, "origin", H5T_NATIVE_DOUBLE, g->dim, origin));
  MPM_CALL(mpm_h5_attr(h, gg, "spacing", H5T_NATIVE_DOUBLE, 1, &g->dx));
  for (int k = 0; k < g->nphases; ++k)
    if (has_name(names, nphases, g->phase[k].name)) MPM_CALL(write_grid_phase(h, gg, g, k, buf));
  return 0;
}

static int write_grid(const mpm_h5 *h, hid_t file, const mpm_grid *g, const char *const *names,
                      int nphases, double *buf) {
  hid_t gg;
  MPM_CALL(mpm_h5_group(h, file, "grid", &gg));
  const int rc = write_grid_fields(h, gg, g, names, nphases, buf);
  H5Gclose(gg);
  MPM_CALL(rc);
  return 0;
}

/* ---- one snapshot file ----------------------------------------------------------------- */

typedef struct snapshot {
  const mpm_output *out;
  double t;
  long step;
  const mpm_particles *const *phases;
  const char *const *names;
  int nphases;
  const mpm_grid *grid;
  const phase_rows *rows;
  double *buf;
} snapshot;

/* Fills the snapshot file (an mpm_h5_fill; arg is the snapshot). */
static int write_contents(const mpm_h5 *h, hid_t file, const void *arg) {
  const snapshot *s = arg;
  const int64_t step = s->step;
  MPM_CALL(mpm_h5_attr(h, file, "time", H5T_NATIVE_DOUBLE, 1, &s->t));
  MPM_CALL(mpm_h5_attr(h, file, "step", H5T_NATIVE_INT64, 1, &step));
  MPM_CALL(mpm_h5_attr(h, file, "dim", H5T_NATIVE_INT, 1, &s->out->dim));
  MPM_CALL(mpm_h5_attr_string(h, file, "config", s->out->config));
  MPM_CALL(mpm_h5_attr_string(h, file, "version", OUTPUT_VERSION));
  for (int k = 0; k < s->nphases; ++k)
    MPM_CALL(write_particles(h, file, s->phases[k], s->names[k], &s->rows[k], s->buf));
  MPM_CALL(write_all_vertices(h, file, s->names, s->nphases, s->rows, s->buf));
  if (s->grid) MPM_CALL(write_grid(h, file, s->grid, s->names, s->nphases, s->buf));
  return 0;
}

/* ---- the index (rank 0) ---------------------------------------------------------------- */

static int index_add(mpm_output *out, const snapshot *s) {
  mpm_xdmf_phase *ph;
  mpm_xdmf_field *fields;
  mpm_xdmf_mesh *mesh;
  ph = calloc((size_t)s->nphases + 1, sizeof *ph);
  fields = calloc((size_t)s->nphases * MPM_PARTICLES_MAX_FIELDS + 1, sizeof *fields);
  mesh = calloc(MPM_GRID_MAX_PHASES, sizeof *mesh);
  if (!ph || !fields || !mesh) {
    free(ph), free(fields), free(mesh);
    MPM_FAIL(MPM_ERR_MEMORY, "output: cannot describe the snapshot for the index");
  }
  for (int k = 0; k < s->nphases; ++k) {
    const mpm_particles *p = s->phases[k];
    mpm_xdmf_field *f = fields + (size_t)k * MPM_PARTICLES_MAX_FIELDS;
    for (int j = 0; j < p->nfields; ++j)
      f[j] = (mpm_xdmf_field){p->field[j].name, p->field[j].ncomp};
    ph[k] = (mpm_xdmf_phase){s->names[k], s->rows[k].total, p->nfields, f};
  }
  int nmesh = 0;
  for (int k = 0; s->grid && k < s->grid->nphases; ++k) {
    const mpm_grid *g = s->grid;
    if (!has_name(s->names, s->nphases, g->phase[k].name)) continue;
    mpm_xdmf_mesh *m = &mesh[nmesh++];
    *m = (mpm_xdmf_mesh){g->phase[k].name, {1, 1, 1}, {0, 0, 0}, g->dx};
    for (int d = 0; d < g->dim; ++d)
      m->n[d] = lattice_nodes(g, d), m->origin[d] = g->lo[d] - g->pad * g->dx;
  }
  int rc = mpm_xdmf_add(out->index, s->t, out->next, ph, s->nphases, NULL, 0);
  if (!rc && nmesh > 0) rc = mpm_xdmf_add(out->grid_index, s->t, out->next, NULL, 0, mesh, nmesh);
  free(ph), free(fields), free(mesh);
  MPM_CALL(rc);
  return 0;
}

/* Write index x as dir/name; an optional index that lists nothing is deleted instead. */
static int write_index(const char *dir, const mpm_xdmf *x, const char *name, int optional) {
  char *path = mpm_path_join(dir, name);
  if (!path) MPM_FAIL(MPM_ERR_MEMORY, "output: cannot build the path of %s", name);
  if (optional && mpm_xdmf_count(x) == 0) {
    const int gone = remove(path) == 0 || errno == ENOENT, e = errno;
    free(path);
    if (!gone)
      MPM_FAIL(MPM_ERR_FILE, "cannot delete the stale index %s/%s: %s; delete it by hand", dir,
               name, strerror(e));
    return 0;
  }
  const int rc = mpm_xdmf_write(x, path);
  free(path);
  MPM_CALL(rc);
  return 0;
}

static int index_write(const mpm_output *out) {
  MPM_CALL(write_index(out->dir, out->index, INDEX_NAME, 0));
  MPM_CALL(write_index(out->dir, out->grid_index, GRID_INDEX_NAME, 1));
  return 0;
}

/* Rank 0, once every rank has closed the file: move it into place, then list it.
 * *renamed tells whether the file is in place (the index may still have failed). */
static int publish(mpm_output *out, const char *tmp, const char *final, const snapshot *s,
                   int *renamed) {
  *renamed = 0;
  if (rename(tmp, final) != 0)
    MPM_FAIL(MPM_ERR_FILE, "cannot rename %s to %s: %s", tmp, final, strerror(errno));
  *renamed = 1;
  mpm_log(MPM_LOG_DEBUG, "output: wrote %s (t = %g, step %ld)", final, s->t, s->step);
  MPM_CALL(index_add(out, s));
  MPM_CALL(index_write(out));
  return 0;
}

/* ---- checks ---------------------------------------------------------------------------- */

static int check_phase(const mpm_output *out, const mpm_particles *p, const char *name) {
  if (!p || !name || !name[0] || strchr(name, '/') || strcmp(name, "grid") == 0 ||
      strcmp(name, MPM_XDMF_VERTICES) == 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "output: phase name '%s' cannot name an HDF5 group (it must be "
             "non-empty, without '/', and not 'grid' or '" MPM_XDMF_VERTICES "')",
             name ? name : "(null)");
  if (p->dim != out->dim || p->nfields < 1 || strcmp(p->field[0].name, "x") != 0 ||
      p->field[0].ncomp != out->dim)
    MPM_FAIL(MPM_ERR_INTERNAL, "output: phase '%s' must be %d-D with field 0 the position x", name,
             out->dim);
  for (int f = 0; f < p->nfields; ++f)
    if (strcmp(p->field[f].name, "id") == 0 || strchr(p->field[f].name, '/'))
      MPM_FAIL(MPM_ERR_INTERNAL, "output: phase '%s' has a field named '%s'", name,
               p->field[f].name);
  return 0;
}

static int check_phases(const mpm_output *out, const mpm_particles *const *phases,
                        const char *const *names, int nphases) {
  if (nphases < 0 || (nphases > 0 && (!phases || !names)))
    MPM_FAIL(MPM_ERR_INTERNAL, "output: %d phases without their sets or names", nphases);
  for (int k = 0; k < nphases; ++k) {
    MPM_CALL(check_phase(out, phases[k], names[k]));
    for (int j = 0; j < k; ++j)
      if (strcmp(names[j], names[k]) == 0)
        MPM_FAIL(MPM_ERR_INPUT, "output: the phase name '%s' is used twice", names[k]);
  }
  return 0;
}

/* ---- snapshot -------------------------------------------------------------------------- */

static int count_rows(const mpm_output *out, const mpm_particles *const *phases, int nphases,
                      phase_rows *rows) {
  int64_t *n = malloc(3 * (size_t)(nphases ? nphases : 1) * sizeof *n);
  const int ok = mpm_h5_agree(out->comm, n ? 0 : MPM_ERR_MEMORY);
  if (ok) free(n);
  MPM_CALL(ok);
  int64_t *before = n + nphases, *total = n + 2 * nphases;
  for (int k = 0; k < nphases; ++k) n[k] = phases[k]->n, before[k] = 0;
  int rc = MPI_Exscan(n, before, nphases, MPI_INT64_T, MPI_SUM, out->comm);
  if (rc == MPI_SUCCESS) rc = MPI_Allreduce(n, total, nphases, MPI_INT64_T, MPI_SUM, out->comm);
  for (int k = 0; k < nphases; ++k) /* MPI_Exscan leaves rank 0's result undefined */
    rows[k] = (phase_rows){n[k], out->rank == 0 ? 0 : before[k], total[k]};
  free(n);
  if (rc != MPI_SUCCESS) MPM_FAIL(MPM_ERR_MPI, "output: counting the particles failed");
  return 0;
}

/* Doubles of the transpose buffer: the largest field or grid block this rank writes. */
static size_t buffer_size(const mpm_particles *const *phases, int nphases, const mpm_grid *g) {
  size_t need = 1;
  for (int k = 0; k < nphases; ++k)
    for (int f = 0; f < phases[k]->nfields; ++f)
      need = MPM_MAX(need, (size_t)phases[k]->n * (size_t)phases[k]->field[f].ncomp);
  if (g) need = MPM_MAX(need, (size_t)owned_nodes(g) * (size_t)g->dim);
  return need;
}

static int snapshot_paths(const mpm_output *out, char **tmp, char **final) {
  char name[40];
  snprintf(name, sizeof name, "snap_%06d.h5.tmp", out->next);
  *tmp = mpm_path_join(out->dir, name);
  name[strlen(name) - 4] = 0;
  *final = mpm_path_join(out->dir, name);
  return *tmp && *final ? 0 : MPM_ERR_MEMORY;
}

static int snapshot_write(mpm_output *out, snapshot *s) {
  char *tmp = NULL, *final = NULL;
  int rc = snapshot_paths(out, &tmp, &final);
  s->buf = rc ? NULL : malloc(buffer_size(s->phases, s->nphases, s->grid) * sizeof(double));
  if (!s->buf && !rc) rc = MPM_ERR_MEMORY;
  if (rc)
    mpm_log_all(MPM_LOG_ERROR, MPM_OOM_MESSAGE,
                (double)buffer_size(s->phases, s->nphases, s->grid) * sizeof(double) / 1e6);
  rc = mpm_h5_agree(out->comm, rc);
  const mpm_h5 h = {out->comm, out->rank, "snapshot"};
  if (!rc) rc = mpm_h5_write_file(&h, tmp, write_contents, s);
  /* mpm_h5_write_file returns once every rank has closed the file (its agreement is the
   * barrier), or the agreement above failed on every rank. */
  int state[2] = {rc, 0};
  if (out->rank == 0 && !rc) state[0] = publish(out, tmp, final, s, &state[1]);
  if (out->rank == 0 && rc && tmp) remove(tmp);
  if (MPI_Bcast(state, 2, MPI_INT, 0, out->comm) != MPI_SUCCESS) state[0] = MPM_ERR_MPI;
  if (state[1]) out->next++;
  free(tmp), free(final), free(s->buf);
  s->buf = NULL;
  MPM_CALL(state[0]);
  return 0;
}

int mpm_output_snapshot(mpm_output *out, double t, long step, const mpm_particles *const *phases,
                        const char *const *names, int nphases, const mpm_grid *grid) {
  /* The checks are local (each rank checks its own block): agreed on before any collective. */
  int rc = check_phases(out, phases, names, nphases);
  if (!rc && grid) rc = check_grid(grid, out->dim);
  phase_rows *rows = rc ? NULL : malloc((size_t)(nphases ? nphases : 1) * sizeof *rows);
  rc = mpm_h5_agree(out->comm, rc ? rc : rows ? 0 : MPM_ERR_MEMORY);
  if (!rc) rc = count_rows(out, phases, nphases, rows);
  snapshot s = {out, t, step, phases, names, nphases, grid, rows, NULL};
  if (!rc) rc = snapshot_write(out, &s);
  free(rows);
  MPM_CALL(rc);
  return 0;
}

int mpm_output_count(const mpm_output *out) {
  return out->next;
}

/* ---- construction ---------------------------------------------------------------------- */

/* The entries of dir/name with time <= t_max; *found is 0 if there is no such file. */
static int load_index(const char *dir, mpm_xdmf *x, const char *name, double t_max, int *found) {
  char *path = mpm_path_join(dir, name);
  if (!path) MPM_FAIL(MPM_ERR_MEMORY, "output: cannot build the path of %s", name);
  const int rc = mpm_xdmf_load(x, path, t_max, found);
  free(path);
  MPM_CALL(rc);
  return 0;
}

/* Rank 0: the directory, and the indexes kept from an earlier run on a restart. */
static int prepare_index(mpm_output *out, int append, double t_restart) {
  const int err = mpm_path_make_dir(out->dir);
  if (err)
    MPM_FAIL(MPM_ERR_FILE,
             "cannot use '%s' as the output directory: %s. Choose another output directory in "
             "the case file, or create this one with write permission",
             out->dir, strerror(err));
  MPM_CALL(mpm_xdmf_new(&out->index, out->dim));
  MPM_CALL(mpm_xdmf_new(&out->grid_index, out->dim));
  if (append) {
    int found = 0, grid_found;
    MPM_CALL(load_index(out->dir, out->index, INDEX_NAME, t_restart, &found));
    MPM_CALL(load_index(out->dir, out->grid_index, GRID_INDEX_NAME, t_restart, &grid_found));
    if (!found)
      mpm_log(MPM_LOG_WARN, "restart: no %s in %s; the index starts empty", INDEX_NAME, out->dir);
    out->next = mpm_xdmf_next_index(out->index);
    mpm_log(MPM_LOG_INFO, "restart: %s keeps %d snapshot(s) with t <= %g; the next is snap_%06d.h5",
            INDEX_NAME, mpm_xdmf_count(out->index), t_restart, out->next);
  }
  /* Written now so that an index left by an earlier run never lists files this run is
   * about to overwrite (a fresh run's grid index is empty: an earlier one is deleted). */
  MPM_CALL(index_write(out));
  return 0;
}

/* Every rank gets a copy of rank 0's text. */
static int bcast_string(MPI_Comm comm, int rank, const char *in, char **out) {
  unsigned long long len = rank == 0 && in ? strlen(in) : 0;
  MPM_CALL_MPI(MPI_Bcast(&len, 1, MPI_UNSIGNED_LONG_LONG, 0, comm));
  if (len > (unsigned long long)INT32_MAX - 1)
    MPM_FAIL(MPM_ERR_INPUT, "output: the case text is too long (%llu bytes)", len);
  *out = calloc(len + 1, 1);
  MPM_CALL(mpm_h5_agree(comm, *out ? 0 : MPM_ERR_MEMORY));
  if (rank == 0 && len) memcpy(*out, in, len);
  MPM_CALL_MPI(MPI_Bcast(*out, (int)len, MPI_CHAR, 0, comm));
  return 0;
}

static int output_init(mpm_output *out, MPI_Comm comm, const char *dir, const char *config_text,
                       int append, double t_restart) {
  MPM_CALL_MPI(MPI_Comm_dup(comm, &out->comm));
  MPM_CALL_MPI(MPI_Comm_rank(out->comm, &out->rank));
  MPM_CALL_MPI(MPI_Comm_size(out->comm, &out->size));
  MPM_CALL(bcast_string(out->comm, out->rank, config_text, &out->config));
  out->dir = malloc(strlen(dir) + 1);
  MPM_CALL(mpm_h5_agree(out->comm, out->dir ? 0 : MPM_ERR_MEMORY));
  memcpy(out->dir, dir, strlen(dir) + 1);
  int state[2] = {0, 0};
  if (out->rank == 0) state[0] = prepare_index(out, append, t_restart), state[1] = out->next;
  MPM_CALL_MPI(MPI_Bcast(state, 2, MPI_INT, 0, out->comm));
  MPM_CALL(state[0]);
  out->next = state[1];
  return 0;
}

int mpm_output_new(mpm_output **out, MPI_Comm comm, const char *dir, const char *config_text,
                   int dim, int append, double t_restart) {
  mpm_output *o;
  *out = NULL;
  if (dim != 2 && dim != 3)
    MPM_FAIL(MPM_ERR_INPUT, "output: snapshots are written for 2-D and 3-D runs, not %d-D", dim);
  if (!dir || !dir[0]) MPM_FAIL(MPM_ERR_INPUT, "output: no output directory was given");
  MPM_ALLOC(o, 1);
  o->comm = MPI_COMM_NULL;
  o->dim = dim;
  const int rc = output_init(o, comm, dir, config_text, append, t_restart);
  if (rc) {
    mpm_output_destroy(&o);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *out = o;
  return 0;
}

void mpm_output_destroy(mpm_output **out) {
  if (!out || !*out) return;
  mpm_output *o = *out;
  if (o->comm != MPI_COMM_NULL) MPI_Comm_free(&o->comm);
  mpm_xdmf_destroy(&o->index);
  mpm_xdmf_destroy(&o->grid_index);
  free(o->dir), free(o->config);
  free(o);
  *out = NULL;
}
