/* Conservative particle regularisation of the gas: every fluid.regularise_every accepted
 * steps, cells holding more than regularise_max particles merge pairs and cells holding fewer
 * than regularise_min (but at least one) split particles, until every non-empty cell holds
 * between the two. Empty cells stay empty: there is no state to seed them from.
 *
 * Merge: in an overcrowded cell the two closest particles (ties: the first pair in id order)
 * become one, which keeps the lower id:
 *   m = m_a + m_b, m v = m_a v_a + m_b v_b, x = the centre of mass, V0 = V0_a + V0_b,
 *   J = (J_a V0_a + J_b V0_b) / V0 (so the volume J V0 is the sum), and
 *   m e = m_a e_a + m_b e_b + (m_a m_b / 2 m) |v_a - v_b|^2:
 * the kinetic energy the averaging of the velocities removes (never negative) becomes heat,
 * so m e + m |v|^2 / 2 is the sum of the two. Every other field (the APIC matrix C, the lagged
 * strain rate divv and D, the pending rate of the ERK pairs) is mass-weighted. The output-only
 * fields (rho, p, mach, T, s) are refreshed before every write, so their merged values do not
 * matter.
 * Split: in a depleted cell the heaviest particle (ties: the lowest id) becomes two halves
 * with half its mass and V0 and its v, e, J, C, divv and D, displaced by -delta and +delta
 * along one axis, so the centre of mass stays. The axis is the one along which the cell's
 * particles leave the widest gap (counted cyclically across the cell, ties: the lowest axis,
 * so a lone particle splits along x); delta is a quarter of the parent's size (J V0)^(1/dim),
 * at most half its distance to the cell faces along the axis, so both halves stay in the
 * cell and no migration is needed. The first half keeps the parent's id.
 * Mass, momentum and total energy are thus unchanged up to roundoff in every event.
 *
 * Refill (fluid.refill, before the merges and splits; at each regularisation, or every
 * fluid.refill_every steps on its own, the merges and splits keeping their period): a cell that
 * strong expansion has emptied is refilled from its neighbours, so that the gas stays a continuum
 * into near vacuum (a double rarefaction, the wake of a bluff body) instead of tearing into clouds
 * with empty gaps, where no later split can put gas back. A target is a cell inside the domain that
 * holds no particle of any phase (the cell occupancy every phase shares on the grid, mpm_cells.h:
 * the gas never refills another material's cells), whose centre is outside the obstacles, and
 * that has a face neighbour holding gas. Its donor is that neighbour with the most gas
 * particles (ties: the lowest global cell index, then the first direction -x, +x, -y, ...),
 * whose heaviest particle (ties: the lowest id) gives half of itself: the child has half the
 * parent's m and V0 and all its other fields (v, e, J, C, ...) and sits at the centre of the
 * target cell. m, m v, m (e + |v|^2 / 2) and the volume J V0 are split exactly (a halving is
 * exact in floating point), so mass, momentum, total energy and the gas's volume are
 * unchanged to roundoff, and both halves keep the parent's density and pressure. (Giving the
 * child the whole cell's volume instead, a free expansion at constant e, was measured worse on
 * the double rarefaction: L1 density 0.030 against 0.027 at 800 cells.) What moves is
 * position: a refill spreads a parent over two cells, a diffusion of one cell per event
 * confined to cells the gas has emptied.
 * Light merge (fluid.merge_light = mu > 0, at every refill and every regularisation, after the
 * splits and merges by count; unset, after a refill of holes alone that made children, at
 * mu = 0.125, and not otherwise): in each cell, while the lightest particle is lighter than mu
 * times the heaviest, the two merge (the merge above, but the heavier keeps its id) and the
 * result splits into two equal halves (the split above; the new half takes the light
 * particle's id, so the cell keeps its ids and no new id is drawn), so that no event leaves
 * a particle lighter than mu times its cell's heaviest and the cell keeps its count. (Merging
 * the light particle away instead thinned the gas where refills had been feeding it: at the
 * main job's outflow corner, at 3 mm, 23 particles were left where 103 had been, most of them
 * expanded 30-45 fold, and the run blew up there at 0.66 ms.) Refill
 * children are halves, and a chain of refills through a wake halves them again and again (the
 * main job held particles of 1/1000 of a seeded mass). Such a particle beside heavy ones takes
 * the acceleration of the nodes its own mass dominates, where a heavy neighbour's stress acts
 * through the far tail of its shape function: measured on the main job at 2 mm, particles of
 * 1/1000 to 1/30 of a seeded mass moved at up to 4 400 m/s (the flow's limit speed is
 * 1 150 m/s), with sound speeds up to 2 600 m/s, and set the step, which fell to a tenth of the
 * free stream's. A light particle in an empty cell (a refill child) has no one to merge into
 * and stays, so the merge leaves no cell empty.
 * Holes (fluid.refill_holes; auto, the default, takes it for a gas alone with the hybrid
 * pressure; on every step that has no refill above): the same refill, but a target must also
 * have an empty face neighbour along every axis, so that only gaps at least two cells across in
 * every direction are filled, and no obstacle may reach the 3^dim cells around it (refills at
 * the foot of the wedge's ramp, under the ghost wall treatment, blew the wedge up). The gas of an
 * ordinary expansion is never touched: Sod's expanded gas, 1.7 particles per cell along x (its
 * particle columns 1.17 cells apart), leaves single empty cells, or single empty columns in the
 * strip, that have gas on both sides along x, where refilling them raised Sod's L1 at 400 cells
 * from 3.17e-3 to 1.14e-2 (docs/gas.md). A gas expanding into near vacuum opens gaps of two cells
 * and more (a double rarefaction's centre, at 2.2 % of the initial density, spreads its seeded
 * columns about 22 cells apart) and tears without them refilled: with the default gas 223
 * empty nodes at 800 cells; with the holes refilled none, and the particle densities converge
 * (docs/gas.md, "Expansion"). A face outside the domain counts as not empty (a wall bounds the
 * gas), so a hole against a wall is filled once it is two cells deep. Beside obstacles and
 * solids the particles' pressure refilled this way blew up the forward step (cases/
 * forward_step.ini at 0.025: its holes above the step behind the corner), so auto leaves them.
 * The holes' children are halves too, and at a near vacuum's centre the holes reopen and are
 * refilled again and again: without light merges the double rarefaction at 800 cells (default
 * settings) took 2,224 steps, its lightest particles setting the step, and 1,151 with them
 * (fluid.merge_light unset: 0.125 after each refill of holes that made children; 0 turns them
 * off), its nodal L1 0.0190 against 0.0188. A step whose refill of holes makes no child
 * merges nothing, so a gas that opens no hole (Sod, Toro 3, the acoustic pulse) is untouched.
 * The gas advances by at most one cell per event into a region no gas has reached, far less
 * than its escape speed 2c / (gamma - 1) would carry it. The donor rank decides alone from the
 * occupancy (its ghost cells reach two cells beyond its own, all a choice needs), the child
 * gets the id id_next + (global index of the target), and migration takes it to its owner:
 * the result does not depend on the rank layout.
 *
 * On a refinement hierarchy (mpm_hier.h) every event runs level by level: a finer level's cells
 * are its spans (mpm_cells.h), a particle belongs to the cells of its position's level, a refill's
 * target and donor are cells wholly on one level (a level-0 cell that a finer region cuts is
 * neither), and the ids of children count the cells of all levels (level_offset). A finer level's
 * occupancy is summed over the ranks, so every rank finds its targets and donors alike, and the
 * rank holding a donor's particles (a span lies in one level-0 cell) splits it.
 *
 * Decomposition independence: the post-step hook runs after migration, so each cell's
 * particles are all on one rank. A cell's particles are processed in id order, and the j-th
 * particle a split creates in global cell c gets the id id_next + c (min - 1) + j (at most
 * min - 1 splits per cell); every rank then advances id_next by ncells (min - 1) when any
 * rank split. The result, new ids included, does not depend on the rank layout. Nothing is
 * kept between events: the sim's step count (restored by a restart) decides when to act. */
