/* Output layer (mpm_output.h): snapshots, the XDMF index and checkpoints, on any number of
 * ranks. Run as `test_output ROOT`; everything is written under ROOT (emptied first), and
 * ROOT/snap2d and ROOT/snap3d are left for tools/check_snapshot.py.
 *
 * - snapshot round trip: every dataset read back with serial HDF5 on rank 0 equals the
 *   particles written, rows in rank order; root attributes; a rank with no particles and a
 *   phase with none at all; grid fields of the matching grid phase only, owned nodes only,
 *   on a hand-made grid (ghost nodes hold a poison value that must never reach the file)
 *   and on one made by mpm_grid.c; `h5dump -H` opens every file, `xmllint --noout` accepts
 *   series.xmf, which names every snapshot; no .tmp file is left;
 * - restart: append keeps the entries with t <= t_restart and numbers on after them;
 * - refinement (hier_fixture.h's three levels, one rank): every level's masks equal the
 *   hierarchy's, the finer levels' m and v are their box nodes', each particle's level is
 *   mpm_hier_level_of of its position, grid.xmf has a block per level; on more ranks
 *   mpm_output_set_hier refuses the hierarchy;
 * - checkpoints: bitwise round trip of ids and data on the same rank count; reading on a
 *   different rank count (written on a sub-communicator) gives even chunks in rank order;
 *   a missing file, a text file, an HDF5 file that is not a checkpoint, a missing
 *   attribute, a missing phase and a different field layout are input errors; a failed
 *   write leaves the earlier checkpoint intact and no file at the final path.
 * Particle sets are filled by hand (as mpm_particles.c would) with values that are a
 * function of the id, so every check is exact. */
#define _XOPEN_SOURCE 700 /* nftw, strdup */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "hier_fixture.h"
#include "mpm_error.h"
#include "mpm_output.h"

#include <hdf5.h>

#include <dirent.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int g_rank, g_size;
static char g_root[4096];

/* ---- particle sets by hand ------------------------------------------------------------- */

typedef struct set_spec {
  const char *phase;
  int dim, nfields;
  mpm_field_desc field[6];
} set_spec;

static const set_spec g_solid2 = {"solid", 2, 4, {{"x", 2}, {"v", 2}, {"F", 4}, {"m", 1}}};
static const set_spec g_fluid2 = {"fluid", 2, 3, {{"x", 2}, {"v", 2}, {"p", 1}}};
static const set_spec g_solid3 = {
    "solid", 3, 5, {{"x", 3}, {"v", 3}, {"F", 9}, {"sigma", 6}, {"m", 1}}};
static const set_spec g_empty3 = {"empty", 3, 2, {{"x", 3}, {"v", 3}}};

/* Component c (over all fields) of particle id: irrational-looking bits, so that a bitwise
 * comparison means something. */
static double value(int64_t id, int c) {
  return sin(0.37 * (double)id + 1.3 * c) * 1e3;
}

/* Particles of phase spec on rank r: counts differ per rank and rank 1 has no fluid. */
static int count_on(const set_spec *s, int r) {
  if (strcmp(s->phase, "empty") == 0) return 0;
  if (strcmp(s->phase, "fluid") == 0) return r == 1 ? 0 : 2 + r;
  return 3 + 2 * r;
}

static int64_t id_on(const set_spec *s, int r, int i) {
  return (strcmp(s->phase, "fluid") == 0 ? 500000 : 0) + 1000 * r + 3 * i;
}

static mpm_particles *make_empty_set(const set_spec *s) {
  mpm_particles *p = calloc(1, sizeof *p);
  assert_non_null(p);
  p->dim = s->dim, p->nfields = s->nfields, p->nstate_fields = 2;
  for (int f = 0; f < s->nfields; ++f) {
    p->field[f] = s->field[f];
    p->offset[f] = p->ncomp;
    p->ncomp += s->field[f].ncomp;
  }
  p->nstate = s->field[0].ncomp + s->field[1].ncomp;
  p->id = malloc(sizeof *p->id);
  p->data = malloc(sizeof *p->data);
  return p;
}

static mpm_particles *make_set(const set_spec *s, int r) {
  mpm_particles *p = make_empty_set(s);
  const int n = count_on(s, r);
  p->n = n;
  p->id = realloc(p->id, ((size_t)n + 1) * sizeof *p->id);
  p->data = realloc(p->data, ((size_t)n * p->ncomp + 1) * sizeof *p->data);
  for (int i = 0; i < n; ++i) p->id[i] = id_on(s, r, i);
  for (int c = 0; c < p->ncomp; ++c)
    for (int i = 0; i < n; ++i) p->data[(size_t)c * n + i] = value(p->id[i], c);
  p->id_next = 7777777;
  return p;
}

/* Field names point at the spec's literals, so only the blocks are freed. */
static void free_set(mpm_particles **p) {
  if (!*p) return;
  /* A read keeps the block it replaced as the set's spare (mpm_particles.h). */
  free((*p)->id), free((*p)->data), free((*p)->spare_id), free((*p)->spare_data), free(*p);
  *p = NULL;
}

/* ---- a grid by hand, split along x ----------------------------------------------------- */

/* Node value of the hand-made grid: m = f, v_d = f + (d + 1) / 2. */
static double node_value(const int *gi, int comp) {
  return 1.0 + gi[0] + 10.0 * gi[1] + 100.0 * gi[2] + 0.5 * comp;
}

#define POISON -999.0

