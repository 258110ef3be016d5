/* Regions from [geometry.NAME] sections, their inside tests, and lattice seeding.
 *
 * A region is a tagged record: `type` points at one row of the static type table (name,
 * keys it uses, dimension it needs, builder, inside test). Composite regions (union,
 * difference) own their children, built recursively from `of`; a chain of the names being
 * built is kept on the C stack so that a cycle is reported instead of recursing forever.
 *
 * Invariants: lo/hi always hold the region's axis-aligned bounding box (for a box they are
 * the box itself), so seeding can skip cells that cannot contain a point; a polygon's
 * vertices have no repeated closing vertex and enclose a non-zero area. */
#define _POSIX_C_SOURCE 200809L
#include "mpm_geometry.h"
#include "mpm_error.h"
#include "mpm_sdf.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KEY_LEN       256
#define MAX_BAD_LINES 10    /* polygon file lines reported before giving up */
#define MAX_VERTICES  20000 /* a polygon's vertices: the crossing check costs their square */

const mpm_key_spec mpm_geometry_keys[] = {
    {"geometry.*.type", MPM_KEY_ENUM, NULL, 0, 0, 0, 0,
     "box|disk|sphere|cylinder|polygon|union|difference",
     "region shape: box (lo, hi), disk (2-D: center, radius), sphere (3-D: center, radius), "
     "cylinder (3-D: p0, p1, radius), polygon (file; z in 3-D), union or difference (of)",
     0, NULL},
    {"geometry.*.lo", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "box: lower corner, one coordinate per dimension (m), each below hi", 1, "m"},
    {"geometry.*.hi", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "box: upper corner, one coordinate per dimension (m), each above lo", 1, "m"},
    {"geometry.*.center", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "disk (x y) or sphere (x y z): centre (m)", 1, "m"},
    {"geometry.*.radius", MPM_KEY_REAL, NULL, 0.0, HUGE_VAL, 1, 0, NULL,
     "disk, sphere, cylinder: radius (m), > 0", 1, "m"},
    {"geometry.*.p0", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "cylinder: centre of one end face, x y z (m)", 1, "m"},
    {"geometry.*.p1", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "cylinder: centre of the other end face, x y z (m), different from p0", 1, "m"},
    {"geometry.*.file", MPM_KEY_PATH, NULL, 0, 0, 0, 0, NULL,
     "polygon: vertex file, one \"x y\" or \"x,y\" per line (m), '#' starts a comment; "
     "closed implicitly, at least 3 vertices",
     1, NULL},
    {"geometry.*.z", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 2, NULL,
     "polygon in 3-D: extrusion range z_lo z_hi (m), z_lo < z_hi", 1, "m"},
    {"geometry.*.of", MPM_KEY_NAMES, NULL, 0, 0, 0, 0, NULL,
     "union: regions to join; difference: a region, then the regions cut out of it", 1, NULL},
};
const int mpm_geometry_nkeys = (int)(sizeof mpm_geometry_keys / sizeof mpm_geometry_keys[0]);

static const char g_axis[MPM_MAX_DIM] = {'x', 'y', 'z'};

/* Every optional field of a [geometry.NAME] section, to find ones the type ignores. */
static const char *const g_fields[] = {"lo", "hi",   "center", "radius", "p0",
                                       "p1", "file", "z",      "of"};

/* Names being built, innermost first: a cycle is a name already on the chain. */
typedef struct chain {
  const char *name;
  const struct chain *up;
} chain;

typedef struct region_type region_type;

typedef struct build_ctx {
  const mpm_config *cfg;
  int dim;
  const char *name;
  const region_type *type;
  const chain *path; /* includes name */
} build_ctx;

struct region_type {
  const char *name;
  const char *uses; /* fields this type reads, blank separated */
  int dim;          /* 2 or 3 if the type exists in one dimension only, else 0 */
  int (*build)(mpm_region *r, const build_ctx *ctx);
  int (*contains)(const mpm_region *r, const double *x);
};

