/* The [refine] section and the build of the static hierarchy (see mpm_refine.h).
 *
 * What the slice refuses here, one line each naming the key: boxes without refine.levels > 1,
 * a solid beside a gas in a partitioned time scheme (coupling.time other than monolithic), off
 * the finest level (REFINE_SOLID_CELLS) or, with the gas's particle pressure (auto), with a box
 * that does not span every periodic axis (check_bands), a solid alone with dynamic regrids (they
 * follow a gas), dynamic regrids beside a solid without fluid.pressure = grid, a shape other
 * than the quadratic B-spline, and a box within three level-0 cells of a non-periodic domain face
 * other than a slip or no-slip wall (open and closed faces act on level 0 alone; the walls are
 * carried to every level for both phases, mpm_hier.h, and a box or region may touch them). Along
 * a periodic axis a box or a dynamic
 * region may touch, cross or span the periodic faces (the levels wrap there, mpm_hier.h).
 * mpm_hier_new's own reasons name the box's key. The gas and the solid refuse their own settings
 * (fluid/fluid_refine.c,
 * solid/solid_refine.c). */
#include "mpm_refine.h"

#include "fluid_module.h"
#include "mpm_bc.h"
#include "mpm_error.h"
#include "solid_module.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Level-0 cells a box keeps from a non-periodic face. */
#define REFINE_FACE_CELLS 3

const mpm_key_spec mpm_refine_keys[] = {
    {"refine.levels", MPM_KEY_INT, "1", 1, MPM_HIER_MAX_LEVELS, 0, 0, NULL,
     "levels of the refinement hierarchy (static boxes, or regridded with refine.criterion), each "
     "halving the spacing of the one below (1: "
     "off); with the quadratic shape, on any number of ranks: a gas, a solid on static boxes, "
     "or both (on bands across a periodic axis, or any box or regridded with fluid.pressure = "
     "grid), see docs/refinement.md",
     0, "-"},
    {"refine.buffer", MPM_KEY_INT, "2", 1, 64, 0, 0, NULL,
     "level-l cells kept between the region of level l + 1 and the edge of level l's region", 0,
     "-"},
    {"refine.criterion", MPM_KEY_NAMES, "none", 0, 0, 0, 0, NULL,
     "dynamic refinement, regridded every refine.every steps: none (the [refine.NAME] boxes, "
     "static) or a list of criteria (e.g. compression, starvation) whose flags are joined: "
     "density (refine where the gas density of neighbouring level-0 cells differs by more than "
     "refine.threshold times the smaller), compression (where the velocity normal to their "
     "face falls by more than refine.threshold times the sound speed: shocks), vorticity "
     "(where a velocity along their face jumps by that much: shear layers), starvation (a "
     "level-0 cell inside the gas holding fewer than refine.min_particles level-0 particles), "
     "proximity (a level-0 cell within refine.distance of an [obstacle.NAME])",
     0, NULL},
    {"refine.threshold", MPM_KEY_REALS, "0", 0, HUGE_VAL, 0, 3, NULL,
     "one threshold per listed density, compression or vorticity criterion, in the list's "
     "order: a relative density difference (density, e.g. 0.02 for Sod, 0.004 for a 5 % pulse) or "
     "a velocity drop or jump "
     "over the sound speed (compression, vorticity, e.g. 0.05) between neighbouring level-0 "
     "cells (required with those criteria)",
     0, "-"},
    {"refine.min_particles", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "the starvation criterion's threshold: a level-0 cell whose gas neighbours it on every side "
     "is refined when it holds fewer particles than this, a level-l particle counting 2^-(dim l) "
     "(fluid.ppc^dim fill a cell at the start; e.g. half that; required with starvation)",
     0, "-"},
    {"refine.distance", MPM_KEY_REAL, "0", 0, HUGE_VAL, 0, 0, NULL,
     "the proximity criterion's reach: every level-0 cell that comes within this distance of an "
     "obstacle's surface (or lies inside it) is refined, m (0: the cells the surface cuts; the "
     "obstacles are static, so nothing pads it for their motion)",
     0, "m"},
    {"refine.every", MPM_KEY_INT, "10", 1, 1000000, 0, 0, NULL,
     "steps between regrids of a dynamic refinement (a regrid also runs before every checkpoint)",
     0, "-"},
    {"refine.dilate", MPM_KEY_INT, "2", 1, 64, 0, 0, NULL,
     "level-0 cells added around the flagged cells, per level: level l's region is the flags "
     "dilated by dilate (levels - l) cells (at least refine.buffer / 2)",
     0, "-"},
    {"refine.*.level", MPM_KEY_INT, NULL, 1, MPM_HIER_MAX_LEVELS - 1, 0, 0, NULL,
     "the level this box refines to (1 .. refine.levels - 1); a box of level l > 1 must lie "
     "inside level l - 1's region by refine.buffer cells",
     0, "-"},
    {"refine.*.lo", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "lower corner of the box, m (dim values; snapped outwards to the coarser level's cells; "
     "along a periodic axis the box may cross the faces, up to a period beyond them)",
     0, "m"},
    {"refine.*.hi", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "upper corner of the box, m (dim values)", 0, "m"},
};
const int mpm_refine_nkeys = (int)(sizeof mpm_refine_keys / sizeof mpm_refine_keys[0]);