static mpm_grid *make_grid(int dim) {
  mpm_grid *g = calloc(1, sizeof *g);
  const int nc[3] = {3 * g_size, 4, 3};
  const double lo[3] = {0.0, -1.0, 2.0};
  g->comm = MPI_COMM_WORLD, g->rank = g_rank, g->size = g_size, g->dim = dim;
  g->dx = 0.5, g->shape = MPM_SHAPE_QUADRATIC, g->ghost = 2, g->pad = 2;
  g->nnodes = 1;
  for (int d = 0; d < 3; ++d) {
    g->nproc[d] = d == 0 ? g_size : 1, g->coord[d] = d == 0 ? g_rank : 0;
    if (d >= dim) { /* degenerate, as mpm_grid.c makes them */
      g->own_lo[d] = g->box_lo[d] = 0, g->own_hi[d] = g->box_n[d] = 1;
      continue;
    }
    g->ncells[d] = nc[d], g->lo[d] = lo[d], g->hi[d] = lo[d] + nc[d] * g->dx;
    const int first = d > 0 || g_rank == 0, last = d > 0 || g_rank == g_size - 1;
    g->own_lo[d] = first ? -g->pad : 3 * g_rank;
    g->own_hi[d] = last ? nc[d] + g->pad + 1 : 3 * (g_rank + 1);
    g->box_lo[d] = g->own_lo[d] - g->ghost;
    g->box_n[d] = g->own_hi[d] - g->own_lo[d] + 2 * g->ghost;
    g->nnodes *= g->box_n[d];
  }
  g->nphases = 2;
  strcpy(g->phase[0].name, "other"); /* no particle phase of that name: never written */
  strcpy(g->phase[1].name, "solid");
  for (int k = 0; k < 2; ++k) {
    g->phase[k].m_i = malloc((size_t)g->nnodes * sizeof(double));
    for (int d = 0; d < dim; ++d) g->phase[k].v_i[d] = malloc((size_t)g->nnodes * sizeof(double));
  }
  int gi[3];
  for (gi[2] = g->box_lo[2]; gi[2] < g->box_lo[2] + g->box_n[2]; ++gi[2])
    for (gi[1] = g->box_lo[1]; gi[1] < g->box_lo[1] + g->box_n[1]; ++gi[1])
      for (gi[0] = g->box_lo[0]; gi[0] < g->box_lo[0] + g->box_n[0]; ++gi[0]) {
        int owned = 1;
        for (int d = 0; d < dim; ++d) owned &= gi[d] >= g->own_lo[d] && gi[d] < g->own_hi[d];
        const mpm_lidx l = mpm_grid_local_index(g, gi);
        for (int k = 0; k < 2; ++k) {
          g->phase[k].m_i[l] = owned ? node_value(gi, 0) : POISON;
          for (int d = 0; d < dim; ++d)
            g->phase[k].v_i[d][l] = owned ? node_value(gi, d + 1) : POISON;
        }
      }
  return g;
}

static void free_grid(mpm_grid **g) {
  for (int k = 0; k < (*g)->nphases; ++k) {
    free((*g)->phase[k].m_i);
    for (int d = 0; d < (*g)->dim; ++d) free((*g)->phase[k].v_i[d]);
  }
  free(*g);
  *g = NULL;
}

/* ---- files ----------------------------------------------------------------------------- */

static void path_of(char *buf, size_t size, const char *a, const char *b) {
  if (snprintf(buf, size, "%s/%s", a, b) >= (int)size) fail_msg("path too long: %s/%s", a, b);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  return remove(path);
}

static void remove_tree(const char *path) {
  nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  const long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = calloc((size_t)len + 1, 1);
  if (s && fread(s, 1, (size_t)len, f) != (size_t)len) s[0] = 0;
  fclose(f);
  return s;
}

static int count_occurrences(const char *text, const char *what) {
  int n = 0;
  for (const char *p = strstr(text, what); p; p = strstr(p + 1, what)) ++n;
  return n;
}

static int has_tmp_file(const char *dir) {
  DIR *d = opendir(dir);
  int found = 0;
  for (struct dirent *e; d && (e = readdir(d));) {
    const size_t n = strlen(e->d_name);
    found |= n > 4 && strcmp(e->d_name + n - 4, ".tmp") == 0;
  }
  if (d) closedir(d);
  return found;
}

static int tool_exists(const char *name) {
  char cmd[256];
  snprintf(cmd, sizeof cmd, "command -v %s > /dev/null 2>&1", name);
  return system(cmd) == 0;
}

static int run_tool(const char *tool, const char *args, const char *path) {
  char cmd[8192];
  snprintf(cmd, sizeof cmd, "%s %s '%s' > /dev/null", tool, args, path);
  return system(cmd);
}

/* ---- HDF5 read-back (serial, rank 0) --------------------------------------------------- */

