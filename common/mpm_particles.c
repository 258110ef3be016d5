/* Particle storage: the component-major block, edits, injection of fresh ids, migration to
 * the owning rank and sorting by cell. mpm_particles.h states the layout; this file keeps
 * these invariants:
 *
 * - data holds ncomp * n doubles, component c of particle i at data[c * n + i]; id[i] is
 *   the global id of particle i. The block is only ever replaced whole (install()), so n,
 *   id and data always change together. The block replaced is kept as the spare and reused
 *   by the next replacement that fits in it (block_get()): a pointer into the block is
 *   valid only until the next edit, migration or sort.
 * - A derived field (mpm_particles_set_derived) is not moved by an edit or a sort: its values
 *   are undefined after one until the module that owns it fills it again.
 * - Ids are unique over all ranks and never reused: id_next exceeds every id handed out
 *   and is equal on every rank (inject() advances it by the global count on every rank).
 * - Migration first wraps positions that left through a periodic face back into [lo, hi)
 *   (mpm_grid_wrap), so ownership and every later use see a position inside the domain.
 * - Migration keeps the order of the particles that stay and appends arrivals in source
 *   rank order; sorting is stable. A run is therefore reproducible for a given rank count.
 * - Collective operations never leave a rank behind: every local failure (a particle out of
 *   the domain, an allocation) is agreed on with an MPI_Allreduce before the next
 *   collective, so all ranks return the same error instead of deadlocking. */
#include "mpm_particles.h"
#include "mpm_error.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- construction ---------------------------------------------------------------------- */

static int check_fields(int dim, const mpm_field_desc *fields, int nfields, int nstate_fields) {
  if (dim < 1 || dim > MPM_MAX_DIM) MPM_FAIL(MPM_ERR_INPUT, "particles: dimension %d", dim);
  if (nfields < 2 || nfields > MPM_PARTICLES_MAX_FIELDS)
    MPM_FAIL(MPM_ERR_INPUT, "particles: %d fields; need 2 (x, v) to %d", nfields,
             MPM_PARTICLES_MAX_FIELDS);
  if (nstate_fields < 0 || nstate_fields > nfields)
    MPM_FAIL(MPM_ERR_INPUT, "particles: %d state fields out of %d", nstate_fields, nfields);
  if (fields[0].ncomp != dim || fields[1].ncomp != dim)
    MPM_FAIL(MPM_ERR_INPUT, "particles: fields 0 and 1 (x and v) need %d components", dim);
  for (int f = 0; f < nfields; ++f) {
    if (!fields[f].name || !fields[f].name[0] || fields[f].ncomp < 1 ||
        fields[f].ncomp > MPM_PARTICLES_MAX_NCOMP)
      MPM_FAIL(MPM_ERR_INPUT, "particles: field %d needs a name and 1 to %d components", f,
               MPM_PARTICLES_MAX_NCOMP);
    for (int e = 0; e < f; ++e)
      if (strcmp(fields[e].name, fields[f].name) == 0)
        MPM_FAIL(MPM_ERR_INPUT, "particles: field '%s' is listed twice", fields[f].name);
  }
  return 0;
}

/* The set keeps its own copies of the names: descriptors often come from temporary tables. */
static int copy_fields(mpm_particles *p, const mpm_field_desc *fields, int nfields) {
  for (int f = 0; f < nfields; ++f) {
    const size_t len = strlen(fields[f].name) + 1;
    char *name;
    MPM_ALLOC(name, len);
    memcpy(name, fields[f].name, len);
    p->field[f].name = name;
    p->field[f].ncomp = fields[f].ncomp;
    p->offset[f] = p->ncomp;
    p->ncomp += fields[f].ncomp;
    p->nfields = f + 1;
  }
  return 0;
}