struct mpm_region {
  const region_type *type;
  int dim;
  double lo[MPM_MAX_DIM], hi[MPM_MAX_DIM]; /* bounding box */
  double c[MPM_MAX_DIM], radius;           /* disk, sphere; cylinder: c = p0 */
  double axis[MPM_MAX_DIM];                /* cylinder: p1 - p0 */
  int nv;
  double *v; /* polygon vertices, (x, y) pairs */
  int nchild;
  mpm_region **child;
};

static int build_region(mpm_region **r, const mpm_config *cfg, int dim, const char *name,
                        const chain *up);

/* ---------------------------------------------------------------------------- keys --- */

static int make_key(char *key, const char *name, const char *field) {
  int k = snprintf(key, KEY_LEN, "geometry.%s.%s", name, field);
  if (k < 0 || k >= KEY_LEN) MPM_FAIL(MPM_ERR_INPUT, "geometry name '%s' is too long", name);
  return 0;
}

/* A key the type needs but the section lacks: blame the type line, which has a location. */
static int missing(const build_ctx *ctx, const char *field, const char *what) {
  char key[KEY_LEN];
  MPM_CALL(make_key(key, ctx->name, "type"));
  return mpm_config_fail(ctx->cfg, key, "a %s needs %s: add `%s = ...` to [geometry.%s]",
                         ctx->type->name, what, field, ctx->name);
}

/* Exactly n reals from geometry.NAME.field, which must be set. */
static int get_vec(const build_ctx *ctx, const char *field, int n, const char *what, double *v) {
  char key[KEY_LEN];
  double buf[MPM_MAX_DIM + 1];
  int count = 0;
  MPM_CALL(make_key(key, ctx->name, field));
  if (!mpm_config_has(ctx->cfg, key)) return missing(ctx, field, what);
  MPM_CALL(mpm_config_get_reals(ctx->cfg, key, buf, MPM_MAX_DIM + 1, &count));
  if (count != n)
    return mpm_config_fail(ctx->cfg, key, "needs %d values (%s), got %d", n, what, count);
  for (int i = 0; i < n; ++i)
    if (!isfinite(buf[i])) return mpm_config_fail(ctx->cfg, key, "values must be finite");
  memcpy(v, buf, (size_t)n * sizeof *v);
  return 0;
}

static int get_radius(const build_ctx *ctx, double *radius) {
  char key[KEY_LEN];
  MPM_CALL(make_key(key, ctx->name, "radius"));
  if (!mpm_config_has(ctx->cfg, key)) return missing(ctx, "radius", "a radius (m, > 0)");
  MPM_CALL(mpm_config_get_real(ctx->cfg, key, radius));
  if (!(*radius > 0.0) || !isfinite(*radius))
    return mpm_config_fail(ctx->cfg, key, "the radius must be a positive length (m)");
  return 0;
}

static int uses_field(const region_type *t, const char *field) {
  size_t n = strlen(field);
  for (const char *s = t->uses; (s = strstr(s, field)) != NULL; s += n)
    if ((s == t->uses || s[-1] == ' ') && (s[n] == ' ' || s[n] == '\0')) return 1;
  return 0;
}

/* A key the type ignores is almost always a typo in the type or a leftover: say so. */
static int check_unused(const mpm_config *cfg, const char *name, const region_type *t) {
  int rc = 0;
  char key[KEY_LEN];
  for (size_t f = 0; f < sizeof g_fields / sizeof g_fields[0]; ++f) {
    MPM_CALL(make_key(key, name, g_fields[f]));
    if (mpm_config_has(cfg, key) && !uses_field(t, g_fields[f]))
      rc = mpm_config_fail(cfg, key, "not used by a %s region (it reads: %s); remove it", t->name,
                           t->uses);
  }
  return rc;
}

/* ---------------------------------------------------------------------- primitives --- */

static int box_build(mpm_region *r, const build_ctx *ctx) {
  int rc = get_vec(ctx, "lo", ctx->dim, "the lower corner (one value per dimension, m)", r->lo);
  int rc_hi = get_vec(ctx, "hi", ctx->dim, "the upper corner (one value per dimension, m)", r->hi);
  if (rc || rc_hi) return rc ? rc : rc_hi;
  char key[KEY_LEN];
  MPM_CALL(make_key(key, ctx->name, "hi"));
  for (int d = 0; d < ctx->dim; ++d)
    if (!(r->lo[d] < r->hi[d]))
      rc = mpm_config_fail(ctx->cfg, key, "hi must be above lo in %c: %g <= %g", g_axis[d],
                           r->hi[d], r->lo[d]);
  return rc;
}