/* Read a whole dataset; returns its rank and extents in dims, and a malloc'ed buffer. */
static void *read_all(hid_t f, const char *name, hid_t mtype, int *rank, hsize_t *dims) {
  const hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  assert_true(d >= 0);
  const hid_t space = H5Dget_space(d);
  *rank = H5Sget_simple_extent_ndims(space);
  H5Sget_simple_extent_dims(space, dims, NULL);
  hsize_t n = 1;
  for (int k = 0; k < *rank; ++k) n *= dims[k];
  void *buf = malloc((size_t)(n + 1) * H5Tget_size(mtype));
  assert_true(H5Dread(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
  H5Sclose(space);
  H5Dclose(d);
  return buf;
}

static double attr_double(hid_t loc, const char *name, hid_t type) {
  double v[3] = {0, 0, 0};
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  assert_true(a >= 0);
  if (H5Tequal(type, H5T_NATIVE_INT64) > 0) {
    int64_t i = 0;
    assert_true(H5Aread(a, type, &i) >= 0);
    v[0] = (double)i;
  } else if (H5Tequal(type, H5T_NATIVE_INT) > 0) {
    int i = 0;
    assert_true(H5Aread(a, type, &i) >= 0);
    v[0] = i;
  } else {
    assert_true(H5Aread(a, type, v) >= 0);
  }
  H5Aclose(a);
  return v[0];
}

static char *attr_string(hid_t loc, const char *name) {
  const hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  assert_true(a >= 0);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  char *s = NULL;
  assert_true(H5Aread(a, type, &s) >= 0);
  char *copy = strdup(s);
  H5free_memory(s);
  H5Tclose(type);
  H5Aclose(a);
  return copy;
}

/* Every particle field of phase spec in the open snapshot f equals what the ranks wrote,
 * rows in rank order. */
static void check_phase_file(hid_t f, const set_spec *s) {
  char name[256];
  int rank;
  hsize_t dims[4];
  int64_t total = 0;
  for (int r = 0; r < g_size; ++r) total += count_on(s, r);
  snprintf(name, sizeof name, "/%s/id", s->phase);
  int64_t *id = read_all(f, name, H5T_NATIVE_INT64, &rank, dims);
  assert_int_equal(rank, 1);
  assert_int_equal(dims[0], total);
  int64_t row = 0;
  for (int r = 0; r < g_size; ++r)
    for (int i = 0; i < count_on(s, r); ++i) assert_int_equal(id[row++], id_on(s, r, i));
  int c0 = 0;
  for (int k = 0; k < s->nfields; ++k) {
    const int nc = s->field[k].ncomp;
    snprintf(name, sizeof name, "/%s/%s", s->phase, s->field[k].name);
    double *v = read_all(f, name, H5T_NATIVE_DOUBLE, &rank, dims);
    assert_int_equal(rank, 2);
    assert_int_equal(dims[0], total);
    assert_int_equal(dims[1], nc);
    for (int64_t i = 0; i < total; ++i)
      for (int c = 0; c < nc; ++c) assert_true(v[i * nc + c] == value(id[i], c0 + c));
    free(v);
    c0 += nc;
  }
  free(id);
}

/* /grid/solid/{m,v} hold the whole lattice, pad layers included; /grid/other is absent. */
static void check_grid_file(hid_t f, int dim) {
  const mpm_grid *ref = make_grid(dim); /* this rank's copy, for the global geometry */
  int rank, n[3] = {1, 1, 1};
  hsize_t dims[4];
  for (int d = 0; d < dim; ++d) n[d] = ref->ncells[d] + 1 + 2 * ref->pad;
  double *m = read_all(f, "/grid/solid/m", H5T_NATIVE_DOUBLE, &rank, dims);
  assert_int_equal(rank, dim);
  for (int d = 0; d < dim; ++d) assert_int_equal(dims[dim - 1 - d], n[d]);
  double *v = read_all(f, "/grid/solid/v", H5T_NATIVE_DOUBLE, &rank, dims);
  assert_int_equal(rank, dim + 1);
  assert_int_equal(dims[dim], dim);
  size_t q = 0;
  int gi[3] = {0, 0, 0};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i, ++q) {
        gi[0] = i - ref->pad, gi[1] = j - ref->pad, gi[2] = dim == 3 ? k - ref->pad : 0;
        assert_true(m[q] == node_value(gi, 0));
        for (int d = 0; d < dim; ++d) assert_true(v[q * dim + d] == node_value(gi, d + 1));
      }
  free(m), free(v);
  assert_true(H5Lexists(f, "/grid/other", H5P_DEFAULT) == 0);
  const hid_t g = H5Gopen2(f, "/grid", H5P_DEFAULT);
  double origin[3] = {0, 0, 0}, spacing = 0;
  const hid_t a = H5Aopen(g, "origin", H5P_DEFAULT);
  assert_true(H5Aread(a, H5T_NATIVE_DOUBLE, origin) >= 0);
  H5Aclose(a);
  spacing = attr_double(g, "spacing", H5T_NATIVE_DOUBLE);
  for (int d = 0; d < dim; ++d) assert_true(origin[d] == ref->lo[d] - ref->pad * ref->dx);
  assert_true(spacing == ref->dx);
  H5Gclose(g);
  mpm_grid *tmp = (mpm_grid *)ref;
  free_grid(&tmp);
}

static void check_root_attrs(hid_t f, double t, long step, int dim, const char *config) {
  assert_true(attr_double(f, "time", H5T_NATIVE_DOUBLE) == t);
  assert_true(attr_double(f, "step", H5T_NATIVE_INT64) == (double)step);
  assert_true(attr_double(f, "dim", H5T_NATIVE_INT) == dim);
  char *s = attr_string(f, "config");
  assert_string_equal(s, config);
  free(s);
  s = attr_string(f, "version");
  assert_string_equal(s, "mpmfsi 0.1");
  free(s);
}

/* h5dump can read the header of every snapshot; xmllint accepts the index. */
static void check_tools(const char *dir, int nsnap) {
  char path[4600], file[64];
  if (tool_exists("h5dump"))
    for (int k = 0; k < nsnap; ++k) {
      snprintf(file, sizeof file, "snap_%06d.h5", k);
      path_of(path, sizeof path, dir, file);
      assert_int_equal(run_tool("h5dump", "-H", path), 0);
    }
  else
    print_message("h5dump not found: skipping its check\n");
  path_of(path, sizeof path, dir, "series.xmf");
  if (tool_exists("xmllint"))
    assert_int_equal(run_tool("xmllint", "--noout", path), 0);
  else
    print_message("xmllint not found: skipping its check\n");
}

/* ---- snapshots ------------------------------------------------------------------------- */

static const char *g_config2 = "[grid]\ndx = 0.5\n# 2-D case text, stored verbatim\n";

static void snap_dir(char *buf, size_t size, const char *name) {
  path_of(buf, size, g_root, name);
}

static void test_snapshot_2d(void **state) {
  (void)state;
  char dir[4200], path[4600];
  snap_dir(dir, sizeof dir, "snap2d");
  mpm_particles *solid = make_set(&g_solid2, g_rank), *fluid = make_set(&g_fluid2, g_rank);
  const mpm_particles *phases[2] = {solid, fluid};
  const char *names[2] = {"solid", "fluid"};
  mpm_grid *grid = make_grid(2);
  mpm_output *out;
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, g_config2, 2, 0, 0.0), 0);
  assert_int_equal(mpm_output_count(out), 0);
  const double times[3] = {0.0, 0.5, 1.0};
  for (int k = 0; k < 3; ++k)
    assert_int_equal(mpm_output_snapshot(out, times[k], 10 * k, phases, names, 2, grid), 0);
  assert_int_equal(mpm_output_count(out), 3);
  mpm_output_destroy(&out);
  assert_null(out);
  MPI_Barrier(MPI_COMM_WORLD);
  if (g_rank == 0) {
    path_of(path, sizeof path, dir, "snap_000001.h5");
    const hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    check_root_attrs(f, 0.5, 10, 2, g_config2);
    check_phase_file(f, &g_solid2);
    check_phase_file(f, &g_fluid2);
    check_grid_file(f, 2);
    H5Fclose(f);
    check_tools(dir, 3);
    assert_false(has_tmp_file(dir));
    path_of(path, sizeof path, dir, "series.xmf");
    char *xmf = read_text(path);
    assert_non_null(xmf);
    for (int k = 0; k < 3; ++k) {
      char want[64];
      snprintf(want, sizeof want, "snap_%06d.h5:/solid/x", k);
      assert_int_equal(count_occurrences(xmf, want), 1);
    }
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"0.5\"/>"), 1);
    assert_int_equal(count_occurrences(xmf, "CollectionType=\"Spatial\""), 3);
    /* rank 1 has no fluid, but the phase as a whole does when there are other ranks; each
     * phase is a temporal collection around one grid of the same name (mpm_xdmf.h) */
    assert_int_equal(count_occurrences(xmf, "Name=\"fluid\""), 6);
    assert_int_equal(count_occurrences(xmf, ".h5:/xdmf/fluid<"), 3); /* Polyvertex cells */
    assert_int_equal(count_occurrences(xmf, "_grid"), 0);            /* grid fields: grid.xmf */
    assert_int_equal(count_occurrences(xmf, "other"), 0);
    /* F has 4 components: a Matrix; no phase has a colour field (rho), so no Scalar */
    assert_int_equal(count_occurrences(xmf, "Name=\"F\" AttributeType=\"Matrix\""), 3);
    assert_int_equal(count_occurrences(xmf, "AttributeType=\"Scalar\""), 0);
    free(xmf);
    path_of(path, sizeof path, dir, "grid.xmf");
    xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "Name=\"solid_grid\""), 6);
    assert_int_equal(count_occurrences(xmf, "other"), 0);
    assert_int_equal(count_occurrences(xmf, "Polyvertex"), 0);
    free(xmf);
  }
  free_set(&solid), free_set(&fluid), free_grid(&grid);
}

