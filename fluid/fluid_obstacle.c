/* Static obstacles: their case keys, their nodes, the constraint and the force report (see
 * fluid_obstacle.h). */
#include "fluid_obstacle.h"

#include "fluid_eos.h"

#include "mpm_bc.h"
#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KEY_LEN 256

const mpm_key_spec fluid_obstacle_keys[] = {
    {"fluid.obstacle_band", MPM_KEY_REAL, "0.5", -2, 2, 0, 0, NULL,
     "obstacle nodes: those with signed distance phi < band * grid.dx (0.5 puts the effective "
     "wall on the surface; see docs/gas.md)",
     0, "dx"},
    {"obstacle.*.shape", MPM_KEY_ENUM, NULL, 0, 0, 0, 0, "box|circle|sphere|polygon|wedge|airfoil",
     "box (lo, hi), circle (2-D) or sphere (3-D) (center, radius), polygon (vertices), wedge "
     "(foot, length, angle), airfoil (file, chord, leading_edge, angle_of_attack)",
     0, NULL},
    {"obstacle.*.condition", MPM_KEY_ENUM, "slip", 0, 0, 0, 0, "slip|no_slip",
     "slip (no flow through the surface) or no_slip (the gas sticks)", 0, NULL},
    {"obstacle.*.lo", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "box: lower corner, m (one value per dimension)", 1, "m"},
    {"obstacle.*.hi", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "box: upper corner, m (one value per dimension)", 1, "m"},
    {"obstacle.*.center", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "circle, sphere: centre, m", 1, "m"},
    {"obstacle.*.radius", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "circle, sphere: radius, m, > 0", 1, "m"},
    {"obstacle.*.vertices", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 0, NULL,
     "polygon: x1 y1 x2 y2 ... (m), at least 3 vertices, closed implicitly, not self-crossing", 1,
     "m"},
    {"obstacle.*.z", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 2, NULL,
     "polygon, wedge, airfoil in 3-D: extrusion range z_lo z_hi, m (default: endless)", 1, "m"},
    {"obstacle.*.foot", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 2, NULL,
     "wedge: x y of the foot of the ramp (on a wall), m", 1, "m"},
    {"obstacle.*.length", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "wedge: length of the ramp along +x, m", 1, "m"},
    {"obstacle.*.angle", MPM_KEY_REAL, NULL, 0, 90, 1, 0, NULL,
     "wedge: ramp angle, degrees, in (0, 90]", 1, "deg"},
    {"obstacle.*.file", MPM_KEY_PATH, NULL, 0, 0, 0, 0, NULL,
     "airfoil: coordinate file (# comments, header x_over_c,y_over_c,surface, rows in order "
     "around the outline)",
     1, NULL},
    {"obstacle.*.chord", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL, "airfoil: chord, m", 1, "m"},
    {"obstacle.*.leading_edge", MPM_KEY_REALS, NULL, -HUGE_VAL, HUGE_VAL, 0, 2, NULL,
     "airfoil: x y of the leading edge, m", 1, "m"},
    {"obstacle.*.angle_of_attack", MPM_KEY_REAL, "0", -90, 90, 0, 0, NULL,
     "airfoil: angle of attack, degrees (positive: nose up for a flow along +x)", 0, "deg"},
    {"obstacle.*.reference_area", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "area for Cd and Cl: m^2 in 3-D, m (per unit span) in 2-D; needs reference_density and "
     "reference_speed",
     1, "m^2 (2-D: m)"},
    {"obstacle.*.reference_density", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "free-stream density for Cd and Cl, kg/m^3", 1, "kg/m^3"},
    {"obstacle.*.reference_speed", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "free-stream speed for Cd and Cl, m/s", 1, "m/s"},
    {"obstacle.*.flow_direction", MPM_KEY_REALS, "1 0 0", -HUGE_VAL, HUGE_VAL, 0, 3, NULL,
     "free-stream direction (drag along it; lift along e_z x it, +y for a flow along +x)", 0, "-"},
    {"obstacle.*.reference_pressure", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 0, 0, NULL,
     "free-stream pressure for Cp in surface_NAME.csv, Pa (with reference_area, _density and "
     "_speed)",
     1, "Pa"},
    {"obstacle.*.surface_interval", MPM_KEY_REAL, NULL, 0, HUGE_VAL, 1, 0, NULL,
     "2-D polygon, wedge, airfoil: write the surface pressure at the outline's vertices, averaged "
     "over windows of this length (s), to surface_NAME.csv",
     1, "s"},
};
const int fluid_obstacle_nkeys = (int)(sizeof fluid_obstacle_keys / sizeof fluid_obstacle_keys[0]);

/* The keys each shape reads; any other shape key set in the section is reported. */
static const char *const g_shapes[][2] = {
    {"box", "lo hi"},
    {"circle", "center radius"},
    {"sphere", "center radius"},
    {"polygon", "vertices z"},
    {"wedge", "foot length angle z"},
    {"airfoil", "file chord leading_edge angle_of_attack z"},
};
static const char *const g_shape_keys[] = {
    "lo",    "hi",   "center", "radius",       "vertices",       "z", "foot", "length",
    "angle", "file", "chord",  "leading_edge", "angle_of_attack"};

typedef struct reader {
  const mpm_config *cfg;
  const char *name;
  int dim;
  char shape_key[KEY_LEN];
} reader;

static void make_key(char *key, const reader *r, const char *field) {
  snprintf(key, KEY_LEN, "obstacle.%s.%s", r->name, field);
}

static int has(const reader *r, const char *field) {
  char key[KEY_LEN];
  make_key(key, r, field);
  return mpm_config_has(r->cfg, key);
}

/* Exactly n reals (n = 0: any even count >= 6, stored in *count) from a key that must be set. */
static int get_vec(const reader *r, const char *field, int n, double *v, int max, int *count) {
  char key[KEY_LEN];
  int got = 0;
  make_key(key, r, field);
  if (!mpm_config_has(r->cfg, key))
    return mpm_config_fail(r->cfg, r->shape_key, "this shape needs `%s = ...` in [obstacle.%s]",
                           field, r->name);
  MPM_CALL(mpm_config_get_reals(r->cfg, key, v, max, &got));
  if (n > 0 && got != n) return mpm_config_fail(r->cfg, key, "needs %d values, got %d", n, got);
  for (int i = 0; i < got; ++i)
    if (!isfinite(v[i])) return mpm_config_fail(r->cfg, key, "values must be finite");
  if (count) *count = got;
  return 0;
}

