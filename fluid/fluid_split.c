/* Split and merge of gas particles for refinement (fluid_split.h), and the choices behind them.
 *
 * Size. A parent's spacing is s = (J V0)^(1/dim), its current volume's edge, not a carried
 * field: the children's cubes of side s / 2 then tile exactly the volume the parent stands for
 * (seeded gas: s = dx / ppc, the seeding lattice), however the gas has been compressed since;
 * the layout has no room for one more field (16 at most, which the gas already reaches with
 * APIC, viscosity and the limiter); and the fluid's regularisation splits by the same size.
 *
 * What is conserved, and how exactly. Split: m / 2^dim and V0 / 2^dim are exact (a power of
 * two), every child has the parent's v and e, so the mass, momentum, kinetic and internal
 * energy, the volume J V0 and hence the density m / (J V0) and the pressure are the parent's
 * bit for bit; the offsets +-delta_d are symmetric, so the centre of mass is the parent's
 * position up to the rounding of x +- delta (one ulp of x). No C dx is added to the children's
 * velocities: it would raise the kinetic energy by m (s/4)^2 |C|^2 / 2 with nothing to pay for
 * it. Merge: m, V0 and J V0 are sums; x and v are mass-weighted, so the centre of mass and the
 * momentum are exact; the kinetic energy lost to averaging, sum 1/2 m_i |v_i - v|^2 >= 0,
 * goes into e, so m e + m |v|^2 / 2 = sum (m_i e_i + m_i |v_i|^2 / 2) exactly in real
 * arithmetic. Split then merge of the same children returns the parent to roundoff.
 *
 * APIC's C. C is the particle's estimate of the velocity gradient, an intensive quantity. A
 * split copies it: the children sample the same affine field, and sum m C (the set's
 * mass-weighted gradient, the affine part's "momentum") is unchanged. A merge mass-weights it,
 * which keeps sum m C and gives back the parent's C after a split. Linear momentum never
 * depends on C (sum_i S_ip (x_i - x_p) = 0). Angular momentum: the orbital part sum x m v is
 * exact under split; a merge loses the group's internal spin sum m_i (x_i - x) x (v_i - v)
 * (its energy is in e, above), which could go into a skew part of C only with the level's
 * inertia D_p = h^2 / 4 (quadratic B-splines), which this level-free operation does not know;
 * and APIC's affine spin m (C D_p)^T : eps scales with the level's D_p, so a particle moving
 * to level l + 1 carries a quarter of it whether it splits or not. Left for the regrid to
 * decide once levels exist.
 *
 * Other fields. divv, D and the limiter psi (and their pending copy under the method of lines)
 * describe the rate of the volume: a merged particle's dV/dt = sum V_i divv_i needs divv
 * volume-weighted, and D with it (tr D = divv), psi too (it scales that rate's stress). Any
 * other field is mass-weighted (per unit mass, like v and C). The output fields are skipped:
 * an edit leaves them undefined and fluid_output_fields refreshes them before any write
 * (after a split each child refreshes to the parent's rho, p, T, s, mach exactly).
 *
 * Ids. A child's id depends only on its parent's cell and id (fluid_split.h), never on the
 * rank layout: the fluid's regularisation and its ties (lowest id) then choose the same
 * particles on 1 rank as on 2. id_next grows by ncells S (2^dim - 1) per split event (S, the
 * most parents a cell splits), linearly in the events, like the regularisation's. A merged
 * particle keeps its members' lowest id (after a split, the parent's own), drawing none.
 *
 * Memory. Merges write in place and drop members: they only shrink the set. A split grows the
 * set once by its (2^dim - 1) k children, whose data it writes straight into the new block (the
 * edit appends them without data): the peak is the old block and the new one, n + (n + (2^dim
 * - 1) k) particles, and the children's ids. A regrid merges before it splits, so the peak is
 * bounded by the set before plus the set after, never the 2^dim-fold peak of splitting
 * everything to the finest level and merging afterwards. (The set's spare block, kept between
 * edits, makes a repeated regrid reuse that memory instead of faulting in new pages.) */
