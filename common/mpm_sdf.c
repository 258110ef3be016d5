/* Signed distances and normals of boxes, balls and (extruded) polygons (see mpm_sdf.h).
 *
 * Boxes and extrusions share one rule: a shape that is the intersection of k slabs, each
 * with a signed distance q_j along an outward unit direction u_j (mutually orthogonal), has
 * phi = |max(q, 0)| outside (the nearest point is on an edge or corner where the positive
 * q_j vanish) and phi = max_j q_j inside (the nearest face). A polygon's distance is the
 * smallest distance to its edges, its sign the even-odd crossing count. */
#define _POSIX_C_SOURCE 200809L
#include "mpm_sdf.h"

#include "mpm_error.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* phi and normal of the intersection of k orthogonal slabs (see the file comment). */
static double slabs(int k, const double *q, const double (*u)[3], int dim, double *normal) {
  double out2 = 0.0, qmax = -HUGE_VAL;
  int jmax = 0;
  for (int j = 0; j < k; ++j) {
    if (q[j] > 0) out2 += q[j] * q[j];
    if (q[j] > qmax) qmax = q[j], jmax = j;
  }
  const double phi = out2 > 0 ? sqrt(out2) : qmax;
  if (normal)
    for (int d = 0; d < dim; ++d) {
      normal[d] = out2 > 0 ? 0.0 : u[jmax][d];
      for (int j = 0; j < k && out2 > 0; ++j)
        if (q[j] > 0) normal[d] += q[j] / phi * u[j][d];
    }
  return phi;
}

void mpm_sdf_box(mpm_sdf *s, int dim, const double *lo, const double *hi) {
  memset(s, 0, sizeof *s);
  s->kind = MPM_SDF_BOX, s->dim = dim;
  for (int d = 0; d < dim; ++d) s->lo[d] = lo[d], s->hi[d] = hi[d];
}

void mpm_sdf_ball(mpm_sdf *s, int dim, const double *c, double r) {
  memset(s, 0, sizeof *s);
  s->kind = MPM_SDF_BALL, s->dim = dim, s->r = r;
  for (int d = 0; d < dim; ++d) s->c[d] = c[d], s->lo[d] = c[d] - r, s->hi[d] = c[d] + r;
}

double mpm_polygon_area(const double *xy, int nv) {
  double a = 0.0;
  for (int i = 0, j = nv - 1; i < nv; j = i++)
    a += xy[2 * j] * xy[2 * i + 1] - xy[2 * i] * xy[2 * j + 1];
  return 0.5 * a;
}

int mpm_sdf_polygon(mpm_sdf *s, int dim, const double *xy, int nv, const double *z) {
  memset(s, 0, sizeof *s);
  s->kind = MPM_SDF_POLYGON, s->dim = dim, s->nv = nv;
  MPM_ALLOC(s->v, 2 * (size_t)nv);
  memcpy(s->v, xy, sizeof *xy * 2 * (size_t)nv);
  s->orient = mpm_polygon_area(xy, nv) >= 0 ? 1.0 : -1.0;
  for (int i = 0; i < nv; ++i)
    for (int d = 0; d < 2; ++d) {
      s->lo[d] = i ? fmin(s->lo[d], xy[2 * i + d]) : xy[d];
      s->hi[d] = i ? fmax(s->hi[d], xy[2 * i + d]) : xy[d];
    }
  if (dim == 3) {
    s->extruded = z != NULL;
    s->lo[2] = z ? z[0] : -HUGE_VAL, s->hi[2] = z ? z[1] : HUGE_VAL;
  }
  return 0;
}

int mpm_sdf_wedge(mpm_sdf *s, int dim, const double *foot, double length, double angle_deg,
                  const double *z) {
  const double rise = length * tan(angle_deg * PI / 180.0);
  const double xy[6] = {foot[0], foot[1],          foot[0] + length,
                        foot[1], foot[0] + length, foot[1] + rise};
  return mpm_sdf_polygon(s, dim, xy, 3, z);
}

void mpm_sdf_free(mpm_sdf *s) {
  free(s->v);
  s->v = NULL;
  s->nv = 0;
}

/* Distance from (x, y) to the edges, the even-odd inside flag, and the outward normal.
 *
 * Where the nearest point lies inside an edge (not at a vertex), the normal is that edge's
 * outward normal, whatever the distance: the direction from the nearest point to x is the
 * same up to roundoff, but at a point on the edge, where that distance is itself roundoff
 * (a grid node on an edge through round coordinates: 5 * 0.02 against a vertex at y = 0.1),
 * it points anywhere, along the edge included. A slip wall with such a normal stopped the
 * flow along it at every node on the edge (uniform flow along a grid-aligned wall blew up). */