#include "fluid_internal.h"

#include "mpm_cells.h"
#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_log.h"
#include "mpm_particles.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The particles of one cell, as rows of ncomp values, gathered in id order (a light merge's
 * new half goes to the end). */
typedef struct reg_cell {
  int k, cap;
  double *row;
  mpm_gidx *id;
  mpm_lidx *slot; /* local indices of the cell's original particles, by id */
} reg_cell;

/* The cells of one level that this rank decides: [c0, c0 + nc) along each axis of the global
 * lattice lo + c dx (ncells along each axis, periodic where the grid is). Without a hierarchy, the
 * cells level 0's grid owns; on a hierarchy, level 0's owned cells or a finer level's whole box
 * (mpm_cells.h: its cells are its spans), and only the particles whose position is on the level
 * (lev[i], mpm_hier_levels) belong to its cells. g holds the occupancy (cell_n). */
typedef struct reg_box {
  const mpm_grid *g;
  const mpm_hier *h; /* NULL: no hierarchy */
  const unsigned char *lev;
  int level;
  int dim, c0[MPM_MAX_DIM], nc[MPM_MAX_DIM], ncells[MPM_MAX_DIM], periodic[MPM_MAX_DIM];
  double lo[MPM_MAX_DIM], dx;
  double light; /* the light merges' share of a cell's heaviest at this event (0: none) */
} reg_box;

/* Level `level`'s cells (level 0 without a hierarchy); lev: the particles' levels (h only). */
static void box_of(reg_box *b, const mpm_module *m, int level, const unsigned char *lev) {
  const mpm_grid *g = m->grid;
  b->h = m->hier, b->lev = m->hier ? lev : NULL, b->level = level, b->dim = g->dim;
  b->g = level ? m->hier->level[level].grid : g;
  b->dx = ldexp(g->dx, -level), b->light = 0.0;
  for (int d = 0; d < g->dim; ++d) {
    b->ncells[d] = g->ncells[d] << level, b->lo[d] = g->lo[d], b->periodic[d] = g->periodic[d];
    if (level) { /* the box's spans, as cells (mpm_cells_level_index) */
      b->c0[d] = b->g->box_lo[d] - (1 << (level - 1)), b->nc[d] = b->g->box_n[d];
      continue;
    }
    b->c0[d] = g->cell_split[d][g->coord[d]];
    b->nc[d] = g->cell_split[d][g->coord[d] + 1] - b->c0[d];
  }
}

/* The cells of all levels together: cells of level l get global indices from
 * level_offset(m, l) on, and level_offset(m, nlevels) is the size of that numbering. */
static mpm_gidx level_offset(const mpm_module *m, int level) {
  mpm_gidx off = 0;
  for (int l = 0; l < level; ++l) {
    mpm_gidx cells = 1;
    for (int d = 0; d < m->grid->dim; ++d) cells *= (mpm_gidx)m->grid->ncells[d] << l;
    off += cells;
  }
  return off;
}

/* The levels the events visit: 1, or the hierarchy's. */
static int levels_of(const mpm_module *m) {
  return m->hier ? m->hier->nlevels : 1;
}

/* Global cell coordinate of x along d, as mpm_grid_owner_of computes it on level 0. */
static int cell_coord(const reg_box *b, int d, double x) {
  const int c = mpm_shape_floor((x - b->lo[d]) / b->dx);
  return c < 0 ? 0 : c >= b->ncells[d] ? b->ncells[d] - 1 : c;
}

/* The occupancy's index of cell c (unwrapped global coordinates; level 0: inside the rank's box
 * with its ghosts), or -1 when a finer level's box does not hold it. */
static mpm_lidx store_index(const reg_box *b, const int *c) {
  return b->level ? mpm_cells_level_index(b->h, b->level, c) : mpm_grid_local_index(b->g, c);
}

/* Is every point of cell c (unwrapped) on the box's level? Always without a hierarchy. A finer
 * level's cell (a span) is wholly on one level, level 0's may straddle a finer region: its 2^dim
 * quarter points decide. */