static int get_real(const reader *r, const char *field, double *v) {
  char key[KEY_LEN];
  make_key(key, r, field);
  if (!mpm_config_has(r->cfg, key))
    return mpm_config_fail(r->cfg, r->shape_key, "this shape needs `%s = ...` in [obstacle.%s]",
                           field, r->name);
  return mpm_config_get_real(r->cfg, key, v);
}

static int check_unused(const reader *r, const char *shape) {
  const char *uses = "";
  int rc = 0;
  for (size_t k = 0; k < sizeof g_shapes / sizeof g_shapes[0]; ++k)
    if (strcmp(g_shapes[k][0], shape) == 0) uses = g_shapes[k][1];
  for (size_t f = 0; f < sizeof g_shape_keys / sizeof g_shape_keys[0]; ++f) {
    const char *field = g_shape_keys[f], *s = uses;
    const size_t n = strlen(field);
    int used = 0;
    for (; (s = strstr(s, field)) != NULL && !used; s += n)
      used = (s == uses || s[-1] == ' ') && (s[n] == ' ' || s[n] == '\0');
    char key[KEY_LEN];
    make_key(key, r, field);
    if (!used && mpm_config_has(r->cfg, key))
      rc = mpm_config_fail(r->cfg, key, "not used by a %s (it reads: %s); remove it", shape, uses);
  }
  return rc;
}

/* The extrusion range of a 3-D polygon, or NULL (endless); z_lo < z_hi. */
static int get_z(const reader *r, double *z, const double **zp) {
  char key[KEY_LEN];
  make_key(key, r, "z");
  *zp = NULL;
  if (!mpm_config_has(r->cfg, key)) return 0;
  if (r->dim == 2) return mpm_config_fail(r->cfg, key, "z (the extrusion range) is 3-D only");
  MPM_CALL(get_vec(r, "z", 2, z, 2, NULL));
  if (!(z[0] < z[1])) return mpm_config_fail(r->cfg, key, "z_lo must be below z_hi");
  *zp = z;
  return 0;
}

/* A polygon must enclose an area and must not cross itself (the sign would be wrong). */
static int polygon_from(mpm_sdf *s, const reader *r, const char *key, const double *xy, int nv,
                        const double *z) {
  int i, j;
  if (nv < 3)
    return mpm_config_fail(r->cfg, key, "a polygon needs at least 3 vertices, got %d", nv);
  if (mpm_polygon_self_intersects(xy, nv, &i, &j))
    return mpm_config_fail(r->cfg, key,
                           "the outline crosses itself: edge %d (from vertex %d) meets edge %d; "
                           "list the vertices in order around the shape",
                           i + 1, i + 1, j + 1);
  if (mpm_polygon_area(xy, nv) == 0.0)
    return mpm_config_fail(r->cfg, key, "the vertices enclose no area (all collinear?)");
  return mpm_sdf_polygon(s, r->dim, xy, nv, z);
}

static int read_box(mpm_sdf *s, const reader *r) {
  double lo[3], hi[3];
  MPM_CALL(get_vec(r, "lo", r->dim, lo, 3, NULL));
  MPM_CALL(get_vec(r, "hi", r->dim, hi, 3, NULL));
  char key[KEY_LEN];
  make_key(key, r, "hi");
  for (int d = 0; d < r->dim; ++d)
    if (!(lo[d] < hi[d]))
      return mpm_config_fail(r->cfg, key, "hi must be above lo along axis %d: %g <= %g", d, hi[d],
                             lo[d]);
  mpm_sdf_box(s, r->dim, lo, hi);
  return 0;
}

static int read_ball(mpm_sdf *s, const reader *r, int dim_needed) {
  double c[3], radius;
  if (r->dim != dim_needed)
    return mpm_config_fail(r->cfg, r->shape_key, "this shape is %d-D only; use %s", dim_needed,
                           r->dim == 2 ? "circle" : "sphere");
  MPM_CALL(get_vec(r, "center", r->dim, c, 3, NULL));
  MPM_CALL(get_real(r, "radius", &radius));
  mpm_sdf_ball(s, r->dim, c, radius);
  return 0;
}

static int read_polygon(mpm_sdf *s, const reader *r) {
  double z[2], *xy;
  const double *zp;
  int count = 0;
  char key[KEY_LEN];
  make_key(key, r, "vertices");
  MPM_CALL(get_z(r, z, &zp));
  enum { MAX_VERTS = 4096 };
  MPM_ALLOC(xy, 2 * MAX_VERTS);
  int rc = get_vec(r, "vertices", 0, xy, 2 * MAX_VERTS, &count);
  if (!rc && count % 2)
    rc = mpm_config_fail(r->cfg, key, "needs x y pairs, got an odd count %d", count);
  if (!rc) rc = polygon_from(s, r, key, xy, count / 2, zp);
  free(xy);
  return rc;
}

static int read_wedge(mpm_sdf *s, const reader *r) {
  double foot[2], length, angle, z[2];
  const double *zp;
  MPM_CALL(get_z(r, z, &zp));
  MPM_CALL(get_vec(r, "foot", 2, foot, 2, NULL));
  MPM_CALL(get_real(r, "length", &length));
  MPM_CALL(get_real(r, "angle", &angle));
  if (!(angle < 90.0)) {
    char key[KEY_LEN];
    make_key(key, r, "angle");
    return mpm_config_fail(r->cfg, key, "the ramp angle must be below 90 degrees");
  }
  return mpm_sdf_wedge(s, r->dim, foot, length, angle, zp);
}

