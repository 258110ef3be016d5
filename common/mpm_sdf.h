/* Signed distance to static rigid shapes, for obstacles on the grid.
 *
 * phi(x) is the exact Euclidean distance to the surface, negative inside; the normal is the
 * outward unit vector at the nearest surface point (the gradient of phi where it exists; on
 * the surface itself the outward normal of the face, edge or side there). Shapes:
 *   box      (2-D/3-D): axis-aligned, lo < hi;
 *   ball     (2-D circle, 3-D sphere): centre, radius > 0;
 *   polygon  (2-D: a closed list of vertices, either orientation; in 3-D extruded along z,
 *            between z[0] and z[1] or without end if no range is given).
 * A wedge (a ramp on a wall) and an aerofoil are polygons built by the helpers below.
 * Invariant: lo/hi hold the shape's bounding box (infinite along an endless extrusion). */
#ifndef MPM_SDF_H
#define MPM_SDF_H

#include <stddef.h>

typedef enum { MPM_SDF_BOX, MPM_SDF_BALL, MPM_SDF_POLYGON } mpm_sdf_kind;

typedef struct mpm_sdf {
  mpm_sdf_kind kind;
  int dim;
  double lo[3], hi[3]; /* bounding box (the box itself for a box) */
  double c[3], r;      /* ball */
  int nv;
  double *v;     /* polygon vertices (x, y) pairs, no repeated closing vertex */
  double orient; /* +1 counter-clockwise, -1 clockwise */
  int extruded;  /* 3-D polygon with a finite z range lo[2]..hi[2] */
} mpm_sdf;

void mpm_sdf_box(mpm_sdf *s, int dim, const double *lo, const double *hi);
void mpm_sdf_ball(mpm_sdf *s, int dim, const double *c, double r);
/* Copies nv >= 3 vertices xy (pairs); z = {z_lo, z_hi} or NULL (3-D: endless along z). */
int mpm_sdf_polygon(mpm_sdf *s, int dim, const double *xy, int nv, const double *z);
/* A ramp on a wall: the triangle (foot), (foot + length e_x), (foot + length (1, tan angle)),
 * angle in degrees in (0, 90). The ramp rises along +x from the foot. */
int mpm_sdf_wedge(mpm_sdf *s, int dim, const double *foot, double length, double angle_deg,
                  const double *z);
void mpm_sdf_free(mpm_sdf *s);

/* phi(x); normal (dim components) if not NULL. */
double mpm_sdf_eval(const mpm_sdf *s, const double *x, double *normal);

/* Signed area of a polygon (positive counter-clockwise). */
double mpm_polygon_area(const double *xy, int nv);
/* 1 if two non-adjacent edges of the closed polygon touch or cross (edges i and j set). */
int mpm_polygon_self_intersects(const double *xy, int nv, int *i, int *j);

/* Read an aerofoil outline in the format of rae2822_coordinates.csv: '#' comments, a header
 * line x_over_c,y_over_c,surface, then rows x/c,y/c,upper|lower|leading_edge in order around
 * the outline. Scales by chord, rotates by angle_of_attack (degrees; positive lifts the nose
 * of a section facing -x, i.e. turns it clockwise) about the leading edge (x/c = y/c = 0),
 * and moves that point to le. *xy (malloc'ed pairs) and *nv receive the vertices, a repeated
 * closing vertex dropped. On a bad file returns MPM_ERR_INPUT or MPM_ERR_FILE and writes
 * "path:line: what" into err. */
int mpm_airfoil_read(const char *path, double chord, const double *le, double angle_deg,
                     double **xy, int *nv, char *err, size_t errlen);

#endif