static int is_leaf(const reg_box *b, const int *c) {
  if (!b->h) return 1;
  for (int q = 0; q < 1 << b->dim; ++q) {
    double x[MPM_MAX_DIM] = {0};
    for (int d = 0; d < b->dim; ++d) x[d] = b->lo[d] + (c[d] + (q >> d & 1 ? 0.75 : 0.25)) * b->dx;
    mpm_grid_wrap(b->h->level[0].grid, x);
    if (mpm_hier_level_of(b->h, x) != b->level) return 0;
    if (b->level) return 1; /* a span: one point tells */
  }
  return 1;
}

/* Local cell index of the particle at x (clamped into the box: after migration it is inside). */
static mpm_lidx local_cell(const reg_box *b, const double *x) {
  mpm_lidx l = 0;
  for (int d = b->dim - 1; d >= 0; --d) {
    int c = cell_coord(b, d, x[d]) - b->c0[d];
    c = c < 0 ? 0 : c >= b->nc[d] ? b->nc[d] - 1 : c;
    l = l * b->nc[d] + c;
  }
  return l;
}

/* The local cells of particles [from, p->n) into cell[from ..]; -1 for a particle on another
 * level than the box's. */
static void cells_from(const reg_box *b, const mpm_particles *p, mpm_lidx from, mpm_lidx *cell) {
  const double *x[MPM_MAX_DIM] = {NULL}; /* (read once: cell may alias the block) */
  for (int d = 0; d < b->dim; ++d) x[d] = mpm_particles_comp(p, 0, d);
  for (mpm_lidx i = from; i < p->n; ++i) {
    double xi[MPM_MAX_DIM] = {0};
    for (int d = 0; d < b->dim; ++d) xi[d] = x[d][i];
    cell[i] = b->lev && b->lev[i] != b->level ? -1 : local_cell(b, xi);
  }
}

static mpm_gidx global_cell(const reg_box *b, const double *x) {
  mpm_gidx c = 0;
  for (int d = b->dim - 1; d >= 0; --d) c = c * b->ncells[d] + cell_coord(b, d, x[d]);
  return c;
}

/* The local cell of every particle (local_cell), or NULL on failure. */
static mpm_lidx *cells_of(const reg_box *b, const mpm_particles *p) {
  mpm_lidx *cell = malloc(sizeof *cell * (size_t)(p->n ? p->n : 1));
  if (cell) cells_from(b, p, 0, cell);
  return cell;
}

/* The local cells of the particles (cells_of), found once per event: the refill's donors and
 * the merges that follow read the same map, which the refill extends by its children. cell is
 * NULL until some pass needs it; valid for particles [0, n) as they are. */
typedef struct reg_cellmap {
  mpm_lidx *cell;
  mpm_lidx n;
} reg_cellmap;

/* The map of the set as it is now (computed if absent or stale), or NULL on failure. */
static const mpm_lidx *cellmap_get(reg_cellmap *map, const reg_box *b, const mpm_particles *p) {
  if (map->cell && map->n == p->n) return map->cell;
  free(map->cell);
  map->cell = cells_of(b, p);
  map->n = map->cell ? p->n : 0;
  return map->cell;
}

/* Particle indices grouped by local cell (cell[i]: particle i's, from cells_of; -1: none):
 * cell l holds perm[start[l] .. start[l + 1]), in index order. With a mask, only the cells l
 * with mask[l] != 0 hold their particles. */
static int group_by_cell(const reg_box *b, const mpm_particles *p, const mpm_lidx *cell,
                         const unsigned char *mask, mpm_lidx **start, mpm_lidx **perm,
                         mpm_lidx *ncell) {
  mpm_lidx nc = 1;
  for (int d = 0; d < b->dim; ++d) nc *= b->nc[d];
  *ncell = nc;
  *start = calloc((size_t)nc + 2, sizeof **start);
  *perm = malloc(sizeof **perm * (size_t)(p->n ? p->n : 1));
  if (!*start || !*perm)
    MPM_FAIL(MPM_ERR_MEMORY, "regularise: cannot group %d particles by cell", (int)p->n);
  for (mpm_lidx i = 0; i < p->n; ++i)
    if (cell[i] >= 0 && (!mask || mask[cell[i]])) (*start)[cell[i] + 2]++;
  for (mpm_lidx l = 0; l < nc; ++l) (*start)[l + 2] += (*start)[l + 1];
  for (mpm_lidx i = 0; i < p->n; ++i)
    if (cell[i] >= 0 && (!mask || mask[cell[i]])) (*perm)[(*start)[cell[i] + 1]++] = i;
  return 0;
}

/* ---- one cell ---------------------------------------------------------------------------- */

static int cell_reserve(reg_cell *c, int k, int ncomp) {
  if (k <= c->cap) return 0;
  const int cap = 2 * k;
  double *row = realloc(c->row, sizeof *row * (size_t)cap * (size_t)ncomp);
  if (row) c->row = row;
  mpm_gidx *id = realloc(c->id, sizeof *id * (size_t)cap);
  if (id) c->id = id;
  mpm_lidx *slot = realloc(c->slot, sizeof *slot * (size_t)cap);
  if (slot) c->slot = slot;
  if (!row || !id || !slot) MPM_FAIL(MPM_ERR_MEMORY, "regularise: a cell of %d particles", k);
  c->cap = cap;
  return 0;
}

/* Gather the k particles perm[0 .. k) into rows, in id order. */
static int cell_gather(reg_cell *c, const mpm_particles *p, const mpm_lidx *perm, int k) {
  MPM_CALL(cell_reserve(c, k, p->ncomp));
  for (int a = 0; a < k; ++a) { /* insertion sort by id: a cell holds a few particles */
    int b = a;
    for (; b > 0 && p->id[c->slot[b - 1]] > p->id[perm[a]]; --b) c->slot[b] = c->slot[b - 1];
    c->slot[b] = perm[a];
  }
  for (int a = 0; a < k; ++a) {
    c->id[a] = p->id[c->slot[a]];
    for (int q = 0; q < p->ncomp; ++q)
      c->row[(size_t)a * p->ncomp + q] = p->data[(size_t)q * p->n + c->slot[a]];
  }
  c->k = k;
  return 0;
}