/* The solid module of the case, or NULL. */
static const mpm_module *solid_of(mpm_module **mod, int nmod) {
  for (int k = 0; k < nmod; ++k)
    if (mod[k]->role == MPM_ROLE_SOLID) return mod[k];
  return NULL;
}

/* The gas module, the one the regrid criteria read (NULL: none). */
static mpm_module *gas_of(mpm_module **mod, int nmod) {
  for (int k = 0; k < nmod; ++k)
    if (mod[k]->role != MPM_ROLE_SOLID) return mod[k];
  return NULL;
}

/* Every module onto h: the gas reseeds its finer regions (seed), the solid too at the start. */
static int refine_modules(const mpm_config *cfg, mpm_module **mod, int nmod, mpm_hier *h,
                          int seed) {
  for (int k = 0; k < nmod; ++k)
    MPM_CALL(mod[k]->role == MPM_ROLE_SOLID ? solid_module_refine(mod[k], cfg, h, seed)
                                            : fluid_module_refine(mod[k], cfg, h, seed));
  return 0;
}

/* The walls the finer levels carry (mpm_hier.h, walls): the slip and no-slip faces, as the
 * components each constrains (both phases fold and mirror their nodes there). */
static int carried_walls(const mpm_config *cfg, const mpm_grid *g,
                         unsigned char wall[MPM_MAX_DIM][2]) {
  memset(wall, 0, sizeof(unsigned char) * MPM_MAX_DIM * 2);
  mpm_walls w;
  MPM_CALL(mpm_walls_from_config(&w, cfg, g->dim));
  for (int d = 0; d < g->dim; ++d)
    for (int s = 0; s < 2; ++s)
      wall[d][s] = w.face[d][s] == MPM_WALL_NO_SLIP ? (unsigned char)((1u << g->dim) - 1)
                   : w.face[d][s] == MPM_WALL_SLIP  ? (unsigned char)(1u << d)
                                                    : 0;
  return 0;
}

/* Finest cells a solid beside a gas keeps inside the finest level's region (solid_refine_inside):
 * its particles' stencils (1.5 cells) and their nodes' supports (1.5 more) lie on that level,
 * so that every node where both phases meet is one of its active nodes, and one cell to move. */
#define REFINE_SOLID_CELLS 4

/* A solid beside a gas: the coupling runs on every level (mpm_coupling_set_hier) in the
 * monolithic time scheme alone (the partitioned ones keep interface state on level 0), with the
 * ERK pairs or usl (musl: the solid refuses it). */
static int check_coupled(const mpm_config *cfg) {
  const char *time;
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  if (strcmp(time, "monolithic") != 0)
    return mpm_config_fail(cfg, "coupling.time",
                           "coupling.time = %s is not carried to the refined levels (refine.levels "
                           "> 1): its interface state (loads, held velocities) lives on level 0's "
                           "nodes; use coupling.time = monolithic or set refine.levels = 1 "
                           "(docs/refinement.md)",
                           time);
  return 0;
}

/* The case-wide refusals: a solid beside a gas in a partitioned time scheme, a solid on several
 * ranks, another shape. */
static int check_case(const mpm_config *cfg, const mpm_grid *grid, mpm_module **mod, int nmod) {
  if (solid_of(mod, nmod) && nmod > 1) MPM_CALL(check_coupled(cfg));
  if (grid->shape != MPM_SHAPE_QUADRATIC)
    return mpm_config_fail(cfg, "grid.shape",
                           "refinement needs the quadratic B-spline (its knot spans nest); set "
                           "grid.shape = quadratic or refine.levels = 1");
  return 0;
}

/* Box NAME from its section, kept REFINE_FACE_CELLS level-0 cells from non-periodic faces other
 * than a carried wall (wall[d][side]: touched, not crossed); along a periodic axis mpm_hier_new
 * takes it up to a period beyond the faces. */