int mpm_particles_new(mpm_particles **p, int dim, const mpm_field_desc *fields, int nfields,
                      int nstate_fields) {
  mpm_particles *s;
  *p = NULL;
  MPM_CALL(check_fields(dim, fields, nfields, nstate_fields));
  MPM_ALLOC(s, 1);
  s->dim = dim;
  s->nstate_fields = nstate_fields;
  int rc = copy_fields(s, fields, nfields);
  if (!rc) rc = mpm_particles_edit(s, NULL, 0, NULL, NULL); /* an empty, non-NULL block */
  if (rc) {
    mpm_particles_destroy(&s);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  for (int f = 0; f < nstate_fields; ++f) s->nstate += fields[f].ncomp;
  *p = s;
  return 0;
}

void mpm_particles_destroy(mpm_particles **p) {
  if (!p || !*p) return;
  for (int f = 0; f < (*p)->nfields; ++f) free((char *)(*p)->field[f].name);
  free((*p)->id), free((*p)->spare_id);
  free((*p)->data), free((*p)->spare_data);
  free((*p)->later.keep), free((*p)->later.id), free((*p)->later.data);
  free(*p);
  *p = NULL;
}

int mpm_particles_find(const mpm_particles *p, const char *name) {
  for (int f = 0; f < p->nfields; ++f)
    if (strcmp(p->field[f].name, name) == 0) return f;
  return -1;
}

/* ---- the block ------------------------------------------------------------------------- */

/* A block with room for n particles: the spare if it is large enough, else a new one with an
 * eighth more room than asked, so that a slowly growing set does not allocate at every step.
 * Its contents are undefined: every caller writes all n particles of every component. */
static int block_get(mpm_particles *p, mpm_lidx n, mpm_gidx **id, double **data, mpm_lidx *cap) {
  if (p->spare_data && p->spare_cap >= n) {
    *id = p->spare_id, *data = p->spare_data, *cap = p->spare_cap;
    p->spare_id = NULL, p->spare_data = NULL, p->spare_cap = 0;
    return 0;
  }
  const mpm_lidx room = n + n / 8 + 16;
  *id = malloc(sizeof **id * (size_t)room);
  *data = malloc(sizeof **data * (size_t)p->ncomp * (size_t)room);
  if (!*id || !*data) {
    free(*id), free(*data), *id = NULL, *data = NULL;
    MPM_FAIL_OOM((double)p->ncomp * (double)room * sizeof **data);
  }
  *cap = room;
  return 0;
}

/* Replace the block by (n, id, data) of room cap, which the set now owns; the old block
 * becomes the spare. Component c starts at data + c n (the stride is n, not cap: the state
 * components stay one contiguous array for the integrator). */
static void install(mpm_particles *p, mpm_lidx n, mpm_gidx *id, double *data, mpm_lidx cap) {
  free(p->spare_id), free(p->spare_data);
  p->spare_id = p->id, p->spare_data = p->data, p->spare_cap = p->cap;
  p->n = n, p->id = id, p->data = data, p->cap = cap;
}

static mpm_lidx count_kept(const mpm_particles *p, const unsigned char *keep) {
  if (!keep) return p->n;
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) k += keep[i] != 0;
  return k;
}

/* The components an edit or a sort moves, those of the fields that are not derived, into
 * comp; returns their number. */
static int moved_components(const mpm_particles *p, int *comp) {
  int n = 0;
  for (int f = 0; f < p->nfields; ++f)
    for (int c = 0; !(p->derived >> f & 1u) && c < p->field[f].ncomp; ++c)
      comp[n++] = p->offset[f] + c;
  return n;
}

void mpm_particles_set_derived(mpm_particles *p, int f) {
  if (f >= 0 && f < p->nfields) p->derived |= 1u << f;
}

void mpm_particles_set_scratch(mpm_particles *p, int f) {
  if (f >= 0 && f < p->nfields) p->scratch |= 1u << f;
}

/* Copy the kept particles, in order, to the front of a block whose components are nnew
 * apart. Runs of kept particles go by memcpy: an edit or a migration keeps nearly all. */
static void copy_kept(const mpm_particles *p, const unsigned char *keep, mpm_lidx nnew,
                      mpm_gidx *id, double *data) {
  int comp[MPM_PARTICLES_MAX_COMPONENTS];
  const int nmoved = moved_components(p, comp);
  mpm_lidx k = 0;
  for (mpm_lidx i = 0; i < p->n;) {
    mpm_lidx j = i;
    while (j < p->n && (!keep || keep[j])) ++j;
    const size_t run = (size_t)(j - i);
    if (run) {
      memcpy(id + k, p->id + i, run * sizeof *id);
      for (int q = 0; q < nmoved; ++q) {
        const size_t c = (size_t)comp[q];
        memcpy(data + c * (size_t)nnew + (size_t)k, p->data + c * (size_t)p->n + i,
               run * sizeof *data);
      }
    }
    k += (mpm_lidx)run;
    for (i = j; i < p->n && keep && !keep[i];) ++i; /* the dropped run */
  }
}