static int read_airfoil(mpm_sdf *s, const reader *r) {
  double chord, le[2], aoa, z[2], *xy = NULL;
  const double *zp;
  const char *path;
  char key[KEY_LEN], err[512];
  int nv = 0;
  MPM_CALL(get_z(r, z, &zp));
  MPM_CALL(get_real(r, "chord", &chord));
  MPM_CALL(get_vec(r, "leading_edge", 2, le, 2, NULL));
  make_key(key, r, "angle_of_attack");
  MPM_CALL(mpm_config_get_real(r->cfg, key, &aoa));
  make_key(key, r, "file");
  if (!mpm_config_has(r->cfg, key))
    return mpm_config_fail(r->cfg, r->shape_key, "an airfoil needs `file = ...` in [obstacle.%s]",
                           r->name);
  MPM_CALL(mpm_config_get_string(r->cfg, key, &path));
  int rc = mpm_airfoil_read(path, chord, le, aoa, &xy, &nv, err, sizeof err);
  if (rc == MPM_ERR_MEMORY) MPM_FAIL(rc, "%s", err);
  if (rc) return mpm_config_fail(r->cfg, key, "%s", err);
  rc = polygon_from(s, r, key, xy, nv, zp);
  free(xy);
  return rc;
}

static int read_shape(mpm_sdf *s, const reader *r, const char *shape) {
  if (!strcmp(shape, "box")) return read_box(s, r);
  if (!strcmp(shape, "circle")) return read_ball(s, r, 2);
  if (!strcmp(shape, "sphere")) return read_ball(s, r, 3);
  if (!strcmp(shape, "polygon")) return read_polygon(s, r);
  if (!strcmp(shape, "wedge")) return read_wedge(s, r);
  return read_airfoil(s, r);
}

/* Cd and Cl need all three reference values; the flow direction is a unit vector. */
static int read_reference(fluid_obstacle *ob, const reader *r) {
  char key[KEY_LEN];
  double area, rho, u, dir[3] = {0, 0, 0};
  int n;
  make_key(key, r, "flow_direction");
  MPM_CALL(mpm_config_get_reals(r->cfg, key, dir, 3, &n));
  const double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + (r->dim == 3 ? dir[2] * dir[2] : 0));
  const double lift_len = sqrt(dir[0] * dir[0] + dir[1] * dir[1]);
  if (!(lift_len > 1e-12 * len) || !isfinite(len))
    return mpm_config_fail(r->cfg, key,
                           "the flow direction needs a non-zero x-y part (lift is along e_z x it)");
  for (int d = 0; d < 3; ++d) ob->flow[d] = d < r->dim ? dir[d] / len : 0.0;
  ob->lift[0] = -dir[1] / lift_len, ob->lift[1] = dir[0] / lift_len, ob->lift[2] = 0.0;
  if (!has(r, "reference_area")) return 0;
  make_key(key, r, "reference_area");
  const char *need[] = {"reference_density", "reference_speed"};
  for (int k = 0; k < 2; ++k)
    if (!has(r, need[k]))
      return mpm_config_fail(r->cfg, key, "Cd and Cl also need %s in [obstacle.%s]", need[k],
                             r->name);
  MPM_CALL(mpm_config_get_real(r->cfg, key, &area));
  MPM_CALL(get_real(r, "reference_density", &rho));
  MPM_CALL(get_real(r, "reference_speed", &u));
  ob->has_ref = 1;
  ob->q_ref = 0.5 * rho * u * u;
  ob->q_ref_area = ob->q_ref * area;
  return 0;
}

/* surface_interval: the outline's vertices as surface pressure samples (fluid_surface.h). */
static int read_surface(fluid_obstacle *ob, const reader *r, const char *shape, const char *dir) {
  char key[KEY_LEN], path[4096];
  double interval, p_ref = 0.0, le[2] = {0, 0}, chord = 0.0, aoa = 0.0;
  if (!has(r, "surface_interval")) {
    if (!has(r, "reference_pressure")) return 0;
    make_key(key, r, "reference_pressure");
    return mpm_config_fail(r->cfg, key,
                           "reference_pressure is for Cp in the surface output: set "
                           "surface_interval in [obstacle.%s] too, or remove it",
                           r->name);
  }
  make_key(key, r, "surface_interval");
  MPM_CALL(mpm_config_get_real(r->cfg, key, &interval));
  if (r->dim != 2 || ob->sdf.kind != MPM_SDF_POLYGON)
    return mpm_config_fail(r->cfg, key,
                           "the surface output samples the vertices of a 2-D outline: it needs "
                           "shape = polygon, wedge or airfoil in a 2-D domain (this is %s, %d-D)",
                           shape, r->dim);
  const int cp = has(r, "reference_pressure");
  make_key(key, r, "reference_pressure");
  if (cp && !ob->has_ref)
    return mpm_config_fail(r->cfg, key,
                           "Cp also needs reference_area, reference_density and "
                           "reference_speed in [obstacle.%s]",
                           r->name);
  if (cp) MPM_CALL(get_real(r, "reference_pressure", &p_ref));
  if (!strcmp(shape, "airfoil")) {
    MPM_CALL(get_real(r, "chord", &chord));
    MPM_CALL(get_vec(r, "leading_edge", 2, le, 2, NULL));
    make_key(key, r, "angle_of_attack");
    MPM_CALL(mpm_config_get_real(r->cfg, key, &aoa));
  }
  snprintf(path, sizeof path, "%s/surface_%s.csv", dir, ob->name);
  return fluid_surface_build(&ob->surf, path, interval, ob->sdf.v, ob->sdf.nv, chord, le, aoa,
                             p_ref, cp ? ob->q_ref : 0.0);
}

/* The obstacle must reach into the domain. */
static int check_overlap(const fluid_obstacle *ob, const reader *r, const mpm_grid *g) {
  for (int d = 0; d < g->dim; ++d)
    if (ob->sdf.hi[d] <= g->lo[d] || ob->sdf.lo[d] >= g->hi[d])
      return mpm_config_fail(r->cfg, r->shape_key,
                             "the obstacle spans [%g, %g] along axis %d, outside the domain "
                             "[%g, %g]; move it or enlarge [domain]",
                             ob->sdf.lo[d], ob->sdf.hi[d], d, g->lo[d], g->hi[d]);
  return 0;
}

/* phi (and the normal) at x, nearest over the periodic images of x: a body near a periodic face
 * is also near the nodes beyond the opposite face. */