/* Row b merged into row a (see the header for the rules). */
static void merge_rows(const fluid_layout *lay, const mpm_particles *p, double *a,
                       const double *b) {
  const int om = p->offset[lay->f_m], oV = p->offset[lay->f_V0], ov = p->offset[FLUID_V];
  const int oJ = p->offset[FLUID_J], oe = p->offset[FLUID_E];
  const double ma = a[om], mb = b[om], m = ma + mb, V0 = a[oV] + b[oV];
  double dv2 = 0.0;
  for (int d = 0; d < p->dim; ++d) dv2 += (a[ov + d] - b[ov + d]) * (a[ov + d] - b[ov + d]);
  const double J = (a[oJ] * a[oV] + b[oJ] * b[oV]) / V0;
  const double e = (ma * a[oe] + mb * b[oe] + 0.5 * ma * mb / m * dv2) / m;
  for (int q = 0; q < p->ncomp; ++q) a[q] = (ma * a[q] + mb * b[q]) / m;
  a[om] = m, a[oV] = V0, a[oJ] = J, a[oe] = e;
}

static double dist2(const double *a, const double *b, int dim) {
  double s = 0.0;
  for (int d = 0; d < dim; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
  return s;
}

/* Row i leaves the cell; the rows after it move up. */
static void remove_row(reg_cell *c, int i, int nc) {
  memmove(c->row + (size_t)i * nc, c->row + (size_t)(i + 1) * nc,
          sizeof *c->row * (size_t)(c->k - i - 1) * nc);
  memmove(c->id + i, c->id + i + 1, sizeof *c->id * (size_t)(c->k - i - 1));
  c->k--;
}

/* Merge the closest pair of rows; the later row (higher id) goes. */
static void merge_closest(reg_cell *c, const fluid_layout *lay, const mpm_particles *p) {
  const int nc = p->ncomp;
  int ia = 0, ib = 1;
  double best = HUGE_VAL;
  for (int a = 0; a < c->k; ++a)
    for (int b = a + 1; b < c->k; ++b) {
      const double s = dist2(c->row + (size_t)a * nc, c->row + (size_t)b * nc, p->dim);
      if (s < best) best = s, ia = a, ib = b;
    }
  merge_rows(lay, p, c->row + (size_t)ia * nc, c->row + (size_t)ib * nc);
  remove_row(c, ib, nc);
}

/* The axis along which the rows leave the widest gap, cyclically across the cell. */
static int widest_gap_axis(const reg_cell *c, const reg_box *b, int nc) {
  int axis = 0;
  double widest = -1.0;
  for (int d = 0; d < b->dim; ++d) {
    double gap = 0.0;
    for (int a = 0; a < c->k; ++a) { /* the gap above row a: to the next coordinate up */
      const double u = c->row[(size_t)a * nc + d];
      double next = HUGE_VAL;
      for (int q = 0; q < c->k; ++q) {
        double w = c->row[(size_t)q * nc + d];
        if (!(w > u) && q != a) w += b->dx; /* at or below: its image in the next cell */
        if (q != a && w < next) next = w;
      }
      gap = fmax(gap, c->k > 1 ? next - u : b->dx);
    }
    if (gap > widest) widest = gap, axis = d;
  }
  return axis;
}

/* Split the heaviest row into two halves; the new half gets id `id`. The halves move apart
 * along the axis of the widest gap, or the next axis where neither would land inside an
 * obstacle (a cell the surface cuts), or stay together. */
static int split_heaviest(reg_cell *c, const fluid_layout *lay, const mpm_particles *p,
                          const reg_box *b, const fluid_obstacles *obs, mpm_gidx id) {
  const int nc = p->ncomp, om = p->offset[lay->f_m];
  MPM_CALL(cell_reserve(c, c->k + 1, nc));
  int h = 0;
  for (int a = 1; a < c->k; ++a)
    if (c->row[(size_t)a * nc + om] > c->row[(size_t)h * nc + om]) h = a;
  const int widest = widest_gap_axis(c, b, nc);
  double *par = c->row + (size_t)h * nc, *kid = c->row + (size_t)c->k * nc;
  const double size = pow(par[p->offset[FLUID_J]] * par[p->offset[lay->f_V0]], 1.0 / p->dim);
  par[om] *= 0.5, par[p->offset[lay->f_V0]] *= 0.5;
  memcpy(kid, par, sizeof *kid * (size_t)nc);
  for (int k = 0; k < p->dim; ++k) {
    const int axis = (widest + k) % p->dim;
    const double x = par[axis];
    const double face = b->lo[axis] + cell_coord(b, axis, x) * b->dx;
    const double room = fmin(x - face, face + b->dx - x);
    const double delta = fmin(0.25 * size, 0.5 * room);
    double xp[MPM_MAX_DIM] = {0}, xk[MPM_MAX_DIM] = {0};
    for (int d = 0; d < p->dim; ++d) xp[d] = xk[d] = par[d];
    xp[axis] = x - delta, xk[axis] = x + delta;
    if (fluid_obstacles_inside(obs, xp) || fluid_obstacles_inside(obs, xk)) continue;
    par[axis] = xp[axis], kid[axis] = xk[axis];
    break;
  }
  c->id[c->k++] = id;
  return 0;
}

/* ---- the event --------------------------------------------------------------------------- */

/* Changes made on this rank: rows written back, particles dropped or appended. */
typedef struct reg_edit {
  unsigned char *keep;
  mpm_lidx nadd, cap;
  double *add; /* rows (row-major) of the appended particles */
  mpm_gidx *add_id;
  long splits, merges; /* by count and light merges (merges), by count (splits) */
  long light;          /* light merges (each split again in place) */
  mpm_lidx drops;      /* particles dropped (keep[i] = 0) */
} reg_edit;

static int edit_append(reg_edit *e, const double *row, mpm_gidx id, int nc) {
  if (e->nadd == e->cap) {
    const mpm_lidx cap = 2 * e->cap + 16;
    double *add = realloc(e->add, sizeof *add * (size_t)cap * (size_t)nc);
    if (add) e->add = add;
    mpm_gidx *ids = realloc(e->add_id, sizeof *ids * (size_t)cap);
    if (ids) e->add_id = ids;
    if (!add || !ids) MPM_FAIL(MPM_ERR_MEMORY, "regularise: cannot append %d particles", cap);
    e->cap = cap;
  }
  memcpy(e->add + (size_t)e->nadd * nc, row, sizeof *row * (size_t)nc);
  e->add_id[e->nadd++] = id;
  return 0;
}

/* Write the cell's rows back: into its original slots first, the rest appended; slots
 * left over are dropped. */
static int cell_scatter(const reg_cell *c, int k0, mpm_particles *p, reg_edit *e) {
  const int nc = p->ncomp;
  for (int a = 0; a < c->k && a < k0; ++a) {
    p->id[c->slot[a]] = c->id[a];
    for (int q = 0; q < nc; ++q)
      p->data[(size_t)q * p->n + c->slot[a]] = c->row[(size_t)a * nc + q];
  }
  for (int a = c->k; a < k0; ++a) e->keep[c->slot[a]] = 0, e->drops++;
  for (int a = k0; a < c->k; ++a) MPM_CALL(edit_append(e, c->row + (size_t)a * nc, c->id[a], nc));
  return 0;
}

/* Does the cell perm[0 .. k) hold a particle lighter than b->light of its heaviest? */
static int has_light(const fluid_content *fc, const reg_box *b, const mpm_particles *p,
                     const mpm_lidx *perm, int k) {
  if (!(b->light > 0.0) || k < 2) return 0;
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  double lo = HUGE_VAL, hi = 0.0;
  for (int a = 0; a < k; ++a) lo = fmin(lo, mass[perm[a]]), hi = fmax(hi, mass[perm[a]]);
  return lo < b->light * hi;
}

/* While the lightest row is lighter than b->light of the heaviest (ties: the first row;
 * the rows start in id order), merge the two and split the result into two equal halves
 * (split_heaviest; the new half takes the light row's id). Each pass leaves one light row fewer:
 * both halves weigh more than half the old heaviest, so at least merge_light (at most 0.5, the
 * key's bound) of any row. Counted as merges only: the split draws no new id. */
static int merge_light(reg_cell *c, const fluid_content *fc, const mpm_particles *p,
                       const reg_box *b, reg_edit *e) {
  const int nc = p->ncomp, om = p->offset[fc->lay.f_m];
  while (c->k > 1) {
    int h = 0, l = 0;
    for (int a = 1; a < c->k; ++a) {
      const double m = c->row[(size_t)a * nc + om];
      if (m > c->row[(size_t)h * nc + om]) h = a;
      if (m < c->row[(size_t)l * nc + om]) l = a;
    }
    if (!(c->row[(size_t)l * nc + om] < b->light * c->row[(size_t)h * nc + om])) return 0;
    const mpm_gidx id = c->id[l];
    merge_rows(&fc->lay, p, c->row + (size_t)h * nc, c->row + (size_t)l * nc);
    remove_row(c, l, nc);
    MPM_CALL(split_heaviest(c, &fc->lay, p, b, &fc->obs, id));
    e->merges++, e->light++;
  }
  return 0;
}

/* Bring one cell's count into [min, max] (with counts), then merge its light particles (with
 * merge_light: last, so that no event leaves a light particle beside a heavier one, a merge by
 * count included). */
static int regularise_cell(const fluid_content *fc, mpm_particles *p, const reg_box *b,
                           const mpm_lidx *perm, int k, mpm_gidx id_base, int counts, reg_cell *c,
                           reg_edit *e) {
  const int by_count = counts && (k < fc->reg_min || k > fc->reg_max);
  if (k == 0 || (!by_count && !has_light(fc, b, p, perm, k))) return 0;
  MPM_CALL(cell_gather(c, p, perm, k));
  const mpm_gidx first = id_base + global_cell(b, c->row) * (mpm_gidx)(fc->reg_min - 1);
  for (int j = 0; by_count && c->k < fc->reg_min; ++j, e->splits++)
    MPM_CALL(split_heaviest(c, &fc->lay, p, b, &fc->obs, first + j));
  for (; by_count && c->k > fc->reg_max; e->merges++) merge_closest(c, &fc->lay, p);
  if (b->light > 0.0) MPM_CALL(merge_light(c, fc, p, b, e));
  return cell_scatter(c, k, p, e);
}

/* Apply the edit: drop and append (component-major add data). */
static int edit_apply(mpm_particles *p, const reg_edit *e) {
  const int nc = p->ncomp;
  double *data;
  MPM_ALLOC(data, (size_t)nc * e->nadd);
  for (mpm_lidx a = 0; a < e->nadd; ++a)
    for (int q = 0; q < nc; ++q) data[(size_t)q * e->nadd + a] = e->add[(size_t)a * nc + q];
  const int rc = mpm_particles_edit(p, e->keep, e->nadd, e->add_id, data);
  free(data);
  return rc;
}

/* Mark the owned cells holding a particle lighter than b->light of the cell's heaviest
 * (two passes over the particles: on a refill-only event only these cells are grouped). Their
 * number goes to *nlight. */
static int light_cells(const fluid_content *fc, const reg_box *b, const mpm_particles *p,
                       const mpm_lidx *cell, unsigned char *mask, mpm_lidx ncell,
                       mpm_lidx *nlight) {
  const double *mass = mpm_particles_comp(p, fc->lay.f_m, 0);
  double *heaviest;
  MPM_ALLOC(heaviest, ncell);
  memset(heaviest, 0, sizeof *heaviest * (size_t)ncell);
  for (mpm_lidx i = 0; i < p->n; ++i) /* (not fmax, a call: the same for any mass, NaN too) */
    if (cell[i] >= 0 && mass[i] > heaviest[cell[i]]) heaviest[cell[i]] = mass[i];
  memset(mask, 0, (size_t)ncell);
  *nlight = 0;
  for (mpm_lidx i = 0; i < p->n; ++i)
    if (cell[i] >= 0 && mass[i] < b->light * heaviest[cell[i]] && !mask[cell[i]])
      mask[cell[i]] = 1, ++*nlight;
  free(heaviest);
  return 0;
}

/* The local part of one event: with counts, every cell's light merges and count rules; without,
 * the light merges of the cells that need one. */
static int regularise_local(mpm_module *m, const reg_box *bx, reg_edit *e, mpm_gidx id_base,
                            int counts, reg_cellmap *map) {
  const fluid_content *fc = m->content;
  mpm_particles *p = m->particles;
  const reg_box b = *bx;
  mpm_lidx *start = NULL, *perm = NULL, ncell = 1, nlight = 0;
  for (int d = 0; d < b.dim; ++d) ncell *= b.nc[d];
  reg_cell c = {0};
  unsigned char *mask = counts ? NULL : malloc((size_t)ncell);
  const mpm_lidx *cell = cellmap_get(map, &b, p);
  e->keep = malloc((size_t)(p->n ? p->n : 1));
  if (!cell || !e->keep || (!counts && !mask)) {
    free(mask);
    MPM_FAIL(MPM_ERR_MEMORY, "regularise: cannot group %d particles by cell", (int)p->n);
  }
  memset(e->keep, 1, (size_t)p->n);
  int rc = counts ? 0 : light_cells(fc, &b, p, cell, mask, ncell, &nlight);
  if (!rc && (counts || nlight > 0)) rc = group_by_cell(&b, p, cell, mask, &start, &perm, &ncell);
  for (mpm_lidx l = 0; !rc && start && l < ncell; ++l)
    rc = regularise_cell(fc, p, &b, perm + start[l], (int)(start[l + 1] - start[l]), id_base,
                         counts, &c, e);
  /* Light merges and splits in pairs leave the count: those rows went back in place. */
  if (!rc && (e->nadd > 0 || e->drops > 0)) rc = edit_apply(p, e);
  free(mask), free(start), free(perm), free(c.row), free(c.id), free(c.slot);
  return rc;
}

/* ---- refill ------------------------------------------------------------------------------ */

/* Particles of `phase` in cell c (unwrapped global coordinates: level 0 inside this rank's box);
 * 0 where nothing was counted. */
static double count_of(const reg_box *b, int phase, const int *c) {
  const double *n = b->g->phase[phase].cell_n;
  const mpm_lidx l = n ? store_index(b, c) : -1;
  return l >= 0 ? n[l] : 0.0;
}

/* Global index of cell c on the box's level, wrapped (as mpm_cells_wrap); -1 outside the
 * domain. */
static mpm_gidx cell_index(const reg_box *b, const int *c) {
  mpm_gidx l = 0;
  for (int d = b->dim - 1; d >= 0; --d) {
    const int n = b->ncells[d];
    int w = c[d];
    if (w < 0 || w >= n) {
      if (!b->periodic[d]) return -1;
      w = (w % n + n) % n;
    }
    l = l * n + w;
  }
  return l;
}

/* Does cell c (unwrapped, level 0: inside the rank's box) hold no particle of any phase? */
static int cell_empty(const reg_box *b, const int *c) {
  for (int k = 0; k < b->g->nphases; ++k)
    if (count_of(b, k, c) > 0.0) return 0;
  return 1;
}

/* Has empty cell e an empty face neighbour inside the domain along every axis (a hole, see the
 * header)? e is at most one cell beyond its donor, its neighbours two: inside the ghost
 * layers. */
static int in_hole(const reg_box *b, const int *e) {
  for (int d = 0; d < b->dim; ++d) {
    int found = 0;
    for (int s = -1; s <= 1 && !found; s += 2) {
      int c[MPM_MAX_DIM] = {0};
      memcpy(c, e, sizeof c);
      c[d] += s;
      found = cell_index(b, c) >= 0 && cell_empty(b, c) && is_leaf(b, c);
    }
    if (!found) return 0;
  }
  return 1;
}

/* Is the lattice point e + k (unwrapped; k[d] in cells) outside the obstacles? */
static int free_at(const mpm_module *m, const reg_box *b, const int *e, const double *k) {
  double x[MPM_MAX_DIM] = {0};
  for (int d = 0; d < b->dim; ++d) x[d] = b->lo[d] + (e[d] + k[d]) * b->dx;
  mpm_grid_wrap(m->grid, x);
  return m->ops->reserved(m, x) == NULL;
}

/* Do the obstacles leave the 3^dim cells around cell e free (every corner of them outside)? */
static int clear_of_obstacles(const mpm_module *m, const reg_box *b, const int *e) {
  int n = 1;
  for (int d = 0; d < b->dim; ++d) n *= 4;
  for (int c = 0; c < n; ++c) {
    double k[MPM_MAX_DIM] = {0};
    for (int d = 0, r = c; d < b->dim; ++d, r /= 4) k[d] = r % 4 - 1;
    if (!free_at(m, b, e, k)) return 0;
  }
  return 1;
}

/* Is cell e (unwrapped) a refill target (see the header; holes: of a hole only, and clear of
 * the obstacles)? On a hierarchy it must lie wholly on the box's level. */
static int refill_target(const mpm_module *m, const reg_box *b, const int *e, int holes) {
  if (cell_index(b, e) < 0 || !cell_empty(b, e) || !is_leaf(b, e)) return 0;
  if (holes && !(in_hole(b, e) && clear_of_obstacles(m, b, e))) return 0;
  const double centre[MPM_MAX_DIM] = {0.5, 0.5, 0.5};
  return free_at(m, b, e, centre);
}

/* The direction (0 .. 2 dim) from target e to its donor, or -1 if no neighbour holds gas. On a
 * hierarchy a donor lies wholly on the target's level. */
static int refill_donor(const mpm_module *m, const reg_box *b, const int *e) {
  int best = -1;
  double nbest = 0.0;
  mpm_gidx ibest = 0;
  for (int q = 0; q < 2 * b->dim; ++q) {
    int c[MPM_MAX_DIM] = {0};
    memcpy(c, e, sizeof c);
    c[q / 2] += q % 2 ? 1 : -1;
    const mpm_gidx ic = cell_index(b, c);
    if (ic < 0) continue;
    const double n = count_of(b, m->phase, c);
    if ((n > nbest || (n == nbest && n > 0.0 && ic < ibest)) && is_leaf(b, c))
      best = q, nbest = n, ibest = ic;
  }
  return best;
}

/* Split the heaviest particle among perm[0 .. k) (ties: the lowest id): it keeps half, and a
 * child with the other half goes to the centre of cell e with id `id`. */
static int refill_split(mpm_module *m, const reg_box *b, const mpm_lidx *perm, int k, const int *e,
                        mpm_gidx id, reg_edit *ed) {
  const fluid_content *fc = m->content;
  mpm_particles *p = m->particles;
  double *mass = mpm_particles_comp(p, fc->lay.f_m, 0),
         *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  mpm_lidx h = perm[0];
  for (int a = 1; a < k; ++a) {
    const mpm_lidx i = perm[a];
    if (mass[i] > mass[h] || (mass[i] == mass[h] && p->id[i] < p->id[h])) h = i;
  }
  mass[h] *= 0.5, V0[h] *= 0.5;
  double row[MPM_PARTICLES_MAX_COMPONENTS];
  const int nc = p->ncomp;
  if (nc > (int)(sizeof row / sizeof row[0]))
    MPM_FAIL(MPM_ERR_INTERNAL, "refill: %d components per particle", nc);
  for (int q = 0; q < nc; ++q) row[q] = p->data[(size_t)q * p->n + h];
  for (int d = 0; d < p->dim; ++d) row[p->offset[0] + d] = b->lo[d] + (e[d] + 0.5) * b->dx;
  return edit_append(ed, row, id, nc);
}

/* Mark the owned cells that give to refill targets: for a cell holding gas, bit q of mark is
 * set when its face neighbour in direction q (-x, +x, -y, ...) is a target that chose it as
 * its donor. From the cell counts alone, so that only the donors' particles are grouped, and
 * a refill that finds no target (a flow with no near vacuum) groups none. Returns the number
 * of donors. */
static mpm_lidx mark_donors(const mpm_module *m, const reg_box *b, int holes, unsigned char *mark) {
  const mpm_grid *g = b->g;
  const int dim = b->dim;
  mpm_lidx total = 1, ndonor = 0, stride[MPM_MAX_DIM] = {1, 1, 1};
  for (int d = 0; d < dim; ++d) total *= b->nc[d];
  for (int d = 1; d < dim; ++d) stride[d] = stride[d - 1] * g->box_n[d - 1];
  for (mpm_lidx l = 0; l < total; ++l) {
    int c[MPM_MAX_DIM] = {0};
    mpm_lidx r = l;
    for (int d = 0; d < dim; ++d) c[d] = b->c0[d] + (int)(r % b->nc[d]), r /= b->nc[d];
    mark[l] = 0;
    if (!(count_of(b, m->phase, c) > 0.0)) continue;
    const mpm_lidx lc = b->level ? -1 : mpm_grid_local_index(g, c);
    for (int q = 0; q < 2 * dim; ++q) {
      /* Most neighbours hold particles and so are no target: the counts reject them first. On
       * level 0 a look at the neighbour's counts in the box (the ghost layers hold the cells next
       * to the owned ones: every step of a run that refills, so it is kept cheap); a finer
       * level's box is looked up (its periodic images hold no counts). */
      int e[MPM_MAX_DIM] = {0};
      memcpy(e, c, sizeof e);
      e[q / 2] += q % 2 ? 1 : -1;
      int occupied = 0;
      if (lc >= 0) {
        const mpm_lidx le = lc + (q % 2 ? stride[q / 2] : -stride[q / 2]);
        for (int k = 0; k < g->nphases && !occupied; ++k)
          occupied = g->phase[k].cell_n && g->phase[k].cell_n[le] > 0.0;
      } else {
        occupied = !cell_empty(b, e);
      }
      if (occupied) continue;
      if (refill_target(m, b, e, holes) && refill_donor(m, b, e) == (q ^ 1)) mark[l] |= 1u << q;
    }
    ndonor += mark[l] != 0;
  }
  return ndonor;
}

/* This rank's part of a refill on one level: each cell of b holding gas gives to the targets
 * that chose it, if its particles are on this rank. Appends the children to ed. */
static int refill_local(mpm_module *m, const reg_box *b, int holes, reg_edit *ed, mpm_gidx id_base,
                        reg_cellmap *map) {
  mpm_particles *p = m->particles;
  mpm_lidx ncell = 1;
  for (int d = 0; d < b->dim; ++d) ncell *= b->nc[d];
  unsigned char *donor;
  MPM_ALLOC(donor, ncell);
  mpm_lidx *start = NULL, *perm = NULL;
  int rc = 0;
  if (mark_donors(m, b, holes, donor)) {
    const mpm_lidx *cell = cellmap_get(map, b, p);
    if (!cell) {
      free(donor);
      MPM_FAIL(MPM_ERR_MEMORY, "refill: cannot group %d particles by cell", (int)p->n);
    }
    rc = group_by_cell(b, p, cell, donor, &start, &perm, &ncell);
  }
  for (mpm_lidx l = 0; !rc && start && l < ncell; ++l) {
    const int k = (int)(start[l + 1] - start[l]);
    if (k == 0) continue;
    int c[MPM_MAX_DIM] = {0};
    mpm_lidx r = l;
    for (int d = 0; d < b->dim; ++d) c[d] = b->c0[d] + (int)(r % b->nc[d]), r /= b->nc[d];
    for (int q = 0; !rc && q < 2 * b->dim; ++q) {
      if (!(donor[l] >> q & 1)) continue;
      int e[MPM_MAX_DIM] = {0};
      memcpy(e, c, sizeof e);
      e[q / 2] += q % 2 ? 1 : -1;
      rc = refill_split(m, b, perm + start[l], k, e, id_base + cell_index(b, e), ed);
    }
  }
  free(donor), free(start), free(perm);
  return rc;
}

/* The particles' levels on a hierarchy (mpm_hier_levels, valid until the set or the hierarchy's
 * census changes), NULL without one; *rc set on failure. */
static const unsigned char *particle_levels(const mpm_module *m, int *rc) {
  if (!m->hier) return NULL;
  const unsigned char *lev = fluid_position_levels(m, m->particles->data);
  if (!lev) *rc = MPM_ERR_MEMORY;
  return lev;
}

/* One refill over all ranks and levels (holes: of the holes only): split, append, migrate.
 * Returns the global number of children. map: level 0's cell map without a hierarchy (extended
 * by the children); on a hierarchy each level's map is made and dropped here. */
static int refill(mpm_module *m, int holes, double *children, int *changed, reg_cellmap *map) {
  mpm_particles *p = m->particles;
  reg_edit ed = {0};
  int rc = 0;
  const unsigned char *lev = particle_levels(m, &rc);
  for (int l = 0; !rc && l < levels_of(m); ++l) {
    reg_box b;
    box_of(&b, m, l, lev);
    reg_cellmap own = {0};
    rc = refill_local(m, &b, holes, &ed, p->id_next + level_offset(m, l), m->hier ? &own : map);
    free(own.cell);
  }
  /* A child lands in a cell next to its donor's: on another rank (or across a periodic face)
   * only at the edge of this rank's box. Migration is needed only for those. */
  mpm_lidx away = 0;
  for (mpm_lidx a = 0; !rc && a < ed.nadd; ++a)
    away += mpm_grid_owner_of(m->grid, ed.add + (size_t)a * (size_t)p->ncomp + p->offset[0]) !=
            m->grid->rank;
  if (!rc && ed.nadd) {
    MPM_ALLOC(ed.keep, p->n);
    memset(ed.keep, 1, (size_t)p->n);
    const mpm_lidx n0 = p->n;
    rc = edit_apply(p, &ed);
    /* The children follow the kept particles: extend the map by their cells (a child bound
     * for another rank is migrated below, which makes the map stale anyway). */
    mpm_lidx *grown = !rc && map->cell && map->n == n0 && !away
                          ? realloc(map->cell, sizeof *map->cell * (size_t)p->n)
                          : NULL;
    if (grown) {
      reg_box b;
      box_of(&b, m, 0, NULL);
      cells_from(&b, p, n0, grown);
      map->cell = grown, map->n = p->n;
    }
  }
  double sum[3] = {rc != 0, (double)ed.nadd, (double)away};
  free(ed.keep), free(ed.add), free(ed.add_id);
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, sum, 3, MPI_DOUBLE, MPI_SUM, m->grid->comm));
  MPM_CALL(rc);
  if (sum[0] > 0) MPM_FAIL(MPM_ERR_MEMORY, "refill: failed on another rank");
  *children = sum[1];
  if (sum[1] == 0) return 0;
  p->id_next += level_offset(m, levels_of(m));
  int migrated = 0;
  if (sum[2] > 0) { /* the set changes on every rank that sends or receives: drop the map */
    free(map->cell), map->cell = NULL, map->n = 0;
    MPM_CALL(mpm_particles_migrate(p, m->grid, &migrated));
  }
  *changed = 1;
  return 0;
}