static int read_box(const mpm_config *cfg, const mpm_grid *g, const char *name,
                    const unsigned char (*wall)[2], mpm_hier_box *b) {
  char key[3][160];
  static const char *const part[3] = {"level", "lo", "hi"};
  for (int j = 0; j < 3; ++j) snprintf(key[j], sizeof key[j], "refine.%s.%s", name, part[j]);
  MPM_CALL(mpm_config_get_int(cfg, key[0], &b->level));
  double *v[2] = {b->lo, b->hi};
  for (int j = 0; j < 2; ++j) {
    int count;
    MPM_CALL(mpm_config_get_reals(cfg, key[1 + j], v[j], MPM_MAX_DIM, &count));
    if (count != g->dim)
      return mpm_config_fail(cfg, key[1 + j], "needs %d values, got %d", g->dim, count);
  }
  const double gap = REFINE_FACE_CELLS * g->dx, tol = 1e-9 * g->dx;
  for (int d = 0; d < g->dim; ++d) {
    if (g->periodic[d]) continue;
    const double gap_lo = wall[d][0] ? 0.0 : gap, gap_hi = wall[d][1] ? 0.0 : gap;
    const int low = b->lo[d] < g->lo[d] + gap_lo - tol;
    if (low || b->hi[d] > g->hi[d] - gap_hi + tol)
      return mpm_config_fail(cfg, key[low ? 1 : 2],
                             "the box comes within %d level-0 cells (%g) of the domain face %c = "
                             "%g, or past a wall: open faces and closed faces (none) act on "
                             "level 0 only; keep the box inside [%g, %g] along %c (a slip or "
                             "no-slip wall may be touched, not crossed)",
                             REFINE_FACE_CELLS, gap, "xyz"[d], low ? g->lo[d] : g->hi[d],
                             g->lo[d] + gap_lo, g->hi[d] - gap_hi, "xyz"[d]);
  }
  return 0;
}

/* A solid beside a gas with fluid.pressure = auto: the gas keeps its particles' pressure
 * (fluid/fluid_gridp.c; grid takes the solid's region out of its span integrals and needs no
 * bands, fluid/fluid_gridp_solid.c), whose
 * quadrature is exact across a level's face only where that face is a plane through the domain
 * (edges and corners of a box in the gas disturb it, docs/refinement.md): every box spans the
 * whole period of every periodic axis, and some axis must be periodic. */
static int check_bands(const mpm_config *cfg, const mpm_grid *g, const char *const *names,
                       const mpm_hier_box *box, int nbox) {
  const double tol = 1e-9 * g->dx;
  for (int k = 0; k < nbox; ++k) {
    int periodic = 0;
    for (int d = 0; d < g->dim; ++d) {
      if (!g->periodic[d]) continue;
      periodic = 1;
      if (box[k].lo[d] <= g->lo[d] + tol && box[k].hi[d] >= g->hi[d] - tol) continue;
      char key[160];
      snprintf(key, sizeof key, "refine.%s.lo", names[k]);
      return mpm_config_fail(cfg, key,
                             "with a solid beside the gas a box must span the periodic axis %c "
                             "(lo = %g, hi = %g along it): the gas keeps its particles' pressure, "
                             "which a box's edges in the gas disturb (docs/refinement.md)",
                             "xyz"[d], g -> lo[d], g -> hi[d]);
    }
    if (!periodic) {
      char key[160];
      snprintf(key, sizeof key, "refine.%s.lo", names[k]);
      return mpm_config_fail(cfg, key,
                             "with a solid beside the gas a box must span a periodic axis, and "
                             "the domain has none: the gas keeps its particles' pressure, which a "
                             "box's edges in the gas disturb; make an axis periodic or set "
                             "refine.levels = 1 (docs/refinement.md)");
    }
  }
  return 0;
}

/* mpm_hier_new's reason, on the key of the box it names ("box N"), else on refine.levels. */
static int fail_why(const mpm_config *cfg, const char *const *names, int nbox, const char *why) {
  const char *at = strstr(why, "box ");
  char key[160] = "refine.levels";
  if (at) {
    char *end;
    const long k = strtol(at + 4, &end, 10);
    if (end != at + 4 && k >= 0 && k < nbox) snprintf(key, sizeof key, "refine.%s.lo", names[k]);
  }
  return mpm_config_fail(cfg, key, "%s", why);
}

static int read_boxes(const mpm_config *cfg, const mpm_grid *g, const char *const *names, int n,
                      const unsigned char (*wall)[2], mpm_hier_box *box) {
  for (int k = 0; k < n; ++k) MPM_CALL(read_box(cfg, g, names[k], wall, &box[k]));
  return 0;
}

/* ---- dynamic refinement: the regions from the criterion's flags --------------------------- */

/* Level-0 cells a dynamic region keeps from every non-periodic domain face other than a carried
 * wall (the static boxes' rule, met by construction: span i's lower face is at (i - 1/2) dx);
 * along a periodic axis the region wraps, and at a wall it may take in the face span. */