static int edit_now(mpm_particles *p, const unsigned char *keep, mpm_lidx nadd,
                    const mpm_gidx *add_id, const double *add_data) {
  if (nadd < 0 || (nadd > 0 && !add_id))
    MPM_FAIL(MPM_ERR_INPUT, "particles: cannot add %d particles without ids", (int)nadd);
  const mpm_lidx kept = count_kept(p, keep);
  if ((int64_t)kept + nadd > INT32_MAX)
    MPM_FAIL(MPM_ERR_INPUT, "particles: %d + %d particles exceed the local index range", (int)kept,
             (int)nadd);
  const mpm_lidx nnew = kept + nadd;
  mpm_gidx *id;
  double *data;
  mpm_lidx cap;
  MPM_CALL(block_get(p, nnew, &id, &data, &cap));
  copy_kept(p, keep, nnew, id, data);
  if (nadd > 0) memcpy(id + kept, add_id, (size_t)nadd * sizeof *id);
  for (int c = 0; c < p->ncomp && nadd > 0 && add_data; ++c)
    memcpy(data + (size_t)c * (size_t)nnew + (size_t)kept, add_data + (size_t)c * (size_t)nadd,
           (size_t)nadd * sizeof *data);
  install(p, nnew, id, data, cap);
  return 0;
}

/* A call that reads or changes the set while a deferred edit waits for its migration. */
static int fail_if_deferred(const mpm_particles *p, const char *what) {
  if (p->later.set)
    MPM_FAIL(MPM_ERR_INTERNAL,
             "particles: %s while a deferred edit waits for the next migration (a module's "
             "boundary step must be followed by mpm_particles_migrate)",
             what);
  return 0;
}

int mpm_particles_edit(mpm_particles *p, const unsigned char *keep, mpm_lidx nadd,
                       const mpm_gidx *add_id, const double *add_data) {
  MPM_CALL(fail_if_deferred(p, "an edit"));
  return edit_now(p, keep, nadd, add_id, add_data);
}

static void later_clear(mpm_particles *p) {
  free(p->later.keep), free(p->later.id), free(p->later.data);
  memset(&p->later, 0, sizeof p->later);
}

int mpm_particles_edit_deferred(mpm_particles *p, unsigned char *keep, mpm_lidx nadd,
                                mpm_gidx *add_id, double *add_data) {
  const char *bad = p->later.set ? "another deferred edit is still pending"
                    : nadd < 0 || (nadd > 0 && (!add_id || !add_data))
                        ? "particles to add without ids or data"
                    : (int64_t)count_kept(p, keep) + nadd > INT32_MAX
                        ? "the particles would exceed the local index range"
                        : NULL;
  if (bad) {
    const int code = p->later.set ? MPM_ERR_INTERNAL : MPM_ERR_INPUT;
    free(keep), free(add_id), free(add_data);
    MPM_FAIL(code, "particles: cannot defer an edit: %s", bad);
  }
  p->later.set = 1, p->later.keep = keep, p->later.nadd = nadd;
  p->later.id = add_id, p->later.data = add_data;
  return 0;
}

int mpm_particles_inject(mpm_particles *p, MPI_Comm comm, mpm_lidx nadd, const double *add_data) {
  int rank;
  mpm_gidx mine = nadd > 0 ? nadd : 0, before = 0, total = 0;
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  MPM_CALL_MPI(MPI_Exscan(&mine, &before, 1, MPM_MPI_GIDX, MPI_SUM, comm));
  MPM_CALL_MPI(MPI_Allreduce(&mine, &total, 1, MPM_MPI_GIDX, MPI_SUM, comm));
  if (rank == 0) before = 0; /* MPI_Exscan leaves rank 0's result undefined */
  const mpm_gidx first = p->id_next + before;
  p->id_next += total; /* on every rank, even if the local edit below fails */
  mpm_gidx *ids;
  MPM_ALLOC(ids, mine);
  for (mpm_lidx i = 0; i < (mpm_lidx)mine; ++i) ids[i] = first + i;
  const int rc = mpm_particles_edit(p, NULL, nadd, ids, add_data);
  free(ids);
  MPM_CALL(rc);
  return 0;
}

int mpm_particles_global_count(const mpm_particles *p, MPI_Comm comm, mpm_gidx *count) {
  mpm_gidx n = p->n;
  MPM_CALL_MPI(MPI_Allreduce(&n, count, 1, MPM_MPI_GIDX, MPI_SUM, comm));
  return 0;
}

/* ---- migration ------------------------------------------------------------------------- */

_Static_assert(sizeof(mpm_gidx) == sizeof(double), "a particle id must fit a double's slot");

/* The buffers of one migration. A record is the id (its bits in one double slot) followed by
 * the ncomp components. count/displ hold [0, size) for sends, [size, 2 size) for receives,
 * in records. */