#include "fluid_split.h"

#include "fluid_internal.h"

#include "mpm_cells.h"
#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_particles.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---- shared ------------------------------------------------------------------------------ */

static double pos(const mpm_particles *p, int d, mpm_lidx i) {
  return mpm_particles_comp(p, FLUID_X, d)[i];
}

/* Mark idx[0 .. k) in used (p->n flags, zeroed); fails on an index out of range or named
 * twice. */
static int mark_indices(const mpm_particles *p, const mpm_lidx *idx, mpm_lidx k,
                        unsigned char *used, const char *what) {
  for (mpm_lidx a = 0; a < k; ++a) {
    const mpm_lidx i = idx[a];
    if (i < 0 || i >= p->n || used[i])
      MPM_FAIL(MPM_ERR_INTERNAL, "%s: particle index %d is out of range (n = %d) or named twice",
               what, (int)i, (int)p->n);
    used[i] = 1;
  }
  return 0;
}

/* Are the k indices idx in range and distinct? A rising list (the relevel's scans) in one pass;
 * any other marked in a flag per particle. */
static int check_indices(const mpm_particles *p, const mpm_lidx *idx, mpm_lidx k,
                         const char *what) {
  int rising = 1;
  for (mpm_lidx a = 0; a < k; ++a)
    rising &= idx[a] >= 0 && idx[a] < p->n && (a == 0 || idx[a] > idx[a - 1]);
  if (rising) return 0;
  unsigned char *used;
  MPM_ALLOC(used, p->n);
  const int rc = mark_indices(p, idx, k, used, what);
  free(used);
  return rc;
}

/* Is particle i in a cell of another rank (or outside the domain)? */
static int is_away(const mpm_module *m, mpm_lidx i) {
  double x[MPM_MAX_DIM] = {0};
  for (int d = 0; d < m->grid->dim; ++d) x[d] = pos(m->particles, d, i);
  mpm_grid_wrap(m->grid, x);
  return mpm_grid_owner_of(m->grid, x) != m->grid->rank;
}

/* Key of a candidate: a global lattice index (cell, slot or span), a finer one within it (a
 * merge's slot within its span, else 0), its id and its place in the list. */
typedef struct split_key {
  mpm_gidx cell, sub, id;
  mpm_lidx a;
} split_key;

static int key_cmp(const void *pa, const void *pb) {
  const split_key *a = pa, *b = pb;
  if (a->cell != b->cell) return a->cell < b->cell ? -1 : 1;
  if (a->sub != b->sub) return a->sub < b->sub ? -1 : 1;
  return (a->id > b->id) - (a->id < b->id);
}

/* ---- split ------------------------------------------------------------------------------- */

static mpm_gidx global_cell(const mpm_grid *g, const mpm_particles *p, mpm_lidx i) {
  mpm_gidx c = 0;
  for (int d = g->dim - 1; d >= 0; --d) c = c * g->ncells[d] + mpm_cells_coord(g, d, pos(p, d, i));
  return c;
}

/* The place of each parent's children in the id range: cell[a] and the parent's rank r[a] by id
 * among the listed parents of its cell; *most: the largest count of one cell. Fails if a
 * parent is not on the rank owning its cell (two ranks could then draw the same ids). */
static int split_places(const mpm_module *m, const mpm_lidx *idx, mpm_lidx k, mpm_gidx *cell,
                        mpm_gidx *r, mpm_gidx *most) {
  const mpm_particles *p = m->particles;
  split_key *key;
  MPM_ALLOC(key, k);
  for (mpm_lidx a = 0; a < k; ++a) {
    if (is_away(m, idx[a])) {
      free(key);
      MPM_FAIL(MPM_ERR_INTERNAL, "split: particle %lld is not on the rank owning its cell",
               (long long)p->id[idx[a]]);
    }
    key[a] = (split_key){global_cell(m->grid, p, idx[a]), 0, p->id[idx[a]], a};
  }
  qsort(key, (size_t)k, sizeof *key, key_cmp);
  *most = 0;
  for (mpm_lidx b = 0, run = 0; b < k; ++b) {
    run = b > 0 && key[b].cell == key[b - 1].cell ? run + 1 : 0;
    cell[key[b].a] = key[b].cell, r[key[b].a] = run;
    if (run + 1 > *most) *most = run + 1;
  }
  free(key);
  return 0;
}