static int box_contains(const mpm_region *r, const double *x) {
  for (int d = 0; d < r->dim; ++d)
    if (x[d] < r->lo[d] || x[d] > r->hi[d]) return 0;
  return 1;
}

/* Disk or sphere. */
static int ball_build(mpm_region *r, const build_ctx *ctx) {
  int rc = get_vec(ctx, "center", ctx->dim, "the centre (one value per dimension, m)", r->c);
  int rc_r = get_radius(ctx, &r->radius);
  if (rc || rc_r) return rc ? rc : rc_r;
  for (int d = 0; d < ctx->dim; ++d) r->lo[d] = r->c[d] - r->radius, r->hi[d] = r->c[d] + r->radius;
  return 0;
}

static int ball_contains(const mpm_region *r, const double *x) {
  double q = 0.0;
  for (int d = 0; d < r->dim; ++d) q += (x[d] - r->c[d]) * (x[d] - r->c[d]);
  return q <= r->radius * r->radius;
}

/* The box of a cylinder: each end disk reaches radius * sin(angle of axis to e_d) along d. */
static void cylinder_bounds(mpm_region *r) {
  double len2 = 0.0;
  for (int d = 0; d < 3; ++d) len2 += r->axis[d] * r->axis[d];
  for (int d = 0; d < 3; ++d) {
    double ext = r->radius * sqrt(fmax(0.0, 1.0 - r->axis[d] * r->axis[d] / len2));
    double e = r->c[d] + r->axis[d];
    r->lo[d] = fmin(r->c[d], e) - ext, r->hi[d] = fmax(r->c[d], e) + ext;
  }
}

static int cylinder_build(mpm_region *r, const build_ctx *ctx) {
  double p1[3];
  int rc = get_vec(ctx, "p0", 3, "the centre of one end (x y z, m)", r->c);
  int rc1 = get_vec(ctx, "p1", 3, "the centre of the other end (x y z, m)", p1);
  int rc_r = get_radius(ctx, &r->radius);
  if (rc || rc1 || rc_r) return rc ? rc : rc1 ? rc1 : rc_r;
  for (int d = 0; d < 3; ++d) r->axis[d] = p1[d] - r->c[d];
  if (r->axis[0] == 0.0 && r->axis[1] == 0.0 && r->axis[2] == 0.0) {
    char key[KEY_LEN];
    MPM_CALL(make_key(key, ctx->name, "p1"));
    return mpm_config_fail(ctx->cfg, key, "p1 equals p0: the axis has no length");
  }
  cylinder_bounds(r);
  return 0;
}

/* Inside if the projection on the axis falls between the ends and the distance to the axis
 * is at most the radius; t stays unnormalised (t = s |a|^2) to avoid a square root. */
static int cylinder_contains(const mpm_region *r, const double *x) {
  double t = 0.0, q = 0.0, a2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    double y = x[d] - r->c[d];
    t += y * r->axis[d], q += y * y, a2 += r->axis[d] * r->axis[d];
  }
  return t >= 0.0 && t <= a2 && q - t * t / a2 <= r->radius * r->radius;
}

/* ------------------------------------------------------------------------- polygon --- */

/* One vertex line: "x y", "x,y" or "x, y"; returns 1 if it parsed. */
static int parse_vertex(const char *s, double *xy) {
  char *end;
  xy[0] = strtod(s, &end);
  if (end == s) return 0;
  s = end + strspn(end, " \t\r");
  if (*s == ',') ++s;
  xy[1] = strtod(s, &end);
  if (end == s) return 0;
  end += strspn(end, " \t\r\n");
  return *end == '\0' && isfinite(xy[0]) && isfinite(xy[1]);
}

/* Blank after removing the comment? */
static int is_blank(char *line) {
  char *hash = strchr(line, '#');
  if (hash) *hash = '\0';
  return line[strspn(line, " \t\r\n")] == '\0';
}