typedef struct migration {
  int *dest;
  unsigned char *keep;
  int *count, *displ;
  double *sendbuf, *recvbuf;
  mpm_gidx *id; /* the new block, filled after the exchange */
  double *data;
  mpm_lidx cap;
  mpm_lidx nmove, nkeep, nrecv;
} migration;

static void migration_free(migration *m) {
  free(m->dest), free(m->keep), free(m->count), free(m->displ);
  free(m->sendbuf), free(m->recvbuf), free(m->id), free(m->data);
}

/* calloc for code that must still reach a collective: failure is recorded in *rc. */
static void *try_alloc(size_t n, size_t size, int *rc) {
  void *q = calloc(n ? n : 1, size);
  if (!q && !*rc) {
    mpm_log_all(MPM_LOG_ERROR, MPM_OOM_MESSAGE, (double)n * (double)size / 1e6);
    *rc = mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_MEMORY);
  }
  return q;
}

/* "(x, y[, z])"; buf must hold 3 numbers (80 characters is plenty). */
static void format_point(char *buf, size_t len, const double *x, int dim) {
  snprintf(buf, len,
           dim == 1   ? "(%.9g)"
           : dim == 2 ? "(%.9g, %.9g)"
                      : "(%.9g, %.9g, %.9g)",
           x[0], dim > 1 ? x[1] : 0.0, dim > 2 ? x[2] : 0.0);
}

/* The particles a migration distributes: the set's own, then the additions of a deferred edit
 * (mpm_particles_edit_deferred), whose dropped particles take no part. */
static mpm_lidx src_count(const mpm_particles *p) {
  return p->n + (p->later.set ? p->later.nadd : 0);
}

static int src_dropped(const mpm_particles *p, mpm_lidx i) {
  return i < p->n && p->later.keep && !p->later.keep[i];
}

static double *src_value(const mpm_particles *p, mpm_lidx i, int c) {
  return i < p->n ? p->data + (size_t)c * (size_t)p->n + i
                  : p->later.data + (size_t)c * (size_t)p->later.nadd + (i - p->n);
}

static mpm_gidx src_id(const mpm_particles *p, mpm_lidx i) {
  return i < p->n ? p->id[i] : p->later.id[i - p->n];
}

static int report_outside(const mpm_particles *p, const mpm_grid *g, mpm_lidx i, mpm_lidx nout) {
  char at[128], lo[128], hi[128];
  double x[MPM_MAX_DIM] = {0};
  for (int d = 0; d < p->dim; ++d) x[d] = *src_value(p, i, d);
  format_point(at, sizeof at, x, p->dim);
  format_point(lo, sizeof lo, g->lo, g->dim);
  format_point(hi, sizeof hi, g->hi, g->dim);
  MPM_FAIL(MPM_ERR_UNPHYSICAL,
           "particle %" PRId64 " at %s left the domain [%s, %s] (%d particle(s) outside on this "
           "rank); reduce the time step or check the boundary conditions that hold it in",
           src_id(p, i), at, lo, hi, (int)nout);
}

/* Wrap positions across periodic faces; returns how many particles moved. */
static mpm_lidx wrap_positions(mpm_particles *p, const mpm_grid *g) {
  mpm_lidx nwrap = 0;
  int any = 0;
  for (int d = 0; d < g->dim; ++d) any |= g->periodic[d];
  if (!any) return 0; /* no pass over the particles when nothing can wrap */
  for (mpm_lidx i = 0; i < src_count(p); ++i) {
    double x[MPM_MAX_DIM];
    if (src_dropped(p, i)) continue;
    for (int d = 0; d < p->dim; ++d) x[d] = *src_value(p, i, d);
    if (!mpm_grid_wrap(g, x)) continue;
    for (int d = 0; d < p->dim; ++d) *src_value(p, i, d) = x[d];
    nwrap++;
  }
  return nwrap;
}

/* Owner of every particle (a dropped one: -2, neither kept nor sent); fails naming the first
 * particle outside the domain. Most particles stay: one that lies inside this rank's cells by
 * more than a millionth of a cell along every axis is its own without mpm_grid_owner_of's
 * division (the margin is far above the division's roundoff, so the two tests never
 * disagree); the rest, near a rank face, ask it. */