/* Is any of the 2^dim children of the box x +- delta inside an obstacle? */
static int child_in_obstacle(const fluid_content *fc, int dim, const double *x,
                             const double *delta) {
  for (int j = 0; fc->obs.count > 0 && j < 1 << dim; ++j) {
    double xc[MPM_MAX_DIM] = {0};
    for (int d = 0; d < dim; ++d) xc[d] = j >> d & 1 ? x[d] + delta[d] : x[d] - delta[d];
    if (fluid_obstacles_inside(&fc->obs, xc)) return 1;
  }
  return 0;
}

/* Half-widths delta of the children's box around parent i (its position into x): s / 4 per
 * axis, at most half the distance to a wall face, then halved (four times at most, then
 * zero: the children coincide) until no child is inside an obstacle. Returns 1 if shortened. */
static int child_offsets(const mpm_module *m, mpm_lidx i, double *x, double *delta) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = p->dim;
  const double V = mpm_particles_comp(p, FLUID_J, 0)[i] * mpm_particles_comp(p, fc->lay.f_V0, 0)[i];
  const double s = dim == 3 ? cbrt(V) : dim == 2 ? sqrt(V) : V;
  int shrunk = 0;
  for (int d = 0; d < dim; ++d) {
    x[d] = pos(p, d, i), delta[d] = 0.25 * s;
    const double room = 0.5 * fmin(x[d] - g->lo[d], g->hi[d] - x[d]);
    if (!g->periodic[d] && room < delta[d]) delta[d] = fmax(room, 0.0), shrunk = 1;
  }
  for (int t = 0; t <= 4 && child_in_obstacle(fc, dim, x, delta); ++t, shrunk = 1)
    for (int d = 0; d < dim; ++d) delta[d] = t < 4 ? 0.5 * delta[d] : 0.0;
  return shrunk;
}

/* Fill the 2^dim - 1 appended children of parent idx[a] (child 0 is the parent, in place) in
 * the set as grown by the edit; n0 particles before it. */
static void split_fill(mpm_module *m, const mpm_lidx *idx, mpm_lidx a, mpm_lidx n0,
                       fluid_split_report *rep) {
  mpm_particles *p = m->particles;
  const fluid_content *fc = m->content;
  const int dim = p->dim, nnew = (1 << dim) - 1;
  const int om = p->offset[fc->lay.f_m], oV = p->offset[fc->lay.f_V0];
  const double scale = 1.0 / (double)(1 << dim); /* exact */
  const mpm_lidx i = idx[a], col = n0 + a * nnew;
  double x[MPM_MAX_DIM] = {0}, delta[MPM_MAX_DIM] = {0};
  rep->shrunk += child_offsets(m, i, x, delta);
  for (int q = 0; q < p->ncomp; ++q) {
    double *v = p->data + (size_t)q * p->n;
    if (q == om || q == oV) v[i] *= scale;
    for (int j = 0; j < nnew; ++j) v[col + j] = v[i];
  }
  for (int j = 0; j <= nnew; ++j)
    for (int d = 0; d < dim; ++d)
      mpm_particles_comp(p, FLUID_X, d)[j ? col + j - 1 : i] =
          j >> d & 1 ? x[d] + delta[d] : x[d] - delta[d];
}

/* The split itself, ids from first[a] = id_next + (cell S + r) (2^dim - 1). The edit grows the
 * set by the children without data, which are then filled in place: no copy of them is held
 * beside the set. */