#define REFINE_CLIP 4

/* The criteria refine.criterion may list, in fluid_refine_criterion's order; the first
 * REFINE_NGAS read refine.threshold, starvation reads refine.min_particles, proximity
 * refine.distance. */
static const char *const g_criteria[] = {"density", "compression", "vorticity", "starvation",
                                         "proximity"};
#define REFINE_NCRIT ((int)(sizeof g_criteria / sizeof g_criteria[0]))
#define REFINE_NGAS  3

typedef struct dynamic {
  int levels, buffer, every, dilate;
  int ncrit; /* criteria listed (0: none) */
  fluid_refine_criterion crit[REFINE_NCRIT];
  double threshold[REFINE_NCRIT];     /* each one's threshold */
  unsigned char wall[MPM_MAX_DIM][2]; /* the walls carried (carried_walls) */
} dynamic;

/* The criteria of refine.criterion into dy->crit (none: ncrit = 0), each known and listed
 * once, none alone. */
static int read_criteria(const mpm_config *cfg, dynamic *dy) {
  const char *list;
  MPM_CALL(mpm_config_get_string(cfg, "refine.criterion", &list));
  int none = 0, seen[REFINE_NCRIT] = {0};
  dy->ncrit = 0;
  for (const char *s = list + strspn(list, " \t,"); *s; s += strspn(s, " \t,")) {
    const int len = (int)strcspn(s, " \t,");
    int k = 0;
    while (k < REFINE_NCRIT &&
           !(strncmp(s, g_criteria[k], (size_t)len) == 0 && g_criteria[k][len] == '\0'))
      ++k;
    if (len == 4 && strncmp(s, "none", 4) == 0)
      none = 1;
    else if (k == REFINE_NCRIT)
      return mpm_config_fail(cfg, "refine.criterion",
                             "'%.*s' is not a criterion; list none, or one or more of density, "
                             "compression, vorticity, starvation and proximity, separated by "
                             "commas",
                             len, s);
    else if (seen[k]++)
      return mpm_config_fail(cfg, "refine.criterion", "lists %s twice; list each criterion once",
                             g_criteria[k]);
    else
      dy->crit[dy->ncrit++] = (fluid_refine_criterion)k;
    s += len;
  }
  if (none && dy->ncrit > 0)
    return mpm_config_fail(cfg, "refine.criterion",
                           "lists none with other criteria; give none alone (no dynamic "
                           "refinement) or remove it from the list");
  return 0;
}

/* Is proximity listed? */
static int near_listed(const dynamic *dy) {
  for (int k = 0; k < dy->ncrit; ++k)
    if (dy->crit[k] == FLUID_REFINE_PROXIMITY) return 1;
  return 0;
}

/* The first listed criterion that reads refine.threshold (the caller knows there is one). */
static fluid_refine_criterion first_gas(const dynamic *dy) {
  int k = 0;
  while (k + 1 < dy->ncrit && dy->crit[k] >= FLUID_REFINE_STARVATION) ++k;
  return dy->crit[k];
}

/* Proximity's reach, refine.distance (>= 0 by its key), into its slot of dy->threshold; the key
 * is refused without proximity, and proximity without an [obstacle.NAME] to be near. */
static int read_distance(const mpm_config *cfg, dynamic *dy) {
  double distance;
  MPM_CALL(mpm_config_get_real(cfg, "refine.distance", &distance));
  const int listed = near_listed(dy);
  if (!listed && mpm_config_has(cfg, "refine.distance"))
    return mpm_config_fail(cfg, "refine.distance",
                           "is set, and refine.criterion does not list proximity, its only "
                           "reader; add proximity to the list or remove the key");
  const char *const *names;
  int nobstacle;
  MPM_CALL(mpm_config_instances(cfg, "obstacle", &names, &nobstacle));
  if (listed && nobstacle == 0)
    return mpm_config_fail(cfg, "refine.criterion",
                           "lists proximity, which refines around the case's [obstacle.NAME] "
                           "bodies, and the case has none; add an obstacle or remove proximity");
  for (int k = 0; k < dy->ncrit; ++k)
    if (dy->crit[k] == FLUID_REFINE_PROXIMITY) dy->threshold[k] = distance;
  return 0;
}

/* The thresholds of the listed criteria: refine.threshold's values, one per gas-state
 * criterion in the list's order, and refine.min_particles for starvation; each required and
 * > 0, and neither key set without a criterion reading it. */