static int push_vertex(mpm_region *r, int *cap, const double *xy) {
  if (r->nv == *cap) {
    int ncap = *cap ? 2 * *cap : 16;
    double *v = realloc(r->v, (size_t)ncap * 2 * sizeof *v);
    if (!v) MPM_FAIL(MPM_ERR_MEMORY, "cannot grow the polygon to %d vertices", ncap);
    r->v = v, *cap = ncap;
  }
  r->v[2 * r->nv] = xy[0], r->v[2 * r->nv + 1] = xy[1];
  ++r->nv;
  return 0;
}

/* Read every line, reporting each bad one (up to a limit) as "file:line: ...": a user
 * fixing a hand-written file wants all of them at once. Every rank reads the (small) file,
 * which keeps this function free of communication. */
static int read_vertices(mpm_region *r, const build_ctx *ctx, const char *key, FILE *f,
                         const char *path) {
  char *line = NULL;
  size_t len = 0;
  int cap = 0, lineno = 0, bad = 0, rc = 0;
  while (rc == 0 && getline(&line, &len, f) != -1) {
    double xy[2];
    ++lineno;
    if (is_blank(line)) continue;
    if (!parse_vertex(line, xy)) {
      if (++bad <= MAX_BAD_LINES) {
        line[strcspn(line, "\r\n")] = '\0';
        mpm_config_fail(ctx->cfg, key, "%s:%d: expected a vertex \"x y\" or \"x,y\", got \"%s\"",
                        path, lineno, line);
      }
    } else if (r->nv == MAX_VERTICES) {
      rc = mpm_config_fail(ctx->cfg, key, "%s:%d: more than %d vertices; simplify the outline",
                           path, lineno, MAX_VERTICES);
    } else {
      rc = push_vertex(r, &cap, xy);
    }
  }
  free(line);
  if (rc) return rc;
  if (bad > MAX_BAD_LINES)
    mpm_config_fail(ctx->cfg, key, "%s: %d more bad lines not shown", path, bad - MAX_BAD_LINES);
  return bad ? MPM_ERR_INPUT : 0;
}

int mpm_polygon_check(const mpm_config *cfg, const char *key, const double *xy, int nv) {
  int i, j;
  if (nv < 3) return mpm_config_fail(cfg, key, "a polygon needs at least 3 vertices, got %d", nv);
  if (mpm_polygon_self_intersects(xy, nv, &i, &j))
    return mpm_config_fail(cfg, key,
                           "the outline crosses itself: edge %d (from vertex %d) meets edge %d; "
                           "list the vertices in order around the shape",
                           i + 1, i + 1, j + 1);
  if (mpm_polygon_area(xy, nv) == 0.0)
    return mpm_config_fail(cfg, key, "the vertices enclose no area (all collinear?)");
  return 0;
}

/* Drop an explicit closing vertex (common in exported outlines), then check the shape. */
static int check_polygon(mpm_region *r, const build_ctx *ctx, const char *key) {
  if (r->nv > 1 && r->v[0] == r->v[2 * r->nv - 2] && r->v[1] == r->v[2 * r->nv - 1]) --r->nv;
  MPM_CALL(mpm_polygon_check(ctx->cfg, key, r->v, r->nv));
  for (int i = 0; i < r->nv; ++i)
    for (int d = 0; d < 2; ++d) {
      r->lo[d] = i ? fmin(r->lo[d], r->v[2 * i + d]) : r->v[d];
      r->hi[d] = i ? fmax(r->hi[d], r->v[2 * i + d]) : r->v[d];
    }
  return 0;
}

static int polygon_extrusion(mpm_region *r, const build_ctx *ctx) {
  char key[KEY_LEN];
  double z[2];
  MPM_CALL(make_key(key, ctx->name, "z"));
  if (ctx->dim == 2) {
    if (mpm_config_has(ctx->cfg, key))
      return mpm_config_fail(ctx->cfg, key, "z (the extrusion range) is only used in 3-D");
    return 0;
  }
  MPM_CALL(get_vec(ctx, "z", 2, "the extrusion range in 3-D (z_lo z_hi, m)", z));
  if (!(z[0] < z[1])) return mpm_config_fail(ctx->cfg, key, "z_lo must be below z_hi");
  r->lo[2] = z[0], r->hi[2] = z[1];
  return 0;
}