static int split_apply(mpm_module *m, const mpm_lidx *idx, mpm_lidx k, const mpm_gidx *first,
                       fluid_split_report *rep) {
  mpm_particles *p = m->particles;
  const int nnew = (1 << p->dim) - 1;
  const mpm_lidx n0 = p->n, nadd = k * nnew;
  mpm_gidx *id;
  MPM_ALLOC(id, nadd);
  for (mpm_lidx a = 0; a < k; ++a)
    for (int j = 0; j < nnew; ++j) id[a * nnew + j] = first[a] + j;
  const double *from = mpm_particles_comp(p, FLUID_X, 0);
  const int rc = mpm_particles_edit(p, NULL, nadd, id, NULL);
  free(id);
  MPM_CALL(rc);
  /* (the parents moved and the children are new: looked up again) */
  mpm_hier_levels_keep(m->hier, from, mpm_particles_comp(p, FLUID_X, 0), NULL, n0);
  for (mpm_lidx a = 0; a < k; ++a) split_fill(m, idx, a, n0, rep);
  rep->parents = k, rep->children = nadd;
  for (mpm_lidx a = 0; a < k; ++a) rep->away += is_away(m, idx[a]);
  for (mpm_lidx i = n0; i < p->n; ++i) rep->away += is_away(m, i);
  return 0;
}

/* The local checks and places; *most = -1 on failure (so the reduction tells every rank). */
static int split_prepare(mpm_module *m, const mpm_lidx *idx, mpm_lidx k, mpm_gidx *cell,
                         mpm_gidx *r, mpm_gidx *most) {
  const mpm_particles *p = m->particles;
  const int nnew = (1 << p->dim) - 1;
  if ((int64_t)k * nnew + p->n > INT32_MAX)
    MPM_FAIL(MPM_ERR_MEMORY, "split: %d parents would exceed the local index range", (int)k);
  MPM_CALL(check_indices(p, idx, k, "split"));
  MPM_CALL(split_places(m, idx, k, cell, r, most));
  return 0;
}

int fluid_split(mpm_module *m, const mpm_lidx *idx, mpm_lidx k, fluid_split_report *rep) {
  mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int nnew = (1 << p->dim) - 1;
  memset(rep, 0, sizeof *rep);
  mpm_gidx *cell = calloc((size_t)(k > 0 ? 2 * k : 1), sizeof *cell), *r = cell + k;
  mpm_gidx most = 0;
  if (!cell) mpm_log_all(MPM_LOG_ERROR, MPM_OOM_MESSAGE, 16e-6 * (double)k);
  int rc = cell ? split_prepare(m, idx, k, cell, r, &most) : MPM_ERR_MEMORY;
  int64_t red[2] = {rc != 0, most};
  const int mpi = MPI_Allreduce(MPI_IN_PLACE, red, 2, MPI_INT64_T, MPI_MAX, g->comm);
  mpm_gidx ncells = 1;
  for (int d = 0; d < g->dim; ++d) ncells *= g->ncells[d];
  const mpm_gidx S = red[1];
  const int overflow = S > 0 && S > (INT64_MAX - p->id_next) / (ncells * nnew);
  if (!rc && !mpi && !red[0] && S > 0 && !overflow) {
    for (mpm_lidx a = 0; a < k; ++a) cell[a] = p->id_next + (cell[a] * S + r[a]) * nnew;
    rc = split_apply(m, idx, k, cell, rep);
  }
  free(cell);
  MPM_CALL(rc);
  MPM_CALL_MPI(mpi);
  if (red[0]) MPM_FAIL(MPM_ERR_INTERNAL, "split: failed on another rank");
  if (overflow) MPM_FAIL(MPM_ERR_INTERNAL, "split: the global ids would overflow");
  p->id_next += ncells * S * nnew; /* on every rank */
  return 0;
}

/* ---- merge ------------------------------------------------------------------------------- */

