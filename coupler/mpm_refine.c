/* The [refine] section and the build of the static hierarchy (see mpm_refine.h).
 *
 * What the slice refuses here, one line each naming the key: boxes without refine.levels > 1,
 * a solid module, more than one rank, a shape other than the quadratic B-spline, and a box
 * within three level-0 cells of a non-periodic domain face (walls and open faces act on level
 * 0 alone). mpm_hier_new's own reasons name the box's key. The gas refuses its own settings
 * (fluid/fluid_refine.c). */
#include "mpm_refine.h"

#include "fluid_module.h"
#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Level-0 cells a box keeps from a non-periodic face. */
#define REFINE_FACE_CELLS 3

const mpm_key_spec mpm_refine_keys[] = {
    {"refine.levels", MPM_KEY_INT, "1", 1, MPM_HIER_MAX_LEVELS, 0, 0, NULL,
     "levels of the static refinement hierarchy, each halving the spacing of the one below (1: "
     "off); gas-only cases on one rank with the quadratic shape, see docs/refinement.md",
     0, "-"},
    {"refine.buffer", MPM_KEY_INT, "2", 1, 64, 0, 0, NULL,
     "level-l cells kept between the region of level l + 1 and the edge of level l's region", 0,
     "-"},
    {"refine.*.level", MPM_KEY_INT, NULL, 1, MPM_HIER_MAX_LEVELS - 1, 0, 0, NULL,
     "the level this box refines to (1 .. refine.levels - 1); a box of level l > 1 must lie "
     "inside level l - 1's region by refine.buffer cells",
     0, "-"},
    {"refine.*.lo", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "lower corner of the box, m (dim values; snapped outwards to the coarser level's cells)", 0,
     "m"},
    {"refine.*.hi", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "upper corner of the box, m (dim values)", 0, "m"},
};
const int mpm_refine_nkeys = (int)(sizeof mpm_refine_keys / sizeof mpm_refine_keys[0]);

/* The case-wide refusals: a solid, several ranks, another shape. */
static int check_case(const mpm_config *cfg, const mpm_grid *grid, mpm_module **mod, int nmod) {
  for (int k = 0; k < nmod; ++k)
    if (mod[k]->role != MPM_ROLE_FLUID)
      return mpm_config_fail(cfg, "refine.levels",
                             "refinement carries the gas alone in this slice, and the case has "
                             "a %s module; remove the [solid.NAME] sections or set levels = 1",
                             mod[k]->name);
  if (grid->size > 1)
    return mpm_config_fail(cfg, "refine.levels",
                           "refinement runs on one rank in this slice, and the run has %d; run "
                           "without mpirun or set levels = 1",
                           grid->size);
  if (grid->shape != MPM_SHAPE_QUADRATIC)
    return mpm_config_fail(cfg, "grid.shape",
                           "refinement needs the quadratic B-spline (its knot spans nest); set "
                           "grid.shape = quadratic or refine.levels = 1");
  return 0;
}

/* Box NAME from its section, kept REFINE_FACE_CELLS level-0 cells from non-periodic faces. */
static int read_box(const mpm_config *cfg, const mpm_grid *g, const char *name, mpm_hier_box *b) {
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
    const int low = b->lo[d] < g->lo[d] + gap - tol;
    if (low || b->hi[d] > g->hi[d] - gap + tol)
      return mpm_config_fail(cfg, key[low ? 1 : 2],
                             "the box comes within %d level-0 cells (%g) of the domain face %c = "
                             "%g, which is not periodic: walls and open faces act on level 0 "
                             "only; keep the box inside [%g, %g] along %c",
                             REFINE_FACE_CELLS, gap, "xyz"[d], low ? g->lo[d] : g->hi[d],
                             g->lo[d] + gap, g->hi[d] - gap, "xyz"[d]);
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
                      mpm_hier_box *box) {
  for (int k = 0; k < n; ++k) MPM_CALL(read_box(cfg, g, names[k], &box[k]));
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
  mpm_hier_box *box;
  MPM_ALLOC(box, nbox);
  int rc = read_boxes(cfg, grid, names, nbox, box);
  char why[512] = "";
  if (!rc) rc = mpm_hier_new(h, grid, levels, box, nbox, buffer, why, sizeof why);
  free(box);
  if (rc == MPM_ERR_INPUT && why[0]) return fail_why(cfg, names, nbox, why);
  MPM_CALL(rc);
  for (int k = 0; k < nmod; ++k) MPM_CALL(fluid_module_refine(mod[k], cfg, *h, seed));
  return 0;
}