static int find_owners(const mpm_particles *p, const mpm_grid *g, migration *m) {
  mpm_lidx nout = 0, first = -1;
  double in_lo[MPM_MAX_DIM], in_hi[MPM_MAX_DIM];
  for (int d = 0; d < p->dim; ++d) {
    const int *split = g->cell_split[d], c = g->coord[d];
    in_lo[d] = g->lo[d] + (split[c] + 1e-6) * g->dx;
    in_hi[d] = g->lo[d] + (split[c + 1] - 1e-6) * g->dx;
  }
  const double *xp[MPM_MAX_DIM] = {NULL};
  for (int d = 0; d < p->dim; ++d) xp[d] = mpm_particles_comp(p, 0, d);
  for (mpm_lidx i = 0; i < src_count(p); ++i) {
    if (src_dropped(p, i)) {
      m->dest[i] = -2, m->keep[i] = 0;
      continue;
    }
    double x[MPM_MAX_DIM];
    int inside = 1;
    for (int d = 0; d < p->dim; ++d) {
      x[d] = i < p->n ? xp[d][i] : *src_value(p, i, d);
      inside &= x[d] > in_lo[d] && x[d] < in_hi[d]; /* false for NaN */
    }
    m->dest[i] = inside ? g->rank : mpm_grid_owner_of(g, x);
    if (m->dest[i] < 0 && nout++ == 0) first = i;
    m->keep[i] = m->dest[i] == g->rank;
    m->nmove += m->dest[i] != g->rank && m->dest[i] >= 0;
    m->nkeep += m->keep[i];
  }
  return nout ? report_outside(p, g, first, nout) : 0;
}

static void prefix_sum(const int *count, int *displ, int n) {
  displ[0] = 0;
  for (int r = 1; r < n; ++r) displ[r] = displ[r - 1] + count[r - 1];
}

/* Pack the movers by destination rank, in particle order within each destination. */
static void pack_movers(const mpm_particles *p, const mpm_grid *g, migration *m) {
  const size_t rec = 1 + (size_t)p->ncomp;
  for (mpm_lidx i = 0; i < src_count(p); ++i) {
    if (m->keep[i] || m->dest[i] < 0) continue;
    double *r = m->sendbuf + (size_t)m->displ[m->dest[i]]++ * rec;
    const mpm_gidx id = src_id(p, i);
    memcpy(r, &id, sizeof *r);
    for (int c = 0; c < p->ncomp; ++c) r[1 + c] = *src_value(p, i, c);
  }
  prefix_sum(m->count, m->displ, g->size); /* packing advanced displ; restore it */
}

/* Everything before the first collective: owners, send counts and the packed movers. */
static int plan_sends(const mpm_particles *p, const mpm_grid *g, migration *m) {
  int rc = 0;
  const mpm_lidx n = src_count(p);
  m->dest = try_alloc((size_t)n, sizeof *m->dest, &rc);
  m->keep = try_alloc((size_t)n, sizeof *m->keep, &rc);
  m->count = try_alloc(2 * (size_t)g->size, sizeof *m->count, &rc);
  m->displ = try_alloc(2 * (size_t)g->size, sizeof *m->displ, &rc);
  if (rc) return rc;
  MPM_CALL(find_owners(p, g, m));
  for (mpm_lidx i = 0; i < n; ++i)
    if (m->dest[i] >= 0) m->count[m->dest[i]] += !m->keep[i];
  prefix_sum(m->count, m->displ, g->size);
  m->sendbuf = try_alloc((size_t)m->nmove * (1 + (size_t)p->ncomp), sizeof(double), &rc);
  if (rc) return rc;
  pack_movers(p, g, m);
  return 0;
}

/* After the counts arrived: receive offsets and room for arrivals and the new block. */
static int plan_receives(mpm_particles *p, const mpm_grid *g, migration *m) {
  int rc = 0, *rcount = m->count + g->size;
  int64_t nrecv = 0;
  for (int r = 0; r < g->size; ++r) nrecv += rcount[r];
  if (nrecv + m->nkeep > INT32_MAX)
    MPM_FAIL(MPM_ERR_INPUT,
             "particles: %" PRId64 " particles would exceed the local index range of one "
             "rank; use more ranks",
             nrecv + m->nkeep);
  m->nrecv = (mpm_lidx)nrecv;
  prefix_sum(rcount, m->displ + g->size, g->size);
  m->recvbuf = try_alloc((size_t)m->nrecv * (1 + (size_t)p->ncomp), sizeof(double), &rc);
  if (!rc) rc = block_get(p, m->nkeep + m->nrecv, &m->id, &m->data, &m->cap);
  return rc;
}