/* How a merge combines a field (see the top of the file). */
typedef enum { MERGE_MASS, MERGE_VOLUME, MERGE_SUM, MERGE_J, MERGE_E, MERGE_NONE } merge_rule;

static merge_rule rule_of(const fluid_layout *lay, const mpm_particles *p, int f) {
  if (p->derived >> f & 1u) return MERGE_NONE;
  if (f == FLUID_J) return MERGE_J;
  if (f == FLUID_E) return MERGE_E;
  if (f == lay->f_m || f == lay->f_V0) return MERGE_SUM;
  const int pending = lay->f_pending >= 0 && f >= lay->f_pending && f < lay->f_divv;
  if (f == lay->f_divv || f == lay->f_D || f == lay->f_psi || pending) return MERGE_VOLUME;
  return MERGE_MASS; /* x, v, C, and any field the gas adds later: per unit mass */
}

/* Coordinate u of the periodic axis d moved by a period to lie within half a period of ref
 * (a group across a periodic face). */
static double unwrap(const mpm_grid *g, int d, double u, double ref) {
  const double L = g->hi[d] - g->lo[d];
  if (!g->periodic[d]) return u;
  return u - ref > 0.5 * L ? u - L : ref - u > 0.5 * L ? u + L : u;
}

void fluid_merge_centre(const mpm_module *m, const mpm_lidx *mem, int c, double *x) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  double M = 0.0;
  for (int d = 0; d < MPM_MAX_DIM; ++d) x[d] = 0.0;
  for (int a = 0; a < c; ++a) {
    M += mass[mem[a]];
    for (int d = 0; d < p->dim; ++d)
      x[d] += mass[mem[a]] * unwrap(m->grid, d, pos(p, d, mem[a]), pos(p, d, mem[0]));
  }
  for (int d = 0; d < p->dim; ++d) x[d] /= M;
  mpm_grid_wrap(m->grid, x);
}

/* The sums of the c members mem[] (rules above) into acc (ncomp). */
static void merge_sums(const mpm_module *m, const mpm_lidx *mem, int c, double *acc) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  const double *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0), *J = mpm_particles_comp(p, FLUID_J, 0);
  memset(acc, 0, sizeof *acc * (size_t)p->ncomp);
  for (int a = 0; a < c; ++a) {
    const mpm_lidx i = mem[a];
    const double mi = mass[i], vi = J[i] * V0[i];
    for (int f = 0; f < p->nfields; ++f) {
      const merge_rule rule = rule_of(&fc->lay, p, f);
      const double w = rule == MERGE_MASS || rule == MERGE_E ? mi : rule == MERGE_VOLUME ? vi : 1.0;
      for (int q = 0; rule != MERGE_NONE && q < p->field[f].ncomp; ++q) {
        const int o = p->offset[f] + q;
        double u = p->data[(size_t)o * p->n + i];
        if (f == FLUID_X) u = unwrap(m->grid, q, u, pos(p, q, mem[0]));
        acc[o] += rule == MERGE_J ? vi : w * u;
      }
    }
  }
}

/* Merge the c >= 2 members mem[] (in id order) into mem[0] (acc: ncomp doubles of scratch). */
static void merge_group(const mpm_module *m, const mpm_lidx *mem, int c, double *acc) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim, oV = p->offset[FLUID_V], oE = p->offset[FLUID_E];
  const int om = p->offset[fc->lay.f_m], oV0 = p->offset[fc->lay.f_V0];
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  merge_sums(m, mem, c, acc);
  const double M = acc[om], vol = acc[p->offset[FLUID_J]];
  for (int f = 0; f < p->nfields; ++f) {
    const merge_rule rule = rule_of(&fc->lay, p, f);
    const double div = rule == MERGE_MASS ? M : rule == MERGE_VOLUME ? vol : 1.0;
    for (int q = 0; q < p->field[f].ncomp; ++q) acc[p->offset[f] + q] /= div;
  }
  acc[p->offset[FLUID_J]] = vol / acc[oV0];
  double heat = 0.0; /* sum 1/2 m_i |v_i - v|^2: the kinetic energy the averaging removes */
  for (int a = 0; a < c; ++a)
    for (int d = 0; d < dim; ++d) {
      const double dv = mpm_particles_comp(p, FLUID_V, d)[mem[a]] - acc[oV + d];
      heat += 0.5 * mass[mem[a]] * dv * dv;
    }
  acc[oE] = (acc[oE] + heat) / M;
  mpm_grid_wrap(m->grid, acc + p->offset[FLUID_X]);
  for (int f = 0; f < p->nfields; ++f)
    for (int q = 0; rule_of(&fc->lay, p, f) != MERGE_NONE && q < p->field[f].ncomp; ++q)
      p->data[(size_t)(p->offset[f] + q) * p->n + mem[0]] = acc[p->offset[f] + q];
}