double fluid_obstacle_phi(const mpm_sdf *sdf, const mpm_grid *g, const double *x, double *normal) {
  double best = HUGE_VAL;
  const int nimg = g->dim == 2 ? 9 : 27;
  for (int k = 0; k < nimg; ++k) {
    double y[3] = {0, 0, 0}, n[3];
    int skip = 0;
    for (int d = 0, r = k; d < g->dim; ++d, r /= 3) {
      const int shift = r % 3 - 1;
      skip |= shift && !g->periodic[d];
      y[d] = x[d] + shift * (g->hi[d] - g->lo[d]);
    }
    if (skip) continue;
    const double phi = mpm_sdf_eval(sdf, y, normal ? n : NULL);
    if (phi < best) {
      best = phi;
      if (normal) memcpy(normal, n, sizeof n);
    }
  }
  return best;
}

/* The nodes with phi < band, their normals and whether this rank owns them. */
static int find_nodes(fluid_obstacle *ob, const mpm_grid *g, double band) {
  const int dim = g->dim;
  mpm_lidx n = 0;
  for (int pass = 0; pass < 2; ++pass) {
    n = 0;
    for (mpm_lidx l = 0; l < g->nnodes; ++l) {
      int gi[MPM_MAX_DIM];
      double x[3] = {0, 0, 0}, nrm[3];
      mpm_grid_node_global(g, l, gi);
      for (int d = 0; d < dim; ++d) x[d] = g->lo[d] + gi[d] * g->dx;
      if (!(fluid_obstacle_phi(&ob->sdf, g, x, nrm) < band)) continue;
      if (pass) {
        ob->node[n] = l;
        memcpy(ob->normal + (size_t)dim * n, nrm, sizeof *nrm * (size_t)dim);
        ob->owned[n] = (unsigned char)mpm_grid_node_is_owned(g, l);
      }
      ++n;
    }
    if (!pass) {
      MPM_ALLOC(ob->node, n);
      MPM_ALLOC(ob->normal, (size_t)dim * n);
      MPM_ALLOC(ob->owned, n);
    }
  }
  ob->count = n;
  return 0;
}

static int build_one(fluid_obstacle *ob, const mpm_config *cfg, const mpm_grid *g, const char *name,
                     double band, const char *dir) {
  reader r = {cfg, name, g->dim, ""};
  const char *shape, *cond;
  char key[KEY_LEN];
  snprintf(ob->name, sizeof ob->name, "%s", name);
  make_key(r.shape_key, &r, "shape");
  snprintf(ob->shape_key, sizeof ob->shape_key, "%s", r.shape_key);
  MPM_CALL(mpm_config_get_string(cfg, r.shape_key, &shape));
  make_key(key, &r, "condition");
  MPM_CALL(mpm_config_get_string(cfg, key, &cond));
  ob->no_slip = strcmp(cond, "no_slip") == 0;
  int rc = check_unused(&r, shape);
  int rc_shape = read_shape(&ob->sdf, &r, shape);
  MPM_CALL(rc_shape ? rc_shape : rc);
  MPM_CALL(read_reference(ob, &r));
  MPM_CALL(read_surface(ob, &r, shape, dir));
  MPM_CALL(check_overlap(ob, &r, g));
  return find_nodes(ob, g, band);
}

/* A particle in cell c reaches nodes c - 1 .. c + 2 at most: flag cells gi - 2 .. gi + 1. */
static void flag_near(fluid_obstacles *o, const mpm_grid *g, const int *gi) {
  const int dim = g->dim, span = 4;
  const int total = dim == 2 ? span * span : span * span * span;
  for (int k = 0; k < total; ++k) {
    int c[MPM_MAX_DIM], ok = 1;
    for (int d = 0, r = k; d < dim; ++d, r /= span) {
      c[d] = gi[d] - 2 + r % span;
      ok &= c[d] >= g->box_lo[d] && c[d] < g->box_lo[d] + g->box_n[d];
    }
    if (ok) o->near[mpm_grid_local_index(g, c)] = o->listed[mpm_grid_local_index(g, c)] = 1;
  }
}

/* ---- ghost pressure ------------------------------------------------------------------------ */

/* The stencil of a point x: first global node and weights (and derivatives, per cell) along
 * each axis. */
typedef struct stencil {
  int base[MPM_MAX_DIM], support;
  double w[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT], dw[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT];
} stencil;

static void stencil_at(stencil *st, const mpm_grid *g, const double *x, double lp) {
  st->support = mpm_shape_support(g->shape);
  for (int d = 0; d < g->dim; ++d)
    st->base[d] = mpm_shape_1d(g->shape, (x[d] - g->lo[d]) / g->dx, lp, st->w[d], st->dw[d]);
}

/* Stencil slot k (x fastest) as a box index, or -1 outside the box; w and grad S there. */
static mpm_lidx stencil_node(const stencil *st, const mpm_grid *g, int k, double *w, double *grad) {
  int gi[MPM_MAX_DIM] = {0}, kd[MPM_MAX_DIM] = {0};
  for (int d = 0; d < g->dim; ++d) {
    kd[d] = k % st->support, k /= st->support;
    gi[d] = st->base[d] + kd[d];
    if (gi[d] < g->box_lo[d] || gi[d] >= g->box_lo[d] + g->box_n[d]) return -1;
  }
  *w = 1.0;
  for (int d = 0; d < g->dim; ++d) *w *= st->w[d][kd[d]];
  for (int d = 0; grad && d < g->dim; ++d) {
    grad[d] = st->dw[d][kd[d]] / g->dx;
    for (int e = 0; e < g->dim; ++e)
      if (e != d) grad[d] *= st->w[e][kd[e]];
  }
  return mpm_grid_local_index(g, gi);
}

static int stencil_count(const stencil *st, int dim) {
  return dim == 2 ? st->support * st->support : st->support * st->support * st->support;
}

/* Does x lie inside the grid's domain along its closed (not periodic, not open) axes? */
static int inside_domain(const fluid_obstacles *o, const mpm_grid *g, const double *x) {
  int in = 1;
  for (int d = 0; d < g->dim; ++d)
    in &= g->periodic[d] ||
          ((o->open[d][0] || x[d] >= g->lo[d]) && (o->open[d][1] || x[d] < g->hi[d]));
  return in;
}

/* Add V grad S_i of every seeding-lattice point inside an obstacle, in the cells of the box, to
 * G (dim arrays of nnodes). A point beyond a periodic face is tested at its image; beyond an
 * open face the body continues; beyond a wall there is none (the wall's mirror rules act). */