static void test_snapshot_3d(void **state) {
  (void)state;
  char dir[4200], path[4600];
  snap_dir(dir, sizeof dir, "snap3d");
  /* A long case text: more than fits in an HDF5 object header (64 KiB). */
  const size_t len = 100000;
  char *config = malloc(len + 1);
  for (size_t k = 0; k < len; ++k) config[k] = k % 64 == 63 ? '\n' : (char)('a' + k % 26);
  config[len] = 0;
  mpm_particles *solid = make_set(&g_solid3, g_rank), *empty = make_set(&g_empty3, g_rank);
  const mpm_particles *phases[2] = {solid, empty};
  const char *names[2] = {"solid", "empty"};
  mpm_grid *grid = make_grid(3);
  mpm_output *out;
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, config, 3, 0, 0.0), 0);
  assert_int_equal(mpm_output_snapshot(out, 0.25, 7, phases, names, 2, grid), 0);
  assert_int_equal(mpm_output_snapshot(out, 0.5, 8, phases, names, 1, NULL), 0);
  mpm_output_destroy(&out);
  MPI_Barrier(MPI_COMM_WORLD);
  if (g_rank == 0) {
    path_of(path, sizeof path, dir, "snap_000000.h5");
    const hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    check_root_attrs(f, 0.25, 7, 3, config);
    check_phase_file(f, &g_solid3);
    check_phase_file(f, &g_empty3); /* [0][3] datasets */
    check_grid_file(f, 3);
    H5Fclose(f);
    path_of(path, sizeof path, dir, "snap_000001.h5");
    const hid_t f1 = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f1 >= 0);
    assert_true(H5Lexists(f1, "/grid", H5P_DEFAULT) == 0);
    H5Fclose(f1);
    check_tools(dir, 2);
    path_of(path, sizeof path, dir, "series.xmf");
    char *xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "Name=\"empty\""), 0); /* no particles at all */
    assert_int_equal(count_occurrences(xmf, "AttributeType=\"Tensor\""), 2); /* F, twice */
    assert_int_equal(count_occurrences(xmf, "3DCoRectMesh"), 0);
    free(xmf);
    path_of(path, sizeof path, dir, "grid.xmf");
    xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "3DCoRectMesh"), 1); /* the first snapshot only */
    free(xmf);
  }
  free(config);
  free_set(&solid), free_set(&empty), free_grid(&grid);
}