static double polygon2(const mpm_sdf *s, const double *x, double *n2) {
  double best = HUGE_VAL, cx = 0, cy = 0, ex = 0, ey = 0;
  int inside = 0, at_vertex = 0;
  for (int i = 0, j = s->nv - 1; i < s->nv; j = i++) {
    const double *a = &s->v[2 * j], *b = &s->v[2 * i];
    const double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy;
    double t = len2 > 0 ? ((x[0] - a[0]) * dx + (x[1] - a[1]) * dy) / len2 : 0.0;
    const int clamped = !(t > 0 && t < 1);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const double px = a[0] + t * dx, py = a[1] + t * dy;
    const double d2 = (x[0] - px) * (x[0] - px) + (x[1] - py) * (x[1] - py);
    if (d2 < best) best = d2, cx = px, cy = py, ex = dx, ey = dy, at_vertex = clamped;
    if ((a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (x[1] - a[1]) * dx / dy) inside = !inside;
  }
  const double dist = sqrt(best), sign = inside ? -1.0 : 1.0;
  if (dist > 0 && at_vertex) {
    n2[0] = sign * (x[0] - cx) / dist, n2[1] = sign * (x[1] - cy) / dist;
  } else { /* the edge's outward normal (right of the edge if counter-clockwise) */
    const double len = sqrt(ex * ex + ey * ey);
    n2[0] = s->orient * ey / len, n2[1] = -s->orient * ex / len;
  }
  return sign * dist;
}

double mpm_sdf_eval(const mpm_sdf *s, const double *x, double *normal) {
  double q[3], u[3][3] = {{0}}, n2[2];
  const int dim = s->dim;
  switch (s->kind) {
  case MPM_SDF_BOX:
    for (int d = 0; d < dim; ++d) {
      const double c = 0.5 * (s->lo[d] + s->hi[d]), h = 0.5 * (s->hi[d] - s->lo[d]);
      q[d] = fabs(x[d] - c) - h;
      u[d][d] = x[d] >= c ? 1.0 : -1.0;
    }
    return slabs(dim, q, (const double(*)[3])u, dim, normal);
  case MPM_SDF_BALL: {
    double r2 = 0.0;
    for (int d = 0; d < dim; ++d) r2 += (x[d] - s->c[d]) * (x[d] - s->c[d]);
    const double r = sqrt(r2);
    for (int d = 0; normal && d < dim; ++d) normal[d] = r > 0 ? (x[d] - s->c[d]) / r : d == 0;
    return r - s->r;
  }
  case MPM_SDF_POLYGON:
    q[0] = polygon2(s, x, n2);
    u[0][0] = n2[0], u[0][1] = n2[1];
    if (dim == 3 && s->extruded) {
      const double c = 0.5 * (s->lo[2] + s->hi[2]), h = 0.5 * (s->hi[2] - s->lo[2]);
      q[1] = fabs(x[2] - c) - h;
      u[1][2] = x[2] >= c ? 1.0 : -1.0;
    }
    return slabs(dim == 3 && s->extruded ? 2 : 1, q, (const double(*)[3])u, dim, normal);
  }
  return HUGE_VAL;
}

/* Orientation of c against the line a-b: +1, -1 or 0 (collinear). */
static int turn(const double *a, const double *b, const double *c) {
  const double t = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  return (t > 0) - (t < 0);
}

static int within(const double *a, const double *b, const double *c) {
  return c[0] >= fmin(a[0], b[0]) && c[0] <= fmax(a[0], b[0]) && c[1] >= fmin(a[1], b[1]) &&
         c[1] <= fmax(a[1], b[1]);
}

/* Do segments a-b and c-d share a point? */
static int segments_meet(const double *a, const double *b, const double *c, const double *d) {
  const int t1 = turn(a, b, c), t2 = turn(a, b, d), t3 = turn(c, d, a), t4 = turn(c, d, b);
  if (t1 * t2 < 0 && t3 * t4 < 0) return 1;
  return (t1 == 0 && within(a, b, c)) || (t2 == 0 && within(a, b, d)) ||
         (t3 == 0 && within(c, d, a)) || (t4 == 0 && within(c, d, b));
}

int mpm_polygon_self_intersects(const double *xy, int nv, int *ei, int *ej) {
  for (int i = 0; i < nv; ++i)
    for (int j = i + 2; j < nv; ++j) {
      if (i == 0 && j == nv - 1) continue; /* adjacent through the closing edge */
      const double *a = &xy[2 * i], *b = &xy[2 * ((i + 1) % nv)];
      const double *c = &xy[2 * j], *d = &xy[2 * ((j + 1) % nv)];
      if (segments_meet(a, b, c, d)) {
        *ei = i, *ej = j;
        return 1;
      }
    }
  return 0;
}

/* ---- aerofoil files ------------------------------------------------------------------------ */

typedef struct airfoil_reader {
  const char *path;
  int line;
  char *err;
  size_t errlen;
  double *xy;
  int nv, cap;
} airfoil_reader;

static int reader_fail(airfoil_reader *r, int code, const char *what) {
  snprintf(r->err, r->errlen, "%s:%d: %s", r->path, r->line, what);
  return code;
}

/* One row "x,y,surface"; 0 on success. */
static int parse_row(airfoil_reader *r, char *text) {
  char *end, *s = text;
  double p[2];
  for (int k = 0; k < 2; ++k) {
    p[k] = strtod(s, &end);
    if (end == s || !isfinite(p[k]))
      return reader_fail(r, MPM_ERR_INPUT, "expected a row x_over_c,y_over_c,surface");
    s = end + strspn(end, " \t");
    if (*s != ',') return reader_fail(r, MPM_ERR_INPUT, "expected ',' after a coordinate");
    s += 1 + strspn(s + 1, " \t");
  }
  s[strcspn(s, " \t\r\n")] = '\0';
  if (strcmp(s, "upper") && strcmp(s, "lower") && strcmp(s, "leading_edge"))
    return reader_fail(r, MPM_ERR_INPUT, "surface must be upper, lower or leading_edge");
  if (r->nv == r->cap) {
    r->cap = r->cap ? 2 * r->cap : 256;
    double *grown = realloc(r->xy, sizeof *grown * 2 * (size_t)r->cap);
    if (!grown) return reader_fail(r, MPM_ERR_MEMORY, "out of memory");
    r->xy = grown;
  }
  r->xy[2 * r->nv] = p[0], r->xy[2 * r->nv + 1] = p[1];
  ++r->nv;
  return 0;
}

static int read_rows(airfoil_reader *r, FILE *f) {
  char *line = NULL;
  size_t len = 0;
  int header = 0, rc = 0;
  while (!rc && getline(&line, &len, f) != -1) {
    ++r->line;
    char *hash = strchr(line, '#');
    if (hash) *hash = '\0';
    char *s = line + strspn(line, " \t\r\n");
    if (*s == '\0') continue;
    if (!header) {
      header = 1;
      if (strncmp(s, "x_over_c", 8) != 0)
        rc = reader_fail(r, MPM_ERR_INPUT, "expected the header x_over_c,y_over_c,surface");
      continue;
    }
    rc = parse_row(r, s);
  }
  free(line);
  return rc;
}

int mpm_airfoil_read(const char *path, double chord, const double *le, double angle_deg,
                     double **xy, int *nv, char *err, size_t errlen) {
  airfoil_reader r = {.path = path, .err = err, .errlen = errlen};
  *xy = NULL, *nv = 0;
  FILE *f = fopen(path, "r");
  if (!f) return reader_fail(&r, MPM_ERR_FILE, strerror(errno));
  int rc = read_rows(&r, f);
  fclose(f);
  if (!rc && r.nv > 1 && r.xy[0] == r.xy[2 * r.nv - 2] && r.xy[1] == r.xy[2 * r.nv - 1]) --r.nv;
  if (!rc && r.nv < 3) rc = reader_fail(&r, MPM_ERR_INPUT, "fewer than 3 outline points");
  if (rc) {
    free(r.xy);
    return rc;
  }
  const double a = angle_deg * PI / 180.0, ca = cos(a), sa = sin(a);
  for (int i = 0; i < r.nv; ++i) {
    const double x = chord * r.xy[2 * i], y = chord * r.xy[2 * i + 1];
    r.xy[2 * i] = le[0] + ca * x + sa * y;
    r.xy[2 * i + 1] = le[1] - sa * x + ca * y;
  }
  *xy = r.xy, *nv = r.nv;
  return 0;
}