static int polygon_build(mpm_region *r, const build_ctx *ctx) {
  char key[KEY_LEN];
  const char *path;
  MPM_CALL(make_key(key, ctx->name, "file"));
  if (!mpm_config_has(ctx->cfg, key)) return missing(ctx, "file", "a vertex file");
  MPM_CALL(polygon_extrusion(r, ctx));
  MPM_CALL(mpm_config_get_string(ctx->cfg, key, &path));
  FILE *f = fopen(path, "r");
  if (!f) return mpm_config_fail(ctx->cfg, key, "cannot open the vertex file %s", path);
  int rc = read_vertices(r, ctx, key, f, path);
  fclose(f);
  MPM_CALL(rc);
  return check_polygon(r, ctx, key);
}

/* Exactly on edge a-b? Exact only where the cross product is computed exactly (axis-aligned
 * edges, say); elsewhere a boundary point may land on either side, but always the same one. */
static int on_edge(const double *a, const double *b, double x, double y) {
  double cross = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
  return cross == 0.0 && x >= fmin(a[0], b[0]) && x <= fmax(a[0], b[0]) && y >= fmin(a[1], b[1]) &&
         y <= fmax(a[1], b[1]);
}

/* Even-odd rule: count edges crossing the ray from (x, y) towards +x. The half-open test
 * (a above y) != (b above y) counts a vertex on the ray once, not twice. */