/* Runs after test_snapshot_2d: keep t <= 0.5 of its three snapshots and go on from there. */
static void test_snapshot_append(void **state) {
  (void)state;
  char dir[4200], path[4600];
  snap_dir(dir, sizeof dir, "snap2d");
  mpm_particles *solid = make_set(&g_solid2, g_rank);
  const mpm_particles *phases[1] = {solid};
  const char *names[1] = {"solid"};
  mpm_output *out;
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, g_config2, 2, 1, 0.5), 0);
  assert_int_equal(mpm_output_count(out), 2);
  assert_int_equal(mpm_output_snapshot(out, 0.75, 15, phases, names, 1, NULL), 0);
  assert_int_equal(mpm_output_count(out), 3);
  mpm_output_destroy(&out);
  MPI_Barrier(MPI_COMM_WORLD);
  if (g_rank == 0) {
    path_of(path, sizeof path, dir, "series.xmf");
    char *xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "CollectionType=\"Spatial\""), 3);
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"0\"/>"), 1);
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"0.5\"/>"), 1);
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"0.75\"/>"), 1);
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"1\"/>"), 0);
    assert_int_equal(count_occurrences(xmf, "snap_000002.h5:/solid/x"), 1);
    assert_int_equal(count_occurrences(xmf, "Name=\"fluid\""), 4); /* kept entries verbatim */
    free(xmf);
    path_of(path, sizeof path, dir, "grid.xmf"); /* kept up to t = 0.5; none at 0.75 */
    xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "CollectionType=\"Spatial\""), 2);
    assert_int_equal(count_occurrences(xmf, "<Time Value=\"1\"/>"), 0);
    free(xmf);
    path_of(path, sizeof path, dir, "snap_000002.h5");
    const hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    assert_true(attr_double(f, "time", H5T_NATIVE_DOUBLE) == 0.75);
    H5Fclose(f);
    check_tools(dir, 3);
  }
  /* Restarting before every kept snapshot empties the index; restarting into a directory
   * without one starts at 0. */
  char other[4200];
  snap_dir(other, sizeof other, "append_fresh");
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, other, g_config2, 2, 1, 3.0), 0);
  assert_int_equal(mpm_output_count(out), 0);
  assert_int_equal(mpm_output_snapshot(out, 3.5, 1, phases, names, 1, NULL), 0);
  mpm_output_destroy(&out);
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, other, g_config2, 2, 1, -1.0), 0);
  assert_int_equal(mpm_output_count(out), 0);
  mpm_output_destroy(&out);
  free_set(&solid);
}

static void test_output_dir_errors(void **state) {
  (void)state;
  char file[4200], dir[4600];
  snap_dir(file, sizeof file, "a_file");
  if (g_rank == 0) {
    FILE *f = fopen(file, "w");
    fputs("not a directory\n", f);
    fclose(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  path_of(dir, sizeof dir, file, "sub");
  mpm_output *out = (mpm_output *)&out; /* not NULL: a failure must reset it */
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, "", 2, 0, 0.0), MPM_ERR_OUTPUT);
  assert_null(out);
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, file, "", 2, 0, 0.0), MPM_ERR_OUTPUT);
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, "", 1, 0, 0.0), MPM_ERR_INPUT);
  /* An index this module did not write is refused on a restart, not silently dropped. */
  snap_dir(dir, sizeof dir, "foreign_index");
  if (g_rank == 0) {
    mkdir(dir, 0777);
    path_of(file, sizeof file, dir, "series.xmf");
    FILE *f = fopen(file, "w");
    fputs("<Xdmf><Domain><Grid CollectionType=\"Spatial\"></Grid></Domain></Xdmf>\n", f);
    fclose(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, "", 2, 1, 1.0), MPM_ERR_INPUT);
}

/* The same through a grid made by mpm_grid.c, split along y this time, 3-D. */
static void test_snapshot_real_grid(void **state) {
  (void)state;
  char dir[4200], path[4600];
  snap_dir(dir, sizeof dir, "realgrid");
  const double lo[3] = {0.0, -1.0, 2.0}, hi[3] = {2.0, -1.0 + 1.5 * g_size, 3.5};
  const int nproc[3] = {1, g_size, 1};
  mpm_grid *g;
  int k = -1;
  assert_int_equal(mpm_grid_new(&g, MPI_COMM_WORLD, 3, lo, hi, 0.5, MPM_SHAPE_CUBIC, nproc), 0);
  assert_int_equal(mpm_grid_add_phase(g, "solid", &k), 0);
  mpm_grid_phase *ph = &g->phase[k];
  int gi[3];
  for (gi[2] = g->box_lo[2]; gi[2] < g->box_lo[2] + g->box_n[2]; ++gi[2])
    for (gi[1] = g->box_lo[1]; gi[1] < g->box_lo[1] + g->box_n[1]; ++gi[1])
      for (gi[0] = g->box_lo[0]; gi[0] < g->box_lo[0] + g->box_n[0]; ++gi[0]) {
        const mpm_lidx l = mpm_grid_local_index(g, gi);
        const int owned = mpm_grid_node_is_owned(g, l);
        ph->m_i[l] = owned ? node_value(gi, 0) : POISON;
        for (int d = 0; d < 3; ++d) ph->v_i[d][l] = owned ? node_value(gi, d + 1) : POISON;
      }
  mpm_particles *solid = make_set(&g_solid3, g_rank);
  const mpm_particles *phases[1] = {solid};
  const char *names[1] = {"solid"};
  mpm_output *out;
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, "", 3, 0, 0.0), 0);
  assert_int_equal(mpm_output_snapshot(out, 0.0, 0, phases, names, 1, g), 0);
  mpm_output_destroy(&out);
  MPI_Barrier(MPI_COMM_WORLD);
  if (g_rank == 0) {
    path_of(path, sizeof path, dir, "snap_000000.h5");
    const hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    int rank, n[3];
    hsize_t dims[4];
    for (int d = 0; d < 3; ++d) n[d] = g->ncells[d] + 1 + 2 * g->pad;
    double *m = read_all(f, "/grid/solid/m", H5T_NATIVE_DOUBLE, &rank, dims);
    double *v = read_all(f, "/grid/solid/v", H5T_NATIVE_DOUBLE, &rank, dims);
    size_t q = 0;
    for (gi[2] = -g->pad; gi[2] < n[2] - g->pad; ++gi[2])
      for (gi[1] = -g->pad; gi[1] < n[1] - g->pad; ++gi[1])
        for (gi[0] = -g->pad; gi[0] < n[0] - g->pad; ++gi[0], ++q) {
          assert_true(m[q] == node_value(gi, 0));
          for (int d = 0; d < 3; ++d) assert_true(v[3 * q + d] == node_value(gi, d + 1));
        }
    free(m), free(v);
    H5Fclose(f);
  }
  free_set(&solid);
  mpm_grid_destroy(&g);
}