static void ghost_sums(const fluid_obstacles *o, const mpm_grid *g, double *const *G) {
  const int dim = g->dim, ppc = o->ppc;
  const double V = pow(g->dx / ppc, dim);
  int npts = 1, n[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) n[d] = (g->box_n[d] - 1) * ppc, npts *= n[d];
  for (int k = 0; k < npts; ++k) {
    double x[3] = {0, 0, 0}, xw[3];
    for (int d = 0, r = k; d < dim; ++d, r /= n[d - 1]) {
      const int l = r % n[d];
      x[d] = g->lo[d] + (g->box_lo[d] + l / ppc + (l % ppc + 0.5) / ppc) * g->dx;
    }
    memcpy(xw, x, sizeof x);
    mpm_grid_wrap(g, xw);
    if (!inside_domain(o, g, xw) || !fluid_obstacles_inside(o, xw)) continue;
    stencil st;
    stencil_at(&st, g, x, o->lp);
    for (int s = 0; s < stencil_count(&st, dim); ++s) {
      double w, grad[MPM_MAX_DIM];
      const mpm_lidx l = stencil_node(&st, g, s, &w, grad);
      for (int d = 0; l >= 0 && d < dim; ++d) G[d][l] += V * grad[d];
    }
  }
}

/* The obstacle nearest to node gi (its ghost force is that obstacle's). */
static int nearest(const fluid_obstacles *o, const mpm_grid *g, const int *gi) {
  double x[3] = {0, 0, 0}, best = HUGE_VAL;
  int k_best = 0;
  for (int d = 0; d < g->dim; ++d) x[d] = g->lo[d] + gi[d] * g->dx;
  for (int k = 0; k < o->count; ++k) {
    const double phi = fluid_obstacle_phi(&o->ob[k].sdf, g, x, NULL);
    if (phi < best) best = phi, k_best = k;
  }
  return k_best;
}

/* The nodes with a ghost force: those whose G is not zero (a node deep inside has ghosts all
 * round, so its G cancels to roundoff; it never has gas mass either). The cells whose particles
 * reach one of them are flagged near. */
static int build_ghosts(fluid_obstacles *o, const mpm_grid *g) {
  const int dim = g->dim;
  double *G[MPM_MAX_DIM] = {NULL};
  int rc = 0;
  for (int d = 0; d < dim && !rc; ++d)
    if (!(G[d] = calloc((size_t)g->nnodes, sizeof *G[d]))) rc = MPM_ERR_MEMORY;
  if (!rc) ghost_sums(o, g, G);
  mpm_lidx count = 0;
  for (mpm_lidx l = 0; !rc && l < g->nnodes; ++l) {
    int any = 0;
    for (int d = 0; d < dim; ++d) any |= G[d][l] != 0.0;
    count += any;
  }
  o->gnode = rc ? NULL : malloc(sizeof *o->gnode * (size_t)(count + 1));
  o->G = rc ? NULL : malloc(sizeof *o->G * (size_t)(dim * count + 1));
  o->gowned = rc ? NULL : malloc((size_t)count + 1);
  o->gob = rc ? NULL : malloc(sizeof *o->gob * (size_t)(count + 1));
  o->near = rc ? NULL : calloc((size_t)g->nnodes, 1);
  o->listed = rc ? NULL : calloc((size_t)g->nnodes, 1);
  o->sm = rc ? NULL : malloc(sizeof *o->sm * 3 * (size_t)g->nnodes);
  o->q = rc ? NULL : calloc((size_t)g->nnodes, sizeof *o->q);
  o->own = rc ? NULL : malloc((size_t)g->nnodes);
  if (!rc &&
      !(o->gnode && o->G && o->gowned && o->gob && o->near && o->listed && o->sm && o->q && o->own))
    rc = MPM_ERR_MEMORY;
  for (mpm_lidx l = 0; !rc && l < g->nnodes; ++l)
    o->own[l] = (unsigned char)mpm_grid_node_is_owned(g, l);
  for (mpm_lidx l = 0; !rc && l < g->nnodes; ++l) {
    int any = 0, gi[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) any |= G[d][l] != 0.0;
    if (!any) continue;
    for (int d = 0; d < dim; ++d) o->G[(size_t)dim * o->gcount + d] = G[d][l];
    o->gowned[o->gcount] = (unsigned char)mpm_grid_node_is_owned(g, l);
    mpm_grid_node_global(g, l, gi);
    o->gob[o->gcount] = nearest(o, g, gi);
    o->gnode[o->gcount++] = l;
    flag_near(o, g, gi);
  }
  for (int d = 0; d < dim; ++d) free(G[d]);
  if (rc) MPM_FAIL(rc, "cannot allocate the obstacles' ghost nodes");
  return 0;
}

/* The owned nodes of the bodies' reach, each once: the constrained nodes of every obstacle
 * (the first that constrains a node owns it), then the ghost nodes of none. */
static int build_reach(fluid_obstacles *o, const mpm_grid *g) {
  int *mark;
  MPM_ALLOC(mark, g->nnodes);
  for (mpm_lidx l = 0; l < g->nnodes; ++l) mark[l] = -1;
  for (int k = 0; k < o->count; ++k)
    for (mpm_lidx j = 0; j < o->ob[k].count; ++j)
      if (o->ob[k].owned[j] && mark[o->ob[k].node[j]] < 0) mark[o->ob[k].node[j]] = k;
  for (mpm_lidx k = 0; k < o->gcount; ++k)
    if (o->gowned[k] && mark[o->gnode[k]] < 0) mark[o->gnode[k]] = o->gob[k];
  mpm_lidx n = 0;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) n += mark[l] >= 0;
  o->lnode = malloc(sizeof *o->lnode * (size_t)(n + 1));
  o->lob = malloc(sizeof *o->lob * (size_t)(n + 1));
  if (!o->lnode || !o->lob) {
    free(mark);
    MPM_FAIL_OOM((double)n * (sizeof *o->lnode + sizeof *o->lob));
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    if (mark[l] >= 0) o->lnode[o->lcount] = l, o->lob[o->lcount++] = mark[l];
  free(mark);
  return 0;
}