/* Group g's members into mem, in id order (a group holds a few particles: insertion sort);
 * fails on an index out of range or already in a group (state[i] != 1). */
static int group_members(const mpm_particles *p, const mpm_lidx *member, mpm_lidx from, int c,
                         const unsigned char *state, mpm_lidx *mem) {
  for (int a = 0; a < c; ++a) {
    const mpm_lidx i = member[from + a];
    if (i < 0 || i >= p->n || state[i] != 1)
      MPM_FAIL(MPM_ERR_INTERNAL,
               "merge: particle index %d is out of range (n = %d) or in two "
               "groups",
               (int)i, (int)p->n);
    int b = a;
    for (; b > 0 && p->id[mem[b - 1]] > p->id[i]; --b) mem[b] = mem[b - 1];
    mem[b] = i;
  }
  return 0;
}

/* Merge every group in place; state[i]: 1 untouched, 2 kept in a group, 0 dropped. */
static int merge_all(mpm_module *m, const mpm_lidx *start, const mpm_lidx *member, mpm_lidx ngroups,
                     unsigned char *state, fluid_split_report *rep) {
  mpm_particles *p = m->particles;
  mpm_lidx biggest = 0;
  for (mpm_lidx g = 0; g < ngroups; ++g)
    if (start[g + 1] - start[g] > biggest) biggest = start[g + 1] - start[g];
  mpm_lidx *mem = malloc(sizeof *mem * (size_t)(biggest + 1));
  double *acc = malloc(sizeof *acc * (size_t)p->ncomp);
  int rc = mem && acc ? 0 : MPM_ERR_MEMORY;
  for (mpm_lidx g = 0; !rc && g < ngroups; ++g) {
    const int c = (int)(start[g + 1] - start[g]);
    rc = c < 0 ? MPM_ERR_INTERNAL : group_members(p, member, start[g], c, state, mem);
    if (rc || c == 0) continue;
    if (c > 1) merge_group(m, mem, c, acc), rep->groups++, rep->removed += c - 1;
    state[mem[0]] = 2;
    for (int a = 1; a < c; ++a) state[mem[a]] = 0;
    rep->away += c > 1 && is_away(m, mem[0]);
  }
  free(mem), free(acc);
  if (rc == MPM_ERR_MEMORY) MPM_FAIL_OOM(sizeof *acc * (size_t)p->ncomp);
  MPM_CALL(rc);
  return 0;
}

int fluid_merge(mpm_module *m, const mpm_lidx *start, const mpm_lidx *member, mpm_lidx ngroups,
                fluid_split_report *rep) {
  mpm_particles *p = m->particles;
  memset(rep, 0, sizeof *rep);
  unsigned char *state;
  MPM_ALLOC(state, p->n);
  memset(state, 1, (size_t)p->n);
  int rc = merge_all(m, start, member, ngroups, state, rep);
  const mpm_lidx n0 = p->n;
  for (mpm_lidx i = 0; !rc && i < n0; ++i) state[i] = state[i] != 0;
  const double *from = mpm_particles_comp(p, FLUID_X, 0);
  if (!rc && rep->removed > 0 && (rc = mpm_particles_edit(p, state, 0, NULL, NULL)) == 0)
    mpm_hier_levels_keep(m->hier, from, mpm_particles_comp(p, FLUID_X, 0), state,
                         n0); /* (a merged one moved: looked up again) */
  free(state);
  MPM_CALL(rc);
  return 0;
}