static int alltoallv_records(const mpm_particles *p, const mpm_grid *g, migration *m) {
  MPI_Datatype rec;
  const int bytes = (int)((1 + (size_t)p->ncomp) * sizeof(double));
  /* Bytes, not doubles: the id travels as raw bits in a double slot. */
  MPM_CALL_MPI(MPI_Type_contiguous(bytes, MPI_BYTE, &rec));
  MPM_CALL_MPI(MPI_Type_commit(&rec));
  const int rc = MPI_Alltoallv(m->sendbuf, m->count, m->displ, rec, m->recvbuf, m->count + g->size,
                               m->displ + g->size, rec, g->comm);
  MPI_Type_free(&rec);
  if (rc != MPI_SUCCESS) MPM_FAIL(MPM_ERR_MPI, "MPI_Alltoallv failed with MPI error %d", rc);
  return 0;
}

/* Kept particles first, in order (a deferred edit's additions after the set's own), then the
 * arrivals in source rank order. */
static void assemble(mpm_particles *p, migration *m) {
  const size_t rec = 1 + (size_t)p->ncomp, nnew = (size_t)(m->nkeep + m->nrecv);
  copy_kept(p, m->keep, (mpm_lidx)nnew, m->id, m->data);
  size_t k = (size_t)count_kept(p, m->keep);
  for (mpm_lidx i = p->n; i < src_count(p); ++i) {
    if (!m->keep[i]) continue;
    m->id[k] = src_id(p, i);
    for (int c = 0; c < p->ncomp; ++c) m->data[(size_t)c * nnew + k] = *src_value(p, i, c);
    ++k;
  }
  for (mpm_lidx j = 0; j < m->nrecv; ++j) {
    const double *r = m->recvbuf + (size_t)j * rec;
    const size_t i = (size_t)(m->nkeep + j);
    memcpy(&m->id[i], r, sizeof *r);
    for (int c = 0; c < p->ncomp; ++c) m->data[(size_t)c * nnew + i] = r[1 + c];
  }
  install(p, (mpm_lidx)nnew, m->id, m->data, m->cap);
  m->id = NULL, m->data = NULL;
}

static int exchange(mpm_particles *p, const mpm_grid *g, migration *m) {
  MPM_CALL_MPI(MPI_Alltoall(m->count, 1, MPI_INT, m->count + g->size, 1, MPI_INT, g->comm));
  int rc = plan_receives(p, g, m);
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &rc, 1, MPI_INT, MPI_MAX, g->comm));
  MPM_CALL(rc);
  MPM_CALL(alltoallv_records(p, g, m));
  assemble(p, m);
  return 0;
}

int mpm_particles_migrate(mpm_particles *p, const mpm_grid *grid, int *changed) {
  migration m = {0};
  /* error code, whether anything moves, whether a position wrapped; agreed on by every rank */
  int status[3];
  if (changed) *changed = 0;
  status[2] = wrap_positions(p, grid) > 0;
  status[0] = plan_sends(p, grid, &m);
  status[1] = m.nmove > 0;
  int rc = MPI_Allreduce(MPI_IN_PLACE, status, 3, MPI_INT, MPI_MAX, grid->comm);
  if (rc != MPI_SUCCESS) {
    migration_free(&m);
    MPM_FAIL(MPM_ERR_MPI, "MPI_Allreduce failed with MPI error %d", rc);
  }
  rc = status[0]; /* a rank with no bad particle returns the error some other rank found */
  if (!rc && status[1]) {
    rc = exchange(p, grid, &m);
    if (changed) *changed = !rc;
  } else if (!rc) {
    /* Nothing moves: a deferred edit is applied on its own. Its caller reported the change. */
    if (p->later.set) rc = edit_now(p, p->later.keep, p->later.nadd, p->later.id, p->later.data);
    if (changed) *changed = status[2]; /* the state changed in place: an integrator must hear */
  }
  later_clear(p);
  migration_free(&m);
  MPM_CALL(rc);
  return 0;
}

/* ---- sorting --------------------------------------------------------------------------- */

/* Cell coordinate along d of every particle, clamped into the grid: a particle outside the
 * domain is migrate()'s error to report, sorting only needs a key. */
static void cell_coords(const mpm_particles *p, const mpm_grid *g, int d, int *cell) {
  const double *x = mpm_particles_comp(p, 0, d);
  const int last = g->ncells[d] - 1;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    const double r = (x[i] - g->lo[d]) / g->dx;
    cell[i] = !(r >= 0) ? 0 : r >= last ? last : (int)r;
  }
}