int fluid_obstacles_build(fluid_obstacles *o, const mpm_config *cfg, const mpm_grid *grid, int ppc,
                          const unsigned char (*open)[2]) {
  const char *const *names;
  const char *dir;
  int count;
  double band;
  memset(o, 0, sizeof *o);
  o->ppc = ppc, o->lp = 0.5 / ppc, o->hold = FLUID_OBSTACLE_HOLD;
  o->nlev = 1;
  memcpy(o->open, open, sizeof o->open);
  MPM_CALL(mpm_config_get_real(cfg, "fluid.obstacle_band", &band));
  o->band = band;
  MPM_CALL(mpm_config_get_string(cfg, "output.dir", &dir));
  snprintf(o->path, sizeof o->path, "%s/obstacles.csv", dir);
  MPM_CALL(mpm_config_instances(cfg, "obstacle", &names, &count));
  if (count == 0) return 0;
  MPM_ALLOC(o->ob, count);
  o->count = count;
  for (int k = 0; k < 2; ++k) MPM_ALLOC(o->f[k], (size_t)grid->dim * count);
  for (int k = 0; k < count; ++k)
    MPM_CALL(build_one(&o->ob[k], cfg, grid, names[k], band * grid->dx, dir));
  o->nsm = 2;
  for (int k = 0; k < count; ++k)
    if (o->ob[k].surf.n) o->nsm = 3;
  MPM_CALL(build_ghosts(o, grid));
  return build_reach(o, grid);
}

int fluid_obstacles_inside(const fluid_obstacles *o, const double *x) {
  return fluid_obstacles_which(o, x) >= 0;
}

int fluid_obstacles_which(const fluid_obstacles *o, const double *x) {
  for (int k = 0; k < o->count; ++k)
    if (mpm_sdf_eval(&o->ob[k].sdf, x, NULL) < 0.0) return k;
  return -1;
}

/* Inside the bounding box of the shape s? */
static int in_bounds(const mpm_sdf *s, int dim, const double *x) {
  int in = 1;
  for (int d = 0; d < dim; ++d) in &= x[d] > s->lo[d] && x[d] < s->hi[d];
  return in;
}

mpm_lidx fluid_obstacles_return(const fluid_obstacles *o, const mpm_grid *grid, mpm_particles *p,
                                int field_x) {
  const int dim = grid->dim;
  mpm_lidx moved = 0;
  double *x[MPM_MAX_DIM] = {NULL, NULL, NULL};
  for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, field_x, d);
  for (mpm_lidx i = 0; o->count > 0 && i < p->n; ++i) {
    double xp[MPM_MAX_DIM] = {0, 0, 0}, nrm[MPM_MAX_DIM] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[d][i];
    for (int k = 0; k < o->count; ++k) {
      const mpm_sdf *s = &o->ob[k].sdf;
      if (!in_bounds(s, dim, xp)) continue;
      const double phi = mpm_sdf_eval(s, xp, nrm);
      if (!(phi < 0.0)) continue;
      double xm[MPM_MAX_DIM] = {0, 0, 0};
      for (int d = 0; d < dim; ++d) xm[d] = xp[d] - 2.0 * phi * nrm[d];
      if (fluid_obstacles_which(o, xm) >= 0 || !inside_domain(o, grid, xm))
        for (int d = 0; d < dim; ++d) xm[d] = xp[d] - (phi - 1e-6 * grid->dx) * nrm[d];
      for (int d = 0; d < dim; ++d) x[d][i] = xm[d];
      ++moved;
      break;
    }
  }
  return moved;
}

/* The cell of particle i (positions x per component): the box index of its lower corner, or -1
 * outside the box. Its position into xp. */
static mpm_lidx cell_of(const mpm_grid *g, const double *const *x, mpm_lidx i, double *xp) {
  int gi[MPM_MAX_DIM] = {0}, in = 1;
  for (int d = 0; d < g->dim; ++d) {
    xp[d] = x[d][i];
    gi[d] = mpm_shape_floor((xp[d] - g->lo[d]) / g->dx);
    in &= gi[d] >= g->box_lo[d] && gi[d] < g->box_lo[d] + g->box_n[d];
  }
  return in ? mpm_grid_local_index(g, gi) : -1;
}

void fluid_obstacles_list_cells(fluid_obstacles *o, const mpm_grid *grid,
                                const unsigned char *flag) {
  for (mpm_lidx l = 0; o->listed && l < grid->nnodes; ++l) o->listed[l] |= flag[l] != 0;
}

const mpm_lidx *fluid_obstacles_listed(const fluid_obstacles *o, const double *x0, mpm_lidx n,
                                       mpm_lidx *count, const mpm_lidx **cells) {
  if (!o->list_x || o->list_x != x0 || o->list_n != n) return NULL;
  *count = o->nlist, *cells = o->list_cell;
  return o->list;
}

void fluid_obstacles_list_done(fluid_obstacles *o) {
  o->list_x = NULL;
}

/* Room for n entries in the list; 0 if there is none (the list is then not kept). */
static int list_reserve(fluid_obstacles *o, mpm_lidx n) {
  if (n <= o->list_cap) return 1;
  const mpm_lidx cap = n + n / 4 + 16;
  mpm_lidx *a = realloc(o->list, sizeof *a * (size_t)cap);
  if (a) o->list = a;
  mpm_lidx *b = a ? realloc(o->list_cell, sizeof *b * (size_t)cap) : NULL;
  if (b) o->list_cell = b;
  if (!(a && b)) return 0;
  o->list_cap = cap;
  return 1;
}