/* ---- a refinement hierarchy ------------------------------------------------------------ */

static const set_spec g_levels2 = {"test", 2, 3, {{"x", 2}, {"v", 2}, {"p", 1}}};

/* Node values of a level: node_value of the global node plus 1000 per level. */
static void fill_level(mpm_grid *g, int phase, int level) {
  int gi[3];
  for (gi[2] = g->box_lo[2]; gi[2] < g->box_lo[2] + g->box_n[2]; ++gi[2])
    for (gi[1] = g->box_lo[1]; gi[1] < g->box_lo[1] + g->box_n[1]; ++gi[1])
      for (gi[0] = g->box_lo[0]; gi[0] < g->box_lo[0] + g->box_n[0]; ++gi[0]) {
        const mpm_lidx l = mpm_grid_local_index(g, gi);
        g->phase[phase].m_i[l] = node_value(gi, 0) + 1000.0 * level;
        for (int d = 0; d < g->dim; ++d)
          g->phase[phase].v_i[d][l] = node_value(gi, d + 1) + 1000.0 * level;
      }
}

/* n particles at the fixture's random points (half of them over the refined boxes). */
static mpm_particles *points_set(const fixture *f, int n) {
  mpm_particles *p = make_empty_set(&g_levels2);
  uint64_t rng = 12345;
  p->n = n;
  p->id = realloc(p->id, (size_t)n * sizeof *p->id);
  p->data = realloc(p->data, (size_t)n * p->ncomp * sizeof *p->data);
  for (int i = 0; i < n; ++i) {
    double x[3];
    fixture_point(f, &rng, i, x);
    p->id[i] = i;
    for (int c = 0; c < p->ncomp; ++c) p->data[(size_t)c * n + i] = c < 2 ? x[c] : 0.5;
  }
  p->id_next = n;
  return p;
}

/* Level l of the snapshot against the hierarchy: masks over the level's lattice (level 0's
 * owned nodes from -pad, a finer level's box) and, on finer levels, m and v. */
static void check_level(hid_t file, const mpm_hier *h, int l) {
  const mpm_grid *g = h->level[l].grid;
  const int first[2] = {l ? g->box_lo[0] : g->own_lo[0], l ? g->box_lo[1] : g->own_lo[1]};
  const int last[2] = {l ? g->box_lo[0] + g->box_n[0] : g->own_hi[0],
                       l ? g->box_lo[1] + g->box_n[1] : g->own_hi[1]};
  char name[64];
  int rank;
  hsize_t dims[4];
  snprintf(name, sizeof name, "/levels/%d/active", l);
  unsigned char *act = read_all(file, name, H5T_NATIVE_UCHAR, &rank, dims);
  snprintf(name, sizeof name, "/levels/%d/own", l);
  unsigned char *own = read_all(file, name, H5T_NATIVE_UCHAR, &rank, dims);
  assert_int_equal(dims[0], last[1] - first[1]);
  assert_int_equal(dims[1], last[0] - first[0]);
  double *m = NULL, *v = NULL;
  if (l) {
    snprintf(name, sizeof name, "/levels/%d/test/m", l);
    m = read_all(file, name, H5T_NATIVE_DOUBLE, &rank, dims);
    snprintf(name, sizeof name, "/levels/%d/test/v", l);
    v = read_all(file, name, H5T_NATIVE_DOUBLE, &rank, dims);
  }
  size_t q = 0;
  int gi[3] = {0, 0, 0};
  for (gi[1] = first[1]; gi[1] < last[1]; ++gi[1])
    for (gi[0] = first[0]; gi[0] < last[0]; ++gi[0], ++q) {
      const mpm_lidx k = mpm_grid_local_index(g, gi);
      assert_int_equal(act[q], h->level[l].active[k]);
      assert_int_equal(own[q], h->level[l].covered[k] && !h->level[l].refined[k]);
      if (!l) continue;
      assert_true(m[q] == node_value(gi, 0) + 1000.0 * l);
      for (int d = 0; d < 2; ++d) assert_true(v[2 * q + d] == node_value(gi, d + 1) + 1000.0 * l);
    }
  free(act), free(own), free(m), free(v);
}

/* The particles' level: mpm_hier_level_of of each position; every level has some. */
static void check_particle_levels(hid_t file, const mpm_hier *h, const mpm_particles *p) {
  int rank, seen[MPM_HIER_MAX_LEVELS] = {0};
  hsize_t dims[4];
  double *level = read_all(file, "/test/level", H5T_NATIVE_DOUBLE, &rank, dims);
  assert_int_equal(rank, 2);
  assert_int_equal(dims[0], p->n);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const double x[3] = {p->data[i], p->data[(size_t)p->n + i], 0.0};
    assert_true(level[i] == mpm_hier_level_of(h, x));
    seen[(int)level[i]] = 1;
  }
  for (int l = 0; l < h->nlevels; ++l) assert_true(seen[l]);
  free(level);
}