/* One stable counting-sort pass of the permutation `perm` by key[perm[i]] in [0, nkeys). */
static void counting_pass(const int *key, int nkeys, mpm_lidx n, const mpm_lidx *perm,
                          mpm_lidx *out, mpm_lidx *start) {
  memset(start, 0, ((size_t)nkeys + 1) * sizeof *start);
  for (mpm_lidx i = 0; i < n; ++i) start[key[perm[i]] + 1]++;
  for (int k = 0; k < nkeys; ++k) start[k + 1] += start[k];
  for (mpm_lidx i = 0; i < n; ++i) out[start[key[perm[i]]]++] = perm[i];
}

static int apply_permutation(mpm_particles *p, const mpm_lidx *perm) {
  mpm_gidx *id;
  double *data;
  mpm_lidx cap;
  MPM_CALL(block_get(p, p->n, &id, &data, &cap));
  for (mpm_lidx k = 0; k < p->n; ++k) id[k] = p->id[perm[k]];
  int comp[MPM_PARTICLES_MAX_COMPONENTS];
  const int nmoved = moved_components(p, comp);
  for (int q = 0; q < nmoved; ++q) {
    const int c = comp[q];
    const double *src = p->data + (size_t)c * (size_t)p->n;
    double *dst = data + (size_t)c * (size_t)p->n;
    for (mpm_lidx k = 0; k < p->n; ++k) dst[k] = src[perm[k]];
  }
  install(p, p->n, id, data, cap);
  return 0;
}

/* Least significant direction first (x), so that after the last pass the order is that of
 * the linear cell index with x fastest; each pass is a counting sort over one direction's
 * cells, which keeps the work O(n + ncells[d]) however large the whole grid is. */
static int sort_passes(mpm_particles *p, const mpm_grid *g, int *cell, mpm_lidx *perm,
                       mpm_lidx *tmp, mpm_lidx *start) {
  for (mpm_lidx i = 0; i < p->n; ++i) perm[i] = i;
  for (int d = 0; d < p->dim; ++d) {
    cell_coords(p, g, d, cell);
    counting_pass(cell, g->ncells[d], p->n, perm, tmp, start);
    mpm_lidx *t = perm;
    perm = tmp, tmp = t;
  }
  return apply_permutation(p, perm);
}

int mpm_particles_sort(mpm_particles *p, const mpm_grid *grid) {
  MPM_CALL(fail_if_deferred(p, "a sort"));
  if (p->n < 2) return 0;
  int maxcells = 0, *cell = NULL, rc = 0;
  mpm_lidx *perm = NULL, *tmp = NULL, *start = NULL;
  for (int d = 0; d < p->dim; ++d) maxcells = MPM_MAX(maxcells, grid->ncells[d]);
  cell = try_alloc((size_t)p->n, sizeof *cell, &rc);
  perm = try_alloc((size_t)p->n, sizeof *perm, &rc);
  tmp = try_alloc((size_t)p->n, sizeof *tmp, &rc);
  start = try_alloc((size_t)maxcells + 1, sizeof *start, &rc);
  if (!rc) rc = sort_passes(p, grid, cell, perm, tmp, start);
  free(cell), free(perm), free(tmp), free(start);
  MPM_CALL(rc);
  return 0;
}

/* ---- validation of data from outside the run ------------------------------------------- */

void mpm_particles_set_range(mpm_particles *p, int f, double lo, double hi, int flags) {
  if (f >= 0 && f < p->nfields) p->range[f] = (mpm_field_range){lo, hi, flags | MPM_FIELD_BOUNDED};
}

static int value_valid(const mpm_field_range *r, double v) {
  if (!isfinite(v)) return 0;
  if (!(r->flags & MPM_FIELD_BOUNDED)) return 1;
  if (v > r->hi || v < r->lo) return 0;
  if ((r->flags & MPM_FIELD_LO_OPEN) && v == r->lo) return 0;
  return !(r->flags & MPM_FIELD_INTEGER) || v == floor(v);
}

static void describe_range(const mpm_field_range *r, char *s, size_t size) {
  const char *kind = r->flags & MPM_FIELD_INTEGER ? "an integer" : "a finite value";
  if (!(r->flags & MPM_FIELD_BOUNDED) || (r->lo == -HUGE_VAL && r->hi == HUGE_VAL))
    snprintf(s, size, "%s", kind);
  else if (r->hi == HUGE_VAL)
    snprintf(s, size, "%s %s %g", kind, r->flags & MPM_FIELD_LO_OPEN ? ">" : ">=", r->lo);
  else
    snprintf(s, size, "%s in %c%g, %g]", kind, r->flags & MPM_FIELD_LO_OPEN ? '(' : '[', r->lo,
             r->hi);
}