static int read_thresholds(const mpm_config *cfg, dynamic *dy) {
  double value[REFINE_NGAS], min_particles;
  int count, ngas = 0, starve = 0;
  MPM_CALL(mpm_config_get_reals(cfg, "refine.threshold", value, REFINE_NGAS, &count));
  MPM_CALL(mpm_config_get_real(cfg, "refine.min_particles", &min_particles));
  for (int k = 0; k < dy->ncrit; ++k) starve += dy->crit[k] == FLUID_REFINE_STARVATION;
  ngas = dy->ncrit - starve - near_listed(dy);
  const int has_threshold = mpm_config_has(cfg, "refine.threshold");
  if (ngas > 0 && !has_threshold) /* named: the first gas-state criterion (starvation is once) */
    return mpm_config_fail(cfg, "refine.criterion",
                           "%s needs a threshold: set refine.threshold > 0 (the jump between "
                           "neighbouring cells that refines them, e.g. 0.05; one value per "
                           "density, compression or vorticity criterion; see the key reference)",
                           g_criteria[first_gas(dy)]);
  if (has_threshold && ngas == 0)
    return mpm_config_fail(cfg, "refine.threshold",
                           "is set, and refine.criterion lists none of its readers (density, "
                           "compression, vorticity); remove the key or list one of them");
  if (has_threshold && count != ngas)
    return mpm_config_fail(cfg, "refine.threshold",
                           "has %d value%s for the %d criteria of refine.criterion that read it "
                           "(density, compression, vorticity); give one per such criterion, in "
                           "the list's order",
                           count, count == 1 ? "" : "s", ngas);
  if (starve && !(min_particles > 0))
    return mpm_config_fail(cfg,
                           mpm_config_has(cfg, "refine.min_particles") ? "refine.min_particles"
                                                                       : "refine.criterion",
                           "starvation needs a threshold: set refine.min_particles > 0 (the "
                           "level-0 particles per cell below which a cell inside the gas is "
                           "refined, e.g. half of fluid.ppc^dim)");
  if (!starve && mpm_config_has(cfg, "refine.min_particles"))
    return mpm_config_fail(cfg, "refine.min_particles",
                           "is set, and refine.criterion does not list starvation, its only "
                           "reader; add starvation to the list or remove the key");
  MPM_CALL(read_distance(cfg, dy));
  for (int k = 0, j = 0; k < dy->ncrit; ++k) {
    if (dy->crit[k] == FLUID_REFINE_PROXIMITY) continue; /* read_distance */
    const int gas = dy->crit[k] != FLUID_REFINE_STARVATION;
    dy->threshold[k] = gas ? value[j++] : min_particles;
    if (!(dy->threshold[k] > 0))
      return mpm_config_fail(cfg, "refine.threshold",
                             "is 0 for %s; give each criterion a threshold > 0 (e.g. 0.05)",
                             g_criteria[dy->crit[k]]);
  }
  return 0;
}

/* With refine.criterion = none nothing regrids: a key only the regrids read is refused rather
 * than ignored, so that a case that forgot its criterion does not run unrefined unawares. */
static int refuse_regrid_keys(const mpm_config *cfg) {
  static const char *const keys[] = {"refine.threshold", "refine.min_particles", "refine.distance",
                                     "refine.every", "refine.dilate"};
  for (size_t k = 0; k < sizeof keys / sizeof keys[0]; ++k)
    if (mpm_config_has(cfg, keys[k]))
      return mpm_config_fail(cfg, keys[k],
                             "is set, and refine.criterion is none, so nothing regrids and the "
                             "key has no effect; name a criterion (density, compression, "
                             "vorticity, starvation, proximity) or remove the key");
  return 0;
}

/* The dynamic settings, or 0 in *on when refine.criterion = none. */
static int read_dynamic(const mpm_config *cfg, dynamic *dy, int *on) {
  MPM_CALL(read_criteria(cfg, dy));
  *on = dy->ncrit > 0;
  MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &dy->levels));
  MPM_CALL(mpm_config_get_int(cfg, "refine.buffer", &dy->buffer));
  MPM_CALL(mpm_config_get_int(cfg, "refine.every", &dy->every));
  MPM_CALL(mpm_config_get_int(cfg, "refine.dilate", &dy->dilate));
  if (!*on) return refuse_regrid_keys(cfg);
  MPM_CALL(read_thresholds(cfg, dy));
  if (2 * dy->dilate < dy->buffer)
    return mpm_config_fail(cfg, "refine.dilate",
                           "is %d, and the levels' regions must nest with refine.buffer = %d "
                           "cells of the finer level between them; set refine.dilate >= %d",
                           dy->dilate, dy->buffer, (dy->buffer + 1) / 2);
  return 0;
}

/* Spans per axis of the flag lattice (fluid_refine_flags). */
static size_t flag_lattice(const mpm_grid *g, int *n) {
  size_t total = 1;
  for (int d = 0; d < MPM_MAX_DIM; ++d) n[d] = 1;
  for (int d = 0; d < g->dim; ++d)
    n[d] = g->ncells[d] + (g->periodic[d] ? 0 : 1), total *= (size_t)n[d];
  return total;
}