void fluid_obstacles_deposit(fluid_obstacles *o, const mpm_grid *grid, mpm_lidx n,
                             const double *const *x, const double *m, const double *V0,
                             const double *J, const double *vsig, const double *e, double gamma) {
  if (o->count == 0 || o->span) return; /* the span ghost reads the grid pressure's nodes */
  const int dim = grid->dim;
  double *sm = o->sm, *smp = o->sm + grid->nnodes, *smt = o->sm + 2 * (size_t)grid->nnodes;
  memset(sm, 0, sizeof *sm * (size_t)o->nsm * grid->nnodes);
  const int surf = o->nsm == 3; /* the surface output's thermodynamic pressure, without q */
  const int keep = list_reserve(o, n);
  o->nlist = 0, o->list_x = keep ? x[0] : NULL, o->list_n = n;
  for (mpm_lidx i = 0; i < n; ++i) {
    double xp[MPM_MAX_DIM];
    const mpm_lidx c = cell_of(grid, x, i, xp);
    if (c < 0 || !o->listed[c]) continue;
    if (keep) o->list[o->nlist] = i, o->list_cell[o->nlist++] = c;
    if (!o->near[c]) continue;
    double p = 0.0; /* p = -tr(V sigma) / (dim V) */
    for (int d = 0; d < dim; ++d) p -= vsig[(size_t)(d * dim + d) * n + i];
    p /= dim * V0[i] * J[i];
    const double pt = surf ? fluid_pressure(gamma, m[i] / (V0[i] * J[i]), e[i]) : 0.0;
    stencil st;
    stencil_at(&st, grid, xp, o->lp);
    for (int s = 0; s < stencil_count(&st, dim); ++s) {
      double w;
      const mpm_lidx l = stencil_node(&st, grid, s, &w, NULL);
      if (l < 0) continue;
      sm[l] += w * m[i], smp[l] += w * m[i] * p;
      if (surf) smt[l] += w * m[i] * pt;
    }
  }
}

int fluid_obstacles_begin(fluid_obstacles *o, mpm_grid *grid, int phase, double t, double h,
                          int record) {
  if (o->count == 0) return 0;
  const int dim = grid->dim;
  double *sm = o->sm, *smp = o->sm + grid->nnodes, *smt = o->sm + 2 * (size_t)grid->nnodes;
  double *fields[3] = {sm, smp, smt};
  if (!o->span) MPM_CALL(mpm_grid_halo_reverse(grid, fields, o->nsm)); /* else not deposited */
  double *rec = o->f[record ? mpm_rhs_records_begin(&o->rec, t, h) : o->rec.latest];
  if (record) memset(rec, 0, sizeof *rec * (size_t)dim * o->count);
  if (record && o->heat) memset(o->q, 0, sizeof *o->q * (size_t)grid->nnodes);
  for (int k = 0; record && !o->span && k < o->count; ++k)
    if (o->ob[k].surf.n) fluid_surface_sample(&o->ob[k].surf, grid, sm, smt, o->own);
  mpm_grid_phase *ph = &grid->phase[phase];
  for (mpm_lidx k = 0; !o->span && k < o->gcount; ++k) {
    const mpm_lidx l = o->gnode[k];
    if (!(sm[l] > 0.0)) continue;
    const double p = smp[l] / sm[l];
    double *f = rec + (size_t)dim * o->gob[k];
    for (int d = 0; d < dim; ++d) {
      ph->f_i[d][l] += p * o->G[(size_t)dim * k + d];
      if (record && o->gowned[k]) f[d] -= p * o->G[(size_t)dim * k + d];
    }
  }
  return 0;
}

/* Constrain one obstacle's nodes; adds this rank's owned share of the force to f. Nodes with
 * less mass than hold_below are held entirely (see the header). In the classic update the
 * velocity change is an impulse over the step (mpm_impulse.h). */
void fluid_obstacle_constrain(const mpm_lidx *node, const double *normal,
                              const unsigned char *owned, mpm_lidx count, int no_slip,
                              mpm_grid_phase *ph, int dim, double h, double hold_below, int coast,
                              double *f, double *q) {
  for (mpm_lidx k = 0; k < count; ++k) {
    const mpm_lidx l = node[k];
    const double m = ph->m_i[l];
    if (!(m > 0.0)) continue; /* empty: the nodal update left v = a = 0 */
    const double *n = normal + (size_t)dim * k;
    const int hold = no_slip || m < hold_below;
    double vn = 0.0, an = 0.0, v[MPM_MAX_DIM], a[MPM_MAX_DIM], force[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) vn += ph->v_i[d][l] * n[d], an += ph->a_i[d][l] * n[d];
    for (int d = 0; d < dim; ++d) {
      v[d] = hold ? 0.0 : ph->v_i[d][l] - vn * n[d];
      a[d] = hold ? 0.0 : ph->a_i[d][l] - an * n[d];
    }
    if (hold && coast && h > 0 && !no_slip) { /* v^n = v - h a, slip-projected */
      double v0n = 0.0;
      for (int d = 0; d < dim; ++d) v0n += (ph->v_i[d][l] - h * ph->a_i[d][l]) * n[d];
      for (int d = 0; d < dim; ++d) v[d] = ph->v_i[d][l] - h * ph->a_i[d][l] - v0n * n[d];
    }
    const double power = mpm_impulse_apply(ph, dim, l, v, a, h, force);
    if (q) q[l] += power;
    /* the force the gas exerts on the obstacle: minus the rate the obstacle gives the gas */
    for (int d = 0; (!owned || owned[k]) && d < dim; ++d) f[d] -= force[d];
  }
}

int fluid_obstacles_apply(fluid_obstacles *o, mpm_grid *grid, int phase, double h, int record) {
  if (o->count == 0) return 0;
  const int dim = grid->dim;
  const mpm_grid_phase *ph = &grid->phase[phase];
  double scratch[3], mmax = 0.0;
  for (int k = 0; k < o->count; ++k)
    for (mpm_lidx j = 0; j < o->ob[k].count; ++j)
      if (ph->m_i[o->ob[k].node[j]] > mmax) mmax = ph->m_i[o->ob[k].node[j]];
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, &mmax, 1, MPI_DOUBLE, MPI_MAX, grid->comm));
  for (mpm_lidx k = 0; record && k < o->lcount; ++k) { /* empty or light: the body took f_i */
    const mpm_lidx l = o->lnode[k];
    if ((!o->span && !(ph->m_i[l] > 0.0)) || ph->m_i[l] > ph->m_empty) continue;
    double *f = o->f[o->rec.latest] + (size_t)dim * o->lob[k];
    for (int d = 0; d < dim; ++d) f[d] += ph->f_i[d][l];
  }
  for (int k = 0; k < o->count; ++k) {
    double *f = record ? o->f[o->rec.latest] + (size_t)dim * k : scratch;
    const fluid_obstacle *ob = &o->ob[k];
    fluid_obstacle_constrain(ob->node, ob->normal, ob->owned, ob->count, ob->no_slip,
                             &grid->phase[phase], dim, h, o->hold * mmax, o->coast, f,
                             record && o->heat ? o->q : NULL);
  }
  return o->hier ? fluid_obstacles_apply_levels(o, phase, h, record) : 0;
}