/* Global totals: mass, momentum (3), total energy. */
static void totals(const mpm_module *m, double *t) {
  mpm_module_sums s;
  m->ops->sums(m, &s);
  t[0] = s.mass, t[4] = s.kinetic + s.internal;
  for (int d = 0; d < 3; ++d) t[1 + d] = s.momentum[d];
}

/* The merges and splits of one event on every level (counts: by count too, else the light
 * merges alone, at the share light), each level's edit applied before the next level's cells
 * are found. */
static int regularise_levels(mpm_module *m, int counts, double light, reg_cellmap *map,
                             long *tally) {
  const fluid_content *fc = m->content;
  int rc = 0;
  for (int l = 0; !rc && l < levels_of(m); ++l) {
    reg_edit e = {0};
    const unsigned char *lev = particle_levels(m, &rc);
    reg_box b;
    box_of(&b, m, l, lev);
    b.light = light;
    reg_cellmap own = {0};
    const mpm_gidx base = m->particles->id_next + level_offset(m, l) * (fc->reg_min - 1);
    if (!rc) rc = regularise_local(m, &b, &e, base, counts, m->hier ? &own : map);
    free(own.cell);
    tally[0] += e.splits, tally[1] += e.merges, tally[2] += e.light;
    free(e.keep), free(e.add), free(e.add_id);
  }
  return rc;
}