/* Dilate mask by r spans along every axis (a box of side 2 r + 1), wrapping along the
 * periodic ones, into out; tmp as scratch. */
static void dilate(const mpm_grid *g, const int *n, int r, const unsigned char *mask,
                   unsigned char *out, unsigned char *tmp) {
  const size_t total = (size_t)n[0] * n[1] * n[2];
  memcpy(out, mask, total);
  size_t stride = 1;
  for (int d = 0; d < g->dim; stride *= (size_t)n[d], ++d) {
    memcpy(tmp, out, total);
    const int wrap = g->periodic[d];
    for (size_t s = 0; s < total; ++s) {
      if (!tmp[s]) continue;
      const int i = (int)(s / stride % (size_t)n[d]);
      const int a = wrap ? i - r : MPM_MAX(0, i - r), z = wrap ? i + r : MPM_MIN(n[d] - 1, i + r);
      for (int j = a; j <= z; ++j) {
        const int k = ((j % n[d]) + n[d]) % n[d];
        out[s + ((size_t)k - (size_t)i) * stride] = 1;
      }
    }
  }
}

/* Append the boxes of level l covering mask (runs along x, one row at a time) to *box. */
static int mask_boxes(const mpm_grid *g, const int *n, int l, double eps, const unsigned char *mask,
                      mpm_hier_box **box, int *nbox, int *cap) {
  const size_t rows = (size_t)n[1] * n[2];
  for (size_t row = 0; row < rows; ++row) {
    const int j[2] = {(int)(row % (size_t)n[1]), (int)(row / (size_t)n[1])};
    const unsigned char *m = mask + row * (size_t)n[0];
    for (int a = 0; a < n[0]; ++a) {
      if (!m[a]) continue;
      int z = a;
      while (z + 1 < n[0] && m[z + 1]) ++z;
      if (*nbox == *cap) {
        *cap = 2 * *cap + 16;
        mpm_hier_box *grown = realloc(*box, sizeof **box * (size_t)*cap);
        if (!grown) MPM_FAIL_OOM(sizeof **box * (size_t)*cap);
        *box = grown;
      }
      mpm_hier_box *b = &(*box)[(*nbox)++];
      const int first[3] = {a, j[0], j[1]}, last[3] = {z, j[0], j[1]};
      b->level = l;
      for (int d = 0; d < g->dim; ++d) { /* (span 0 of a periodic axis crosses its face) */
        b->lo[d] = g->lo[d] + (first[d] - 0.5) * g->dx + eps;
        b->hi[d] = g->lo[d] + (last[d] + 0.5) * g->dx - eps;
        if (!g->periodic[d]) /* at a wall: its face span, snapped back to it by mpm_hier_new */
          b->lo[d] = fmax(b->lo[d], g->lo[d]), b->hi[d] = fmin(b->hi[d], g->hi[d]);
      }
      a = z;
    }
  }
  return 0;
}

/* The hierarchy the gas's flags ask for (*h = NULL when nothing is flagged). Level l's region
 * is the flags dilated by dilate (levels - l) spans, clipped to REFINE_CLIP + (l - 1) dilate
 * spans from every non-periodic face, so that each level nests in the one below with its
 * buffer; along a periodic axis the dilation wraps and nothing is clipped. Beside a solid
 * (solid not NULL) the spans holding its particles, dilated by REFINE_SOLID_CELLS + every
 * finest cells and half a span, are flagged too, so that the solid stays on the finest level
 * with its cells to spare until the next regrid (a particle moves less than a finest cell per
 * step: the stable step); *kept says whether the finest level's region holds all of them
 * (clipping at the faces may take some away). */