static int polygon_contains(const mpm_region *r, const double *x) {
  if (r->dim == 3 && (x[2] < r->lo[2] || x[2] > r->hi[2])) return 0;
  int inside = 0;
  for (int i = 0, j = r->nv - 1; i < r->nv; j = i++) {
    const double *a = &r->v[2 * j], *b = &r->v[2 * i];
    if (on_edge(a, b, x[0], x[1])) return 1;
    if ((a[1] > x[1]) != (b[1] > x[1]) &&
        x[0] < a[0] + (x[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
      inside = !inside;
  }
  return inside;
}

/* ---------------------------------------------------------------------- composites --- */

static int is_instance(const mpm_config *cfg, const char *name) {
  const char *const *names;
  int count = 0;
  if (mpm_config_instances(cfg, "geometry", &names, &count)) return 0;
  for (int i = 0; i < count; ++i)
    if (strcmp(names[i], name) == 0) return 1;
  return 0;
}

/* "a -> b -> c -> a": the chain from the outermost region down to the repeated name. */
static void cycle_text(char *buf, size_t n, const chain *path, const char *again) {
  const char *names[64];
  int k = 0;
  for (const chain *c = path; c && k < 64; c = c->up) names[k++] = c->name;
  size_t used = 0;
  buf[0] = '\0';
  for (int i = k - 1; i >= 0 && used < n; --i)
    used += (size_t)snprintf(buf + used, n - used, "%s -> ", names[i]);
  if (used < n) snprintf(buf + used, n - used, "%s", again);
}

/* Check one name of `of` before building it: it must exist and must not close a cycle. */
static int check_child(const build_ctx *ctx, const char *key, const char *child) {
  if (!is_instance(ctx->cfg, child))
    return mpm_config_fail(ctx->cfg, key, "no region named '%s': define [geometry.%s]", child,
                           child);
  for (const chain *c = ctx->path; c; c = c->up)
    if (strcmp(c->name, child) == 0) {
      char text[512];
      cycle_text(text, sizeof text, ctx->path, child);
      return mpm_config_fail(ctx->cfg, key, "regions refer to each other in a cycle: %s", text);
    }
  return 0;
}

static int add_child(mpm_region *r, const build_ctx *ctx, const char *key, const char *child) {
  MPM_CALL(check_child(ctx, key, child));
  mpm_region **grown = realloc(r->child, (size_t)(r->nchild + 1) * sizeof *grown);
  if (!grown) MPM_FAIL(MPM_ERR_MEMORY, "cannot grow region %s", ctx->name);
  r->child = grown;
  r->child[r->nchild] = NULL;
  chain link = {child, ctx->path};
  MPM_CALL(build_region(&r->child[r->nchild], ctx->cfg, ctx->dim, child, &link));
  ++r->nchild;
  return 0;
}

/* Build each name of `of` (blank- or comma-separated) as a child. */
static int build_children(mpm_region *r, const build_ctx *ctx, const char *key) {
  const char *list;
  MPM_CALL(mpm_config_get_string(ctx->cfg, key, &list));
  for (const char *s = list + strspn(list, " \t,"); *s; s += strspn(s, " \t,")) {
    size_t n = strcspn(s, " \t,");
    char child[KEY_LEN];
    if (n >= sizeof child) return mpm_config_fail(ctx->cfg, key, "a name is too long");
    memcpy(child, s, n);
    child[n] = '\0';
    MPM_CALL(add_child(r, ctx, key, child));
    s += n;
  }
  return 0;
}

/* The bounding box of a union covers every child; a difference lies inside its first. */
static void composite_bounds(mpm_region *r, int nchild) {
  for (int d = 0; d < r->dim; ++d) {
    r->lo[d] = r->child[0]->lo[d], r->hi[d] = r->child[0]->hi[d];
    for (int i = 1; i < nchild; ++i)
      r->lo[d] = fmin(r->lo[d], r->child[i]->lo[d]), r->hi[d] = fmax(r->hi[d], r->child[i]->hi[d]);
  }
}

static int set_build(mpm_region *r, const build_ctx *ctx) {
  char key[KEY_LEN];
  int is_union = strcmp(r->type->name, "union") == 0, need = is_union ? 1 : 2;
  MPM_CALL(make_key(key, ctx->name, "of"));
  if (!mpm_config_has(ctx->cfg, key))
    return missing(ctx, "of", is_union ? "the regions to join" : "a region and those cut from it");
  MPM_CALL(build_children(r, ctx, key));
  if (r->nchild < need)
    return mpm_config_fail(ctx->cfg, key, "a %s needs at least %d region names, got %d",
                           r->type->name, need, r->nchild);
  composite_bounds(r, is_union ? r->nchild : 1);
  return 0;
}

static int union_contains(const mpm_region *r, const double *x) {
  for (int i = 0; i < r->nchild; ++i)
    if (mpm_region_contains(r->child[i], x)) return 1;
  return 0;
}

static int difference_contains(const mpm_region *r, const double *x) {
  if (!mpm_region_contains(r->child[0], x)) return 0;
  for (int i = 1; i < r->nchild; ++i)
    if (mpm_region_contains(r->child[i], x)) return 0;
  return 1;
}

/* ----------------------------------------------------------------- build / destroy --- */

static const region_type g_types[] = {
    {"box", "lo hi", 0, box_build, box_contains},
    {"disk", "center radius", 2, ball_build, ball_contains},
    {"sphere", "center radius", 3, ball_build, ball_contains},
    {"cylinder", "p0 p1 radius", 3, cylinder_build, cylinder_contains},
    {"polygon", "file z", 0, polygon_build, polygon_contains},
    {"union", "of", 0, set_build, union_contains},
    {"difference", "of", 0, set_build, difference_contains},
};

/* Look up the type of region name, checking that it exists in this dimension. */
static int find_type(const mpm_config *cfg, int dim, const char *name, const region_type **t) {
  char key[KEY_LEN];
  const char *text;
  MPM_CALL(make_key(key, name, "type"));
  if (!mpm_config_has(cfg, key))
    return mpm_config_fail(cfg, key, "%s: add `type = box|disk|...` to [geometry.%s]",
                           is_instance(cfg, name) ? "the region has no type" : "no such region",
                           name);
  MPM_CALL(mpm_config_get_string(cfg, key, &text));
  for (size_t k = 0; k < sizeof g_types / sizeof g_types[0]; ++k)
    if (strcmp(text, g_types[k].name) == 0) *t = &g_types[k];
  if (!*t) return mpm_config_fail(cfg, key, "unknown region type '%s'", text);
  if ((*t)->dim && (*t)->dim != dim)
    return mpm_config_fail(cfg, key, "a %s exists only in %d-D, this case is %d-D (use %s)", text,
                           (*t)->dim, dim, dim == 2 ? "disk or polygon" : "sphere or cylinder");
  return 0;
}

static int build_region(mpm_region **r, const mpm_config *cfg, int dim, const char *name,
                        const chain *path) {
  const region_type *t = NULL;
  MPM_CALL(find_type(cfg, dim, name, &t));
  int rc_unused = check_unused(cfg, name, t); /* then build anyway, to report everything */
  MPM_ALLOC(*r, 1);
  (*r)->type = t, (*r)->dim = dim;
  build_ctx ctx = {cfg, dim, name, t, path};
  int rc = t->build(*r, &ctx);
  if (rc == 0) rc = rc_unused;
  if (rc) mpm_region_destroy(r);
  return rc;
}

int mpm_region_from_config(mpm_region **r, const mpm_config *cfg, int dim, const char *name) {
  *r = NULL;
  if (dim != 2 && dim != 3) MPM_FAIL(MPM_ERR_INPUT, "regions exist in 2-D and 3-D, not %d-D", dim);
  chain root = {name, NULL};
  MPM_CALL(build_region(r, cfg, dim, name, &root));
  return 0;
}

void mpm_region_destroy(mpm_region **r) {
  if (!r || !*r) return;
  for (int i = 0; i < (*r)->nchild; ++i) mpm_region_destroy(&(*r)->child[i]);
  free((*r)->child);
  free((*r)->v);
  free(*r);
  *r = NULL;
}

int mpm_region_contains(const mpm_region *r, const double *x) {
  return r->type->contains(r, x);
}

void mpm_region_bounds(const mpm_region *r, double *lo, double *hi) {
  for (int d = 0; d < r->dim; ++d) lo[d] = r->lo[d], hi[d] = r->hi[d];
}

double mpm_region_volume(const mpm_region *r, double h, double max_points) {
  const int dim = r->dim;
  double w[MPM_MAX_DIM] = {1, 1, 1}, points;
  int64_t n[MPM_MAX_DIM] = {1, 1, 1};
  do { /* cells of exactly (hi - lo) / n, so that a box's volume comes out exact */
    points = 1.0;
    for (int d = 0; d < dim; ++d) {
      n[d] = (int64_t)fmax(1.0, ceil((r->hi[d] - r->lo[d]) / h - 1e-9));
      w[d] = (r->hi[d] - r->lo[d]) / (double)n[d];
      points *= (double)n[d];
    }
    h *= 1.25;
  } while (points > max_points);
  int64_t inside = 0;
  for (int64_t k = 0; k < n[2]; ++k)
    for (int64_t j = 0; j < n[1]; ++j)
      for (int64_t i = 0; i < n[0]; ++i) {
        const int64_t at[3] = {i, j, k};
        double x[3] = {0, 0, 0};
        for (int d = 0; d < dim; ++d) x[d] = r->lo[d] + ((double)at[d] + 0.5) * w[d];
        inside += mpm_region_contains(r, x);
      }
  double cell = 1.0;
  for (int d = 0; d < dim; ++d) cell *= w[d];
  return (double)inside * cell;
}

/* ------------------------------------------------------------------------- seeding --- */

/* The lattice has ncells[d] * ppc points along d; point L sits in cell L / ppc at
 * sub-position L % ppc. A rank visits the points of its own cells that can lie in the
 * region's bounding box: [l0[d], l0[d] + len[d]). */
typedef struct lattice {
  int dim, ppc;
  int64_t l0[MPM_MAX_DIM], len[MPM_MAX_DIM], stride[MPM_MAX_DIM];
  int64_t count; /* candidate points */
} lattice;

/* One lattice point's margin around the bounding box absorbs rounding in the conversion;
 * contains() has the last word, so visiting a few extra points is harmless. */
static void lattice_range(lattice *lt, const mpm_region *r, const mpm_grid *g, int ppc) {
  double h = g->dx / ppc;
  lt->dim = g->dim, lt->ppc = ppc, lt->count = 1;
  for (int d = 0; d < g->dim; ++d) {
    int64_t own0 = (int64_t)g->cell_split[d][g->coord[d]] * ppc;
    int64_t own1 = (int64_t)g->cell_split[d][g->coord[d] + 1] * ppc;
    /* Clamp in floating point: a far-away region must not overflow the conversion. */
    double a = floor((r->lo[d] - g->lo[d]) / h - 0.5) - 1.0;
    double b = ceil((r->hi[d] - g->lo[d]) / h - 0.5) + 2.0;
    int64_t l0 = (int64_t)fmin(fmax(a, (double)own0), (double)own1);
    int64_t l1 = (int64_t)fmin(fmax(b, (double)own0), (double)own1);
    lt->l0[d] = l0, lt->len[d] = l1 > l0 ? l1 - l0 : 0;
    lt->stride[d] = d ? lt->stride[d - 1] * (int64_t)g->ncells[d - 1] * ppc : 1;
    lt->count *= lt->len[d];
  }
}

/* Position and global lattice index of candidate k (x fastest). */
static int64_t lattice_point(const lattice *lt, const mpm_grid *g, int64_t k, double *x) {
  int64_t index = 0;
  for (int d = 0; d < lt->dim; ++d) {
    int64_t l = lt->l0[d] + k % lt->len[d];
    k /= lt->len[d];
    x[d] = g->lo[d] + ((double)(l / lt->ppc) + (l % lt->ppc + 0.5) / lt->ppc) * g->dx;
    index += l * lt->stride[d];
  }
  return index;
}

/* First pass: mark the candidates inside, so the output is allocated at its exact size
 * (the caller indexes x[d * n + i]) with one inside test per point. */
static int mark_inside(const mpm_region *r, const mpm_grid *g, const lattice *lt,
                       unsigned char *mark, int64_t *n) {
  double x[MPM_MAX_DIM];
  *n = 0;
  for (int64_t k = 0; k < lt->count; ++k) {
    lattice_point(lt, g, k, x);
    mark[k] = (unsigned char)mpm_region_contains(r, x);
    *n += mark[k];
  }
  if (*n > INT32_MAX)
    MPM_FAIL(MPM_ERR_INPUT,
             "%lld particles on one rank exceed the local index range; use more "
             "ranks or fewer particles per cell",
             (long long)*n);
  return 0;
}

static int alloc_output(int64_t count, int dim, double **x, mpm_gidx **id) {
  size_t n = (size_t)(count ? count : 1);
  *x = malloc(n * (size_t)dim * sizeof **x);
  *id = malloc(n * sizeof **id);
  if (*x && *id) return 0;
  free(*x), free(*id);
  *x = NULL, *id = NULL;
  MPM_FAIL(MPM_ERR_MEMORY, "cannot allocate %lld seeded particles", (long long)count);
}

/* Second pass: positions (component-major, capacity = count) and ids of marked points. */
static void fill_points(const mpm_grid *g, const lattice *lt, const unsigned char *mark,
                        mpm_gidx id_base, int64_t count, double *x, mpm_gidx *id) {
  double p[MPM_MAX_DIM];
  for (int64_t k = 0, i = 0; k < lt->count; ++k) {
    if (!mark[k]) continue;
    id[i] = id_base + lattice_point(lt, g, k, p);
    for (int d = 0; d < g->dim; ++d) x[d * count + i] = p[d];
    ++i;
  }
}

int mpm_region_seed(const mpm_region *r, const mpm_grid *grid, int ppc, mpm_gidx id_base,
                    mpm_lidx *n, double **x, mpm_gidx **id) {
  lattice lt;
  unsigned char *mark;
  int64_t count = 0;
  *n = 0, *x = NULL, *id = NULL;
  if (ppc < 1) MPM_FAIL(MPM_ERR_INPUT, "particles per cell must be at least 1, got %d", ppc);
  lattice_range(&lt, r, grid, ppc);
  MPM_ALLOC(mark, lt.count);
  int rc = mark_inside(r, grid, &lt, mark, &count);
  if (rc == 0) rc = alloc_output(count, grid->dim, x, id);
  if (rc == 0) fill_points(grid, &lt, mark, id_base, count, *x, *id);
  free(mark);
  MPM_CALL(rc);
  *n = (mpm_lidx)count;
  return 0;
}

mpm_gidx mpm_region_seed_span(const mpm_grid *grid, int ppc) {
  mpm_gidx span = 1;
  for (int d = 0; d < grid->dim; ++d) span *= (mpm_gidx)grid->ncells[d] * ppc;
  return span;
}