static void test_snapshot_levels(void **state) {
  (void)state;
  char dir[4200], path[4600];
  snap_dir(dir, sizeof dir, "levels");
  fixture f;
  assert_int_equal(fixture_make(&f, HIER_3LEV), 0);
  assert_int_equal(mpm_hier_add_phases(f.h), 0);
  for (int l = 0; l < f.h->nlevels; ++l) fill_level(f.h->level[l].grid, f.phase, l);
  mpm_particles *p = points_set(&f, 400);
  const mpm_particles *phases[1] = {p};
  const char *names[1] = {"test"};
  mpm_output *out;
  assert_int_equal(mpm_output_new(&out, MPI_COMM_WORLD, dir, "", 2, 0, 0.0), 0);
  /* On more than one rank every rank holds the finer levels whole and rank 0 writes them, so
   * each rank checks them against its own copy; level 0's parts and the particles' levels are
   * compared with one rank's end to end (test_refine_ranks_static). */
  assert_int_equal(mpm_output_set_hier(out, f.h), 0);
  assert_int_equal(mpm_output_snapshot(out, 0.5, 3, phases, names, 1, f.grid), 0);
  MPI_Barrier(MPI_COMM_WORLD);
  {
    path_of(path, sizeof path, dir, "snap_000000.h5");
    const hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    for (int l = g_size > 1; l < f.h->nlevels; ++l) check_level(file, f.h, l);
    if (g_size == 1) check_particle_levels(file, f.h, p);
    H5Fclose(file);
    path_of(path, sizeof path, dir, "grid.xmf");
    char *xmf = read_text(path);
    assert_non_null(xmf);
    assert_int_equal(count_occurrences(xmf, "Name=\"test_grid_l2\" GridType=\"Uniform\""), 1);
    for (int l = 0; l < f.h->nlevels; ++l) { /* each block reads its own level's masks */
      char item[64];
      snprintf(item, sizeof item, "snap_000000.h5:/levels/%d/own", l);
      assert_int_equal(count_occurrences(xmf, item), 1);
    }
    free(xmf);
  }
  mpm_output_destroy(&out);
  free_set(&p);
  fixture_free(&f);
}

/* ---- checkpoints ----------------------------------------------------------------------- */

static const char *g_ckconfig = "[run]\nname = checkpoint test\n";

static void ck_path(char *buf, size_t size, const char *name) {
  char dir[4200];
  snap_dir(dir, sizeof dir, "ck");
  if (g_rank == 0) mkdir(dir, 0777);
  MPI_Barrier(MPI_COMM_WORLD);
  path_of(buf, size, dir, name);
}

static int write_ck(MPI_Comm comm, const char *path, int r, double t) {
  mpm_particles *solid = make_set(&g_solid2, r), *fluid = make_set(&g_fluid2, r);
  const mpm_particles *phases[2] = {solid, fluid};
  const char *names[2] = {"solid", "fluid"};
  const char *attr_names[2] = {"time", "dt"};
  const double attr_values[2] = {t, 1e-3 / 3};
  const int rc =
      mpm_checkpoint_write(comm, path, g_ckconfig, attr_names, attr_values, 2, phases, names, 2);
  free_set(&solid), free_set(&fluid);
  return rc;
}

/* The set read back is bitwise the set written by this rank. */
static void check_same_set(const mpm_particles *a, const mpm_particles *b) {
  assert_int_equal(a->n, b->n);
  assert_int_equal(a->id_next, b->id_next);
  assert_memory_equal(a->id, b->id, (size_t)a->n * sizeof *a->id);
  assert_memory_equal(a->data, b->data, (size_t)a->n * a->ncomp * sizeof *a->data);
}

static void test_checkpoint_roundtrip(void **state) {
  (void)state;
  char path[4600];
  ck_path(path, sizeof path, "roundtrip.h5");
  assert_int_equal(write_ck(MPI_COMM_WORLD, path, g_rank, 0.125), 0);
  mpm_checkpoint *ck;
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path), 0);
  assert_string_equal(mpm_checkpoint_config(ck), g_ckconfig);
  double t = 0, dt = 0;
  assert_int_equal(mpm_checkpoint_attr(ck, "time", &t), 0);
  assert_int_equal(mpm_checkpoint_attr(ck, "dt", &dt), 0);
  assert_true(t == 0.125 && dt == 1e-3 / 3);
  assert_int_equal(mpm_checkpoint_attr(ck, "nothing", &t), MPM_ERR_INPUT);
  const set_spec *specs[2] = {&g_solid2, &g_fluid2};
  for (int k = 0; k < 2; ++k) {
    mpm_particles *want = make_set(specs[k], g_rank);
    mpm_particles *got = k ? make_set(&g_fluid2, g_rank + 5) : make_empty_set(specs[k]);
    assert_int_equal(mpm_checkpoint_read_particles(ck, specs[k]->phase, got), 0);
    check_same_set(want, got);
    free_set(&want), free_set(&got);
  }
  /* the wrong layout, a missing phase */
  mpm_particles *wrong = make_empty_set(&g_fluid2);
  assert_int_equal(mpm_checkpoint_read_particles(ck, "solid", wrong), MPM_ERR_INPUT);
  assert_int_equal(mpm_checkpoint_read_particles(ck, "gas", wrong), MPM_ERR_INPUT);
  free_set(&wrong);
  mpm_checkpoint_close(&ck);
  assert_null(ck);
  if (g_rank == 0) {
    char tmp[4700];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_int_not_equal(access(tmp, F_OK), 0);
    if (tool_exists("h5dump")) assert_int_equal(run_tool("h5dump", "-H", path), 0);
  }
}