void fluid_obstacles_book_heat(fluid_obstacles *o, const mpm_grid *g) {
  o->heat = 1;
  for (int k = 0; k < o->count; ++k) /* the heat reaches the constrained nodes too */
    for (mpm_lidx j = 0; j < o->ob[k].count; ++j) {
      int gi[MPM_MAX_DIM];
      mpm_grid_node_global(g, o->ob[k].node[j], gi);
      flag_near(o, g, gi);
    }
}

int fluid_obstacles_work(fluid_obstacles *o, mpm_grid *grid, int phase, double h) {
  if (o->count == 0 || !o->heat) return 0;
  const int dim = grid->dim;
  const mpm_grid_phase *ph = &grid->phase[phase];
  const double *sm = o->sm, *smp = o->sm + grid->nnodes;
  for (mpm_lidx k = 0; k < o->gcount; ++k) {
    const mpm_lidx l = o->gnode[k];
    if (!(sm[l] > 0.0)) continue;
    const double p = smp[l] / sm[l];
    for (int d = 0; d < dim; ++d)
      o->q[l] += p * o->G[(size_t)dim * k + d] * (ph->v_i[d][l] - 0.5 * h * ph->a_i[d][l]);
  }
  /* Per unit of nodal mass, from the owners: the ghost copies' sums are partial until the
   * forward exchange, and a mirrored pad node beyond a wall (owned by no rank) was constrained
   * before the wall copied its image into it. */
  for (mpm_lidx l = 0; l < grid->nnodes; ++l)
    o->q[l] = o->own[l] && ph->m_i[l] > 0.0 ? o->q[l] / ph->m_i[l] : 0.0;
  return mpm_grid_halo_forward(grid, &o->q, 1);
}

void fluid_obstacles_heat(const fluid_obstacles *o, const mpm_grid *grid, mpm_lidx n,
                          const double *const *x, const double *e, double h, double *power) {
  if (o->count == 0 || !o->heat) return;
  const int dim = grid->dim;
  mpm_lidx nl = n;
  const mpm_lidx *cells = NULL, *list = fluid_obstacles_listed(o, x[0], n, &nl, &cells);
  for (mpm_lidx k = 0; k < nl; ++k) {
    double xp[MPM_MAX_DIM];
    const mpm_lidx i = list ? list[k] : k, c = list ? cells[k] : cell_of(grid, x, i, xp);
    if (c < 0 || !o->near[c]) continue;
    for (int d = 0; list && d < dim; ++d) xp[d] = x[d][i];
    stencil st;
    stencil_at(&st, grid, xp, o->lp);
    double heat = 0.0;
    for (int s = 0; s < stencil_count(&st, dim); ++s) {
      double w;
      const mpm_lidx l = stencil_node(&st, grid, s, &w, NULL);
      if (l >= 0) heat -= w * o->q[l];
    }
    /* The step may cool a particle to half its internal energy, no further. */
    if (h > 0.0 && heat < -0.5 * e[i] / h - power[i]) heat = -0.5 * e[i] / h - power[i];
    power[i] += heat;
  }
}

static int open_csv(fluid_obstacles *o, const mpm_grid *g, double t0) {
  const char *names[] = {"t", "name", "Fx", "Fy", "Fz", "Cd", "Cl"};
  const char *cols[7];
  int n = 0;
  for (int c = 0; c < 7; ++c)
    if (c != 4 || g->dim == 3) cols[n++] = names[c];
  /* A run that starts after t = 0 is a restart: keep the rows up to its start. */
  return mpm_diag_open(&o->csv, g->comm, o->path, n, cols, t0 > 0, t0);
}

int fluid_obstacles_report(fluid_obstacles *o, const mpm_grid *grid, double t, double h) {
  if (o->count == 0) return 0;
  const int dim = grid->dim;
  if (!o->csv) MPM_CALL(open_csv(o, grid, t - h));
  const double *use = o->f[mpm_rhs_records_pick(&o->rec, t)];
  double *f;
  MPM_ALLOC(f, (size_t)dim * o->count);
  int rc = MPI_Allreduce(use, f, dim * o->count, MPI_DOUBLE, MPI_SUM, grid->comm), failed = 0;
  for (int k = 0; rc == MPI_SUCCESS && !failed && k < o->count; ++k) {
    const fluid_obstacle *ob = &o->ob[k];
    double row[6], drag = 0.0, lift = 0.0;
    int c = 0;
    row[c++] = t;
    for (int d = 0; d < dim; ++d) {
      row[c++] = f[dim * k + d];
      drag += f[dim * k + d] * ob->flow[d], lift += f[dim * k + d] * ob->lift[d];
    }
    row[c++] = ob->has_ref ? drag / ob->q_ref_area : NAN;
    row[c++] = ob->has_ref ? lift / ob->q_ref_area : NAN;
    failed = mpm_diag_row_label(o->csv, ob->name, row); /* explained, agreed on every rank */
  }
  free(f);
  MPM_CALL(failed);
  if (rc != MPI_SUCCESS) MPM_FAIL(MPM_ERR_MPI, "cannot report the obstacle forces");
  for (int k = 0; k < o->count; ++k) MPM_CALL(fluid_surface_step(&o->ob[k].surf, grid, t, h));
  return 0;
}

void fluid_obstacles_free(fluid_obstacles *o) {
  fluid_obstacles_levels_free(o); /* reads o->ob */
  for (int k = 0; k < o->count; ++k) {
    mpm_sdf_free(&o->ob[k].sdf);
    fluid_surface_free(&o->ob[k].surf);
    free(o->ob[k].node), free(o->ob[k].normal), free(o->ob[k].owned);
  }
  free(o->ob);
  free(o->f[0]), free(o->f[1]);
  free(o->gnode), free(o->G), free(o->gowned), free(o->gob), free(o->lnode), free(o->lob),
      free(o->near), free(o->listed), free(o->list), free(o->list_cell), free(o->sm), free(o->q),
      free(o->own);
  mpm_diag_close(&o->csv);
  memset(o, 0, sizeof *o);
}