mpm_lidx mpm_particles_find_invalid(const mpm_particles *p, mpm_lidx n, const mpm_gidx *id,
                                    const double *data, char *why, size_t size) {
  for (mpm_lidx i = 0; i < n; ++i)
    if (id[i] < 0) { /* ids beyond id_next are legal: the gas's inflow has its own ranges */
      snprintf(why, size, "particle id %" PRId64 " is negative", (int64_t)id[i]);
      return i;
    }
  /* Field by field: each component is one contiguous run. */
  for (int f = 0; f < p->nfields; ++f)
    for (int c = 0; c < p->field[f].ncomp; ++c) {
      const double *v = data + (size_t)(p->offset[f] + c) * (size_t)n;
      for (mpm_lidx i = 0; i < n; ++i)
        if (!value_valid(&p->range[f], v[i])) {
          char want[96];
          describe_range(&p->range[f], want, sizeof want);
          snprintf(why, size, "particle %" PRId64 " has %s[%d] = %.17g, but it must be %s",
                   (int64_t)id[i], p->field[f].name, c, v[i], want);
          return i;
        }
    }
  return -1;
}

static int compare_gidx(const void *a, const void *b) {
  const mpm_gidx x = *(const mpm_gidx *)a, y = *(const mpm_gidx *)b;
  return (x > y) - (x < y);
}

/* The ids this rank checks (those with id % size == rank), sorted, in *mine (*nmine). */
static int gather_by_owner(MPI_Comm comm, int size, const mpm_gidx *id, mpm_lidx n, mpm_gidx **mine,
                           int *nmine) {
  int *cnt = calloc(4 * (size_t)size, sizeof *cnt);
  mpm_gidx *send = malloc(((size_t)n + 1) * sizeof *send);
  int rc = cnt && send ? 0 : MPM_ERR_MEMORY;
  int *displ = cnt ? cnt + size : NULL, *rcnt = cnt ? cnt + 2 * size : NULL,
      *rdispl = cnt ? cnt + 3 * size : NULL;
  for (mpm_lidx i = 0; !rc && i < n; ++i) cnt[id[i] % size]++;
  if (!rc) prefix_sum(cnt, displ, size);
  for (mpm_lidx i = 0; !rc && i < n; ++i) send[displ[id[i] % size]++] = id[i];
  if (!rc) prefix_sum(cnt, displ, size);
  int failed = rc;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, comm);
  if (!failed && MPI_Alltoall(cnt, 1, MPI_INT, rcnt, 1, MPI_INT, comm) != MPI_SUCCESS)
    failed = MPM_ERR_MPI;
  long long total = 0;
  for (int r = 0; !failed && r < size; ++r) total += rcnt[r];
  *mine = failed || total > INT32_MAX ? NULL : malloc(((size_t)total + 1) * sizeof **mine);
  rc = failed ? failed : *mine ? 0 : MPM_ERR_MEMORY;
  if (!failed) MPI_Allreduce(MPI_IN_PLACE, &rc, 1, MPI_INT, MPI_MAX, comm);
  if (!rc) {
    prefix_sum(rcnt, rdispl, size);
    if (MPI_Alltoallv(send, cnt, displ, MPM_MPI_GIDX, *mine, rcnt, rdispl, MPM_MPI_GIDX, comm) !=
        MPI_SUCCESS)
      rc = MPM_ERR_MPI;
  }
  *nmine = (int)total;
  free(cnt), free(send);
  if (rc) free(*mine), *mine = NULL;
  return rc;
}

int mpm_particles_find_duplicate(MPI_Comm comm, const mpm_gidx *id, mpm_lidx n, mpm_gidx *dup) {
  int size;
  MPM_CALL_MPI(MPI_Comm_size(comm, &size));
  mpm_gidx *mine = NULL;
  int nmine = 0;
  *dup = -1;
  MPM_CALL(gather_by_owner(comm, size, id, n, &mine, &nmine));
  qsort(mine, (size_t)nmine, sizeof *mine, compare_gidx);
  mpm_gidx first = INT64_MAX;
  for (int k = 1; k < nmine && first == INT64_MAX; ++k)
    if (mine[k] == mine[k - 1]) first = mine[k];
  free(mine);
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPM_MPI_GIDX, MPI_MIN, comm));
  *dup = first == INT64_MAX ? -1 : first;
  return 0;
}