/* Written on the first size - 1 ranks, read on all: even chunks of the rank-order rows. */
static void test_checkpoint_other_rank_count(void **state) {
  (void)state;
  if (g_size < 2) {
    print_message("1 rank: the even-chunk path needs a run on 2 or more ranks\n");
    skip();
  }
  char path[4600];
  ck_path(path, sizeof path, "fewer_ranks.h5");
  MPI_Comm sub;
  MPI_Comm_split(MPI_COMM_WORLD, g_rank < g_size - 1 ? 0 : MPI_UNDEFINED, g_rank, &sub);
  if (sub != MPI_COMM_NULL) {
    assert_int_equal(write_ck(sub, path, g_rank, 2.0), 0);
    MPI_Comm_free(&sub);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  mpm_checkpoint *ck;
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path), 0);
  const set_spec *specs[2] = {&g_solid2, &g_fluid2};
  for (int k = 0; k < 2; ++k) {
    /* the rows as written: ranks 0 .. size-2 in order */
    int64_t total = 0;
    for (int r = 0; r < g_size - 1; ++r) total += count_on(specs[k], r);
    int64_t *rid = malloc(((size_t)total + 1) * sizeof *rid), row = 0;
    for (int r = 0; r < g_size - 1; ++r)
      for (int i = 0; i < count_on(specs[k], r); ++i) rid[row++] = id_on(specs[k], r, i);
    const int64_t q = total / g_size, rem = total % g_size;
    const int64_t first = g_rank * q + (g_rank < rem ? g_rank : rem), n = q + (g_rank < rem);
    mpm_particles *got = make_empty_set(specs[k]);
    assert_int_equal(mpm_checkpoint_read_particles(ck, specs[k]->phase, got), 0);
    assert_int_equal(got->n, n);
    assert_int_equal(got->id_next, 7777777);
    for (int i = 0; i < got->n; ++i) {
      assert_int_equal(got->id[i], rid[first + i]);
      for (int c = 0; c < got->ncomp; ++c)
        assert_true(got->data[(size_t)c * got->n + i] == value(got->id[i], c));
    }
    free(rid);
    free_set(&got);
  }
  mpm_checkpoint_close(&ck);
}

static void test_checkpoint_bad_files(void **state) {
  (void)state;
  char path[4600], text[4600];
  mpm_checkpoint *ck = (mpm_checkpoint *)&ck; /* not NULL: a failure must reset it */
  ck_path(path, sizeof path, "does_not_exist.h5");
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path), MPM_ERR_INPUT);
  assert_null(ck);
  ck_path(text, sizeof text, "text.h5");
  if (g_rank == 0) {
    FILE *f = fopen(text, "w");
    fputs("[run]\nthis is a case file, not a checkpoint\n", f);
    fclose(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, text), MPM_ERR_INPUT);
  /* an HDF5 file, but a snapshot */
  snap_dir(text, sizeof text, "snap2d/snap_000000.h5");
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, text), MPM_ERR_INPUT);
}

static void test_checkpoint_failed_write(void **state) {
  (void)state;
  char path[4600], tmp[4700], missing[4600];
  ck_path(path, sizeof path, "keep.h5");
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  assert_int_equal(write_ck(MPI_COMM_WORLD, path, g_rank, 1.0), 0);
  /* A directory in the way of PATH.tmp makes the next write fail at the start. */
  if (g_rank == 0) assert_int_equal(mkdir(tmp, 0777), 0);
  MPI_Barrier(MPI_COMM_WORLD);
  assert_int_equal(write_ck(MPI_COMM_WORLD, path, g_rank, 2.0), MPM_ERR_OUTPUT);
  mpm_checkpoint *ck;
  double t = 0;
  assert_int_equal(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path), 0);
  assert_int_equal(mpm_checkpoint_attr(ck, "time", &t), 0);
  assert_true(t == 1.0); /* the earlier checkpoint, intact */
  mpm_particles *want = make_set(&g_solid2, g_rank), *got = make_empty_set(&g_solid2);
  assert_int_equal(mpm_checkpoint_read_particles(ck, "solid", got), 0);
  check_same_set(want, got);
  free_set(&want), free_set(&got);
  mpm_checkpoint_close(&ck);
  MPI_Barrier(MPI_COMM_WORLD);
  if (g_rank == 0) rmdir(tmp);
  /* A directory that does not exist: an error, and nothing at the path. */
  ck_path(missing, sizeof missing, "no/such/dir/ck.h5");
  assert_int_equal(write_ck(MPI_COMM_WORLD, missing, g_rank, 1.0), MPM_ERR_OUTPUT);
  assert_int_not_equal(access(missing, F_OK), 0);
}

/* ---- main ------------------------------------------------------------------------------ */

static int prepare_root(void **state) {
  (void)state;
  if (g_rank == 0) {
    remove_tree(g_root);
    mkdir(g_root, 0777);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return 0;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  snprintf(g_root, sizeof g_root, "%s", argc > 1 ? argv[1] : "test_output_dir");
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_snapshot_2d),
      cmocka_unit_test(test_snapshot_3d),
      cmocka_unit_test(test_snapshot_append),
      cmocka_unit_test(test_snapshot_real_grid),
      cmocka_unit_test(test_snapshot_levels),
      cmocka_unit_test(test_output_dir_errors),
      cmocka_unit_test(test_checkpoint_roundtrip),
      cmocka_unit_test(test_checkpoint_other_rank_count),
      cmocka_unit_test(test_checkpoint_bad_files),
      cmocka_unit_test(test_checkpoint_failed_write),
  };
  const int failed = cmocka_run_group_tests(tests, prepare_root, NULL);
  int any = failed;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any ? 1 : 0;
}