static int make_dynamic(mpm_hier **h, const dynamic *dy, mpm_grid *grid, mpm_module *gas,
                        const mpm_module *solid, int *kept) {
  int n[MPM_MAX_DIM];
  const size_t total = flag_lattice(grid, n);
  unsigned char *flag = malloc(4 * total);
  if (!flag) MPM_FAIL_OOM(4 * total);
  unsigned char *mask = flag + total, *tmp = mask + total, *held = tmp + total;
  mpm_hier_box *box = NULL;
  int nbox = 0, cap = 0, used = 1;
  int rc = 0;
  memset(flag, 0, total);
  for (int k = 0; k < dy->ncrit && !rc; ++k) { /* the union of the criteria's flags */
    rc = fluid_refine_flags(gas, dy->crit[k], dy->threshold[k], n, tmp);
    for (size_t s = 0; s < total && !rc; ++s) flag[s] |= tmp[s];
  }
  *kept = 1;
  if (solid && !rc) {
    const double reach = (REFINE_SOLID_CELLS + dy->every) * ldexp(1.0, 1 - dy->levels);
    rc = solid_refine_spans(solid, n, mask);
    if (!rc) dilate(grid, n, (int)ceil(reach + 0.5), mask, held, tmp);
    for (size_t s = 0; s < total && !rc; ++s) flag[s] |= held[s];
  }
  const double eps = 1e-6 * ldexp(grid->dx, -dy->levels);
  for (int l = 1; l < dy->levels && !rc; ++l) {
    dilate(grid, n, dy->dilate * (dy->levels - l), flag, mask, tmp);
    const int clip = REFINE_CLIP + (l - 1) * dy->dilate;
    int any = 0;
    for (size_t s = 0; s < total; ++s) {
      int in = 1;
      for (int d = 0, r = (int)s; d < grid->dim; r /= n[d], ++d)
        in &= grid->periodic[d] || ((dy->wall[d][0] || r % n[d] >= clip) &&
                                    (dy->wall[d][1] || r % n[d] <= grid->ncells[d] - clip));
      mask[s] &= (unsigned char)in;
      any |= mask[s];
    }
    if (!any) break;
    used = l + 1;
    rc = mask_boxes(grid, n, l, eps, mask, &box, &nbox, &cap);
    for (size_t s = 0; solid && l + 1 == dy->levels && s < total; ++s) *kept &= !held[s] || mask[s];
  }
  if (solid && used < dy->levels) *kept = 0;
  free(flag);
  char why[512] = "";
  *h = NULL;
  if (!rc && used > 1)
    rc = mpm_hier_new_walled(h, grid, used, box, nbox, dy->buffer,
                             (const unsigned char(*)[2])dy->wall, why, sizeof why);
  free(box);
  if (rc == MPM_ERR_INPUT) MPM_FAIL(MPM_ERR_INTERNAL, "regrid: %s", why);
  return rc;
}

/* Do a and b (either may be NULL) have the same levels and regions? */
static int same_regions(const mpm_hier *a, const mpm_hier *b) {
  if (!a || !b) return a == b;
  if (a->nlevels != b->nlevels) return 0;
  if (memcmp(a->level[0].refined, b->level[0].refined, (size_t)a->level[0].grid->nnodes)) return 0;
  for (int l = 1; l < a->nlevels; ++l) {
    const mpm_grid *ga = a->level[l].grid, *gb = b->level[l].grid;
    for (int d = 0; d < a->dim; ++d)
      if (ga->box_lo[d] != gb->box_lo[d] || ga->box_n[d] != gb->box_n[d]) return 0;
    if (memcmp(a->level[l].covered, b->level[l].covered, (size_t)ga->nnodes)) return 0;
  }
  return 1;
}

int mpm_refine_dynamic(const mpm_config *cfg) {
  const char *criterion;
  int levels;
  if (mpm_config_get_string(cfg, "refine.criterion", &criterion) ||
      mpm_config_get_int(cfg, "refine.levels", &levels))
    return 0;
  const char *first = criterion + strspn(criterion, " \t,");
  return levels > 1 && !(strncmp(first, "none", 4) == 0 && strcspn(first, " \t,") == 4);
}

int mpm_refine_regrid(mpm_hier **h, const mpm_config *cfg, mpm_grid *grid, mpm_module **mod,
                      int nmod, long step, int force, int *changed) {
  *changed = 0;
  dynamic dy;
  int on;
  MPM_CALL(read_dynamic(cfg, &dy, &on));
  if (!on || nmod < 1 || (!force && step % dy.every != 0)) return 0;
  MPM_CALL(carried_walls(cfg, grid, dy.wall));
  mpm_hier *next;
  const mpm_module *solid = nmod > 1 ? solid_of(mod, nmod) : NULL;
  int kept;
  MPM_CALL(make_dynamic(&next, &dy, grid, gas_of(mod, nmod), solid, &kept));
  if (same_regions(next, *h)) { /* keep the hierarchy, and the integrator's state */
    mpm_hier_destroy(&next);
    return 0;
  }
  int rc = 0;
  for (int k = 0; k < nmod; ++k) {
    if (mod[k]->role != MPM_ROLE_SOLID)
      fluid_module_rehier(mod[k], next);
    else if (!rc)
      rc = solid_module_rehier(mod[k], next);
  }
  mpm_hier_destroy(h);
  *h = next;
  MPM_CALL(rc); /* (out of memory: the modules are on the new hierarchy, the run stops) */
  *changed = 1;
  /* The flags keep the solid on the finest level (make_dynamic); a body the faces' clipping
   * takes off it is an error of the run, named on its key (solid_refine_inside finds it). */
  if (solid && !kept) {
    MPM_CALL(solid_refine_inside(solid, cfg, REFINE_SOLID_CELLS));
    MPM_FAIL(MPM_ERR_INPUT,
             "regrid: the solid's margin reaches past the finest level's region "
             "at a domain face; keep the body %d level-0 cells from the faces",
             REFINE_CLIP + (dy.levels - 2) * dy.dilate);
  }
  return 0;
}