int fluid_regularise(mpm_module *m, long step, int *changed) {
  const fluid_content *fc = m->content;
  const int merge_split = fc->reg_every > 0 && step % fc->reg_every == 0;
  const int full = fluid_refill_due(fc, step) == 2, fill = fluid_refill_due(fc, step) > 0;
  if (!merge_split && !fill) return 0;
  mpm_particles *p = m->particles;
  long tally[3] = {0, 0, 0}; /* splits, merges, light merges */
  double sum[13] = {0};      /* failures, splits, merges, totals before (5) and after (5) */
  double children = 0.0;
  const int logged = mpm_log_get_level() >= MPM_LOG_DEBUG; /* the totals are for the log only */
  if (logged) totals(m, sum + 3);
  reg_cellmap map = {0};
  int rc = fill ? refill(m, !full, &children, changed, &map) : 0;
  /* The light merges: at every regularisation and full refill at fluid.merge_light; after a
   * refill of holes alone only when it made children, at fluid.merge_light where the key is
   * set, else merge_light_holes (the header, Holes). */
  const double light = merge_split || full ? fc->merge_light
                       : children > 0.0    ? fc->merge_light_holes
                                           : 0.0;
  if (!rc && (merge_split || light > 0.0))
    rc = regularise_levels(m, merge_split, light, &map, tally);
  free(map.cell);
  sum[0] = rc != 0, sum[1] = (double)tally[0], sum[2] = (double)tally[1];
  if (logged) totals(m, sum + 8);
  /* One reduction: every rank learns of a failure anywhere before it goes on. */
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, sum, 13, MPI_DOUBLE, MPI_SUM, m->grid->comm));
  MPM_CALL(rc);
  if (sum[0] > 0) MPM_FAIL(MPM_ERR_MEMORY, "regularise: failed on another rank");
  if (sum[1] > 0) p->id_next += level_offset(m, levels_of(m)) * (mpm_gidx)(fc->reg_min - 1);
  if (tally[0] || tally[1] || tally[2]) *changed = 1;
  mpm_log(MPM_LOG_DEBUG,
          "regularise step %ld: %.0f refills, %.0f splits, %.0f merges; mass %.17g -> %.17g, "
          "momentum (%.17g, %.17g, %.17g) -> (%.17g, %.17g, %.17g), energy %.17g -> %.17g",
          step, children, sum[1], sum[2], sum[3], sum[8], sum[4], sum[5], sum[6], sum[9], sum[10],
          sum[11], sum[7], sum[12]);
  return 0;
}