/* ---- groups by parent slot --------------------------------------------------------------- */

/* The cell of particle i on the lattice of spacing H from the domain's lower corner (clamped
 * to the domain's cells of that lattice). */
static mpm_gidx slot_of(const mpm_grid *g, const mpm_particles *p, mpm_lidx i, double H) {
  mpm_gidx s = 0;
  for (int d = g->dim - 1; d >= 0; --d) {
    const mpm_gidx ns = (mpm_gidx)ceil((g->hi[d] - g->lo[d]) / H);
    mpm_gidx c = (mpm_gidx)floor((pos(p, d, i) - g->lo[d]) / H);
    c = c < 0 ? 0 : c >= ns ? ns - 1 : c;
    s = s * ns + c;
  }
  return s;
}

/* The CSR groups of the sorted keys: each run of one slot of c >= 2 splits into
 * ceil(c / size) groups, the first c mod that count one larger. */
static void groups_of_runs(const split_key *key, mpm_lidx k, int size, int full,
                           const mpm_lidx *idx, mpm_lidx *start, mpm_lidx *member,
                           mpm_lidx *ngroups) {
  mpm_lidx ng = 0, nm = 0;
  start[0] = 0;
  for (mpm_lidx b = 0; b < k;) {
    mpm_lidx e = b + 1;
    while (e < k && key[e].cell == key[b].cell) ++e;
    const mpm_lidx c = e - b, parts = full ? c / size : (c + size - 1) / size;
    for (mpm_lidx t = 0, at = b; c >= 2 && t < parts; ++t) {
      const mpm_lidx len = full ? size : c / parts + (t < c % parts);
      for (mpm_lidx u = 0; u < len; ++u) member[nm++] = idx[key[at + u].a];
      at += len, start[++ng] = nm;
    }
    b = e;
  }
  *ngroups = ng;
}

int fluid_merge_groups(const mpm_module *m, const mpm_lidx *idx, mpm_lidx k, double H, double span,
                       int full, mpm_lidx **start, mpm_lidx **member, mpm_lidx *ngroups) {
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  *start = NULL, *member = NULL, *ngroups = 0;
  double slots = 1.0;
  for (int d = 0; d < g->dim; ++d) slots *= ceil((g->hi[d] - g->lo[d]) / H);
  if (!(H > 0.0) || !(slots < 0x1p62) || !(span == 0.0 || span >= H))
    MPM_FAIL(MPM_ERR_INTERNAL, "merge: slot spacing %g or span %g is not positive or too small", H,
             span);
  MPM_CALL(check_indices(p, idx, k, "merge"));
  split_key *key;
  MPM_ALLOC(key, k);
  for (mpm_lidx a = 0; a < k; ++a) {
    const mpm_gidx slot = slot_of(g, p, idx[a], H);
    key[a] = (split_key){span > 0.0 ? slot_of(g, p, idx[a], span) : slot, span > 0.0 ? slot : 0,
                         p->id[idx[a]], a};
  }
  qsort(key, (size_t)k, sizeof *key, key_cmp);
  *start = malloc(sizeof **start * (size_t)(k / 2 + 2));
  *member = malloc(sizeof **member * (size_t)(k > 0 ? k : 1));
  if (!*start || !*member) {
    free(key), free(*start), free(*member);
    *start = NULL, *member = NULL;
    MPM_FAIL_OOM(sizeof **member * (size_t)k);
  }
  groups_of_runs(key, k, 1 << g->dim, full, idx, *start, *member, ngroups);
  free(key);
  return 0;
}