int mpm_refine_follow(mpm_module **mod, int nmod, int *changed) {
  for (int k = 0; k < nmod; ++k)
    if (mod[k]->role != MPM_ROLE_SOLID) MPM_CALL(fluid_module_follow(mod[k], changed));
  return 0;
}

int mpm_refine_build(mpm_hier **h, const mpm_config *cfg, mpm_grid *grid, mpm_module **mod,
                     int nmod, int seed) {
  int levels, buffer, nbox;
  const char *const *names;
  *h = NULL;
  MPM_CALL(mpm_config_get_int(cfg, "refine.levels", &levels));
  MPM_CALL(mpm_config_get_int(cfg, "refine.buffer", &buffer));
  MPM_CALL(mpm_config_instances(cfg, "refine", &names, &nbox));
  if (levels == 1 && nbox > 0) {
    char key[160];
    snprintf(key, sizeof key, "refine.%s.level", names[0]);
    return mpm_config_fail(cfg, key,
                           "refines a box, and refine.levels = 1 turns refinement off; set "
                           "refine.levels to the finest box level + 1, or remove the box");
  }
  if (levels == 1) return 0;
  MPM_CALL(check_case(cfg, grid, mod, nmod));
  dynamic dy;
  int on;
  MPM_CALL(read_dynamic(cfg, &dy, &on));
  if (on && solid_of(mod, nmod) && nmod == 1)
    return mpm_config_fail(cfg, "refine.criterion",
                           "regrids follow a gas, and a solid alone runs on static boxes; set "
                           "refine.criterion = none and give [refine.NAME] boxes");
  const char *pressure = "auto";
  if (on && solid_of(mod, nmod)) MPM_CALL(mpm_config_get_string(cfg, "fluid.pressure", &pressure));
  if (on && solid_of(mod, nmod) && strcmp(pressure, "grid") != 0)
    return mpm_config_fail(cfg, "refine.criterion",
                           "regrids beside a solid need fluid.pressure = grid (the particles' "
                           "pressure needs bands across a periodic axis, which a regridded "
                           "region is not); set fluid.pressure = grid, or refine.criterion = none "
                           "with [refine.NAME] bands");
  if (on && nbox > 0) {
    char key[160];
    snprintf(key, sizeof key, "refine.%s.level", names[0]);
    return mpm_config_fail(cfg, key,
                           "is a static box, and refine.criterion refines dynamically: remove "
                           "the [refine.NAME] boxes or set refine.criterion = none");
  }
  unsigned char wall[MPM_MAX_DIM][2];
  MPM_CALL(carried_walls(cfg, grid, wall));
  memcpy(dy.wall, wall, sizeof wall);
  if (on) { /* from the seeded gas (on a restart the sim regrids once the particles are read) */
    const mpm_module *solid = nmod > 1 ? solid_of(mod, nmod) : NULL;
    int kept;
    MPM_CALL(make_dynamic(h, &dy, grid, gas_of(mod, nmod), solid, &kept));
    MPM_CALL(refine_modules(cfg, mod, nmod, *h, seed));
    if (solid && *h) MPM_CALL(solid_refine_inside(solid, cfg, REFINE_SOLID_CELLS));
    return 0;
  }
  mpm_hier_box *box;
  MPM_ALLOC(box, nbox);
  int rc = read_boxes(cfg, grid, names, nbox, (const unsigned char(*)[2])wall, box);
  if (!rc && solid_of(mod, nmod) && nmod > 1)
    rc = mpm_config_get_string(cfg, "fluid.pressure", &pressure);
  if (!rc && solid_of(mod, nmod) && nmod > 1 && strcmp(pressure, "grid") != 0)
    rc = check_bands(cfg, grid, names, box, nbox);
  char why[512] = "";
  if (!rc)
    rc = mpm_hier_new_walled(h, grid, levels, box, nbox, buffer, (const unsigned char(*)[2])wall,
                             why, sizeof why);
  free(box);
  if (rc == MPM_ERR_INPUT && why[0]) return fail_why(cfg, names, nbox, why);
  MPM_CALL(rc);
  MPM_CALL(refine_modules(cfg, mod, nmod, *h, seed));
  const mpm_module *solid = solid_of(mod, nmod);
  if (solid && nmod > 1) MPM_CALL(solid_refine_inside(solid, cfg, REFINE_SOLID_CELLS));
  return 0;
}
