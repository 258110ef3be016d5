/* The pressure on an obstacle's surface, sampled at the points of its outline and averaged over
 * time: obstacle.NAME.surface_interval = T writes, every T of simulated time, one row per point
 * to surface_NAME.csv in the output directory (2-D polygon, wedge and airfoil shapes; the points
 * are the outline's vertices). Private to fluid/.
 *
 * Sample. The pressure at a point x_s is the thermodynamic pressure of the gas next to it (the
 * equation of state's p, without the artificial viscosity q, which the force on the body does
 * include: in a noisy wake q is positive wherever the gas compresses and would bias a mean
 * upwards): the mass-weighted nodal pressure p_i = sum_p S_ip m_p p_p / sum_p S_ip m_p that the
 * obstacles deposit beside the ghosts' pressure, read with the bilinear weights N_i(x_s) of the
 * four nodes around x_s, weighted by the nodal mass:
 *   p_s = sum_i N_i(x_s) m_i p_i / sum_i N_i(x_s) m_i.
 * The nodes inside the body carry no mass and drop out, so p_s is a mean over the gas particles
 * within about two cells of x_s on the gas side. It is taken from the recorded RHS of every
 * accepted step (the only one in the classic update), with the owned nodes of each rank, and
 * summed over the ranks: independent of the decomposition.
 *
 * Average. Each window [t_k, t_k + T) weights the steps by their length h; its row carries the
 * window's end time. A window after a restart starts at the restart time. A point with no gas
 * near it in the whole window gets NaN.
 *
 * Columns: t, side (upper or lower on an airfoil, from the file's order: the points before its
 * leading edge are upper; else outline), point, x, y, coordinate (x/c along the chord for an
 * airfoil, otherwise the arc length from the first vertex, m), p (Pa), cp = (p - p_ref) / q_ref
 * with the obstacle's reference density and speed and the free stream's pressure (NaN without a
 * reference). */
#ifndef FLUID_SURFACE_H
#define FLUID_SURFACE_H

#include "mpm_diag.h"
#include "mpm_grid.h"

typedef struct fluid_surface {
  int n;               /* sample points; 0: no surface output */
  double *x;           /* 2 per point */
  double *coord;       /* x/c or arc length */
  unsigned char *side; /* 0 outline, 1 upper, 2 lower */
  double interval;     /* T */
  double t_next;       /* end of the current window */
  double p_ref, q_ref; /* Cp = (p - p_ref) / q_ref; q_ref 0: no Cp */
  double *sum;         /* this step's local sums: N m and N m p per point (2 n) */
  double *acc;         /* the window's integrals of h p and h per point (2 n) */
  char path[4096];
  mpm_diag *csv;
} fluid_surface;

/* Sample points at the n vertices xy (pairs). chord > 0 marks an airfoil: le, angle_deg give its
 * frame for x/c and the leading edge splits upper from lower. */
int fluid_surface_build(fluid_surface *s, const char *path, double interval, const double *xy,
                        int n, double chord, const double *le, double angle_deg, double p_ref,
                        double q_ref);
/* The local sums of one RHS from the nodal m and m p (sm, smp: the thermodynamic p) of the
 * owned nodes (own). */
void fluid_surface_sample(fluid_surface *s, const mpm_grid *g, const double *sm, const double *smp,
                          const unsigned char *own);
/* Add point i's share of g's nodes to its sums (own NULL: all owned), without zeroing them. */
void fluid_surface_sample_point(fluid_surface *s, int i, const mpm_grid *g, const double *sm,
                                const double *smp, const unsigned char *own);
/* After an accepted step from t - h to t: reduce the sums, add them to the window and write the
 * window when t reaches its end. Collective. */
int fluid_surface_step(fluid_surface *s, const mpm_grid *g, double t, double h);
void fluid_surface_free(fluid_surface *s);

#endif
