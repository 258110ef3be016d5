/* Surface pressure of an obstacle, sampled and averaged over time (see fluid_surface.h). */
#include "fluid_surface.h"

#include "mpm_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* x/c and the side of each point of an airfoil: the points before the leading edge (the least
 * x/c, the file's order: upper surface from the trailing edge, then lower) are upper. */
static void airfoil_frame(fluid_surface *s, double chord, const double *le, double angle_deg) {
  const double a = angle_deg * PI / 180.0, ca = cos(a), sa = sin(a);
  int lead = 0;
  for (int i = 0; i < s->n; ++i) {
    const double dx = s->x[2 * i] - le[0], dy = s->x[2 * i + 1] - le[1];
    s->coord[i] = (ca * dx - sa * dy) / chord;
    if (s->coord[i] < s->coord[lead]) lead = i;
  }
  for (int i = 0; i < s->n; ++i) s->side[i] = i <= lead ? 1 : 2;
}

int fluid_surface_build(fluid_surface *s, const char *path, double interval, const double *xy,
                        int n, double chord, const double *le, double angle_deg, double p_ref,
                        double q_ref) {
  memset(s, 0, sizeof *s);
  s->n = n, s->interval = interval, s->p_ref = p_ref, s->q_ref = q_ref, s->t_next = NAN;
  snprintf(s->path, sizeof s->path, "%s", path);
  MPM_ALLOC(s->x, 2 * (size_t)n);
  MPM_ALLOC(s->coord, (size_t)n);
  MPM_ALLOC(s->side, (size_t)n);
  MPM_ALLOC(s->sum, 2 * (size_t)n);
  MPM_ALLOC(s->acc, 2 * (size_t)n);
  memcpy(s->x, xy, sizeof *xy * 2 * (size_t)n);
  if (chord > 0.0) {
    airfoil_frame(s, chord, le, angle_deg);
    return 0;
  }
  for (int i = 0; i < n; ++i) {
    const double d = i ? hypot(xy[2 * i] - xy[2 * i - 2], xy[2 * i + 1] - xy[2 * i - 1]) : 0.0;
    s->coord[i] = i ? s->coord[i - 1] + d : 0.0;
  }
  return 0;
}

void fluid_surface_sample(fluid_surface *s, const mpm_grid *g, const double *sm, const double *smp,
                          const unsigned char *own) {
  memset(s->sum, 0, sizeof *s->sum * 2 * (size_t)s->n);
  for (int i = 0; i < s->n; ++i) fluid_surface_sample_point(s, i, g, sm, smp, own);
}

void fluid_surface_sample_point(fluid_surface *s, int i, const mpm_grid *g, const double *sm,
                                const double *smp, const unsigned char *own) {
  {
    double xi[2];
    int base[2];
    for (int d = 0; d < 2; ++d) {
      xi[d] = (s->x[2 * i + d] - g->lo[d]) / g->dx;
      base[d] = (int)floor(xi[d]);
      xi[d] -= base[d];
    }
    for (int k = 0; k < 4; ++k) {
      const int off[2] = {k & 1, k >> 1}, gi[2] = {base[0] + off[0], base[1] + off[1]};
      int in = 1;
      for (int d = 0; d < 2; ++d) in &= gi[d] >= g->box_lo[d] && gi[d] < g->box_lo[d] + g->box_n[d];
      if (!in) continue;
      const mpm_lidx l = mpm_grid_local_index(g, gi);
      if ((own && !own[l]) || !(sm[l] > 0.0)) continue;
      const double w = (off[0] ? xi[0] : 1.0 - xi[0]) * (off[1] ? xi[1] : 1.0 - xi[1]);
      s->sum[2 * i] += w * sm[l], s->sum[2 * i + 1] += w * smp[l];
    }
  }
}

static int write_window(fluid_surface *s, double t) {
  static const char *const label[] = {"outline", "upper", "lower"};
  for (int i = 0; i < s->n; ++i) {
    const double p = s->acc[2 * i + 1] > 0.0 ? s->acc[2 * i] / s->acc[2 * i + 1] : NAN;
    const double cp = s->q_ref > 0.0 ? (p - s->p_ref) / s->q_ref : NAN;
    const double row[] = {t, i, s->x[2 * i], s->x[2 * i + 1], s->coord[i], p, cp};
    MPM_CALL(mpm_diag_row_label(s->csv, label[s->side[i]], row)); /* explained, agreed */
  }
  memset(s->acc, 0, sizeof *s->acc * 2 * (size_t)s->n);
  return 0;
}

int fluid_surface_step(fluid_surface *s, const mpm_grid *g, double t, double h) {
  if (s->n == 0) return 0;
  if (!s->csv) { /* a run that starts after t = 0 is a restart: keep the rows up to its start */
    static const char *const cols[] = {"t", "side", "point", "x", "y", "coordinate", "p", "cp"};
    const double t0 = t - h;
    MPM_CALL(mpm_diag_open(&s->csv, g->comm, s->path, 8, cols, t0 > 0, t0));
    s->t_next = (floor(t0 / s->interval * (1 + 1e-12)) + 1.0) * s->interval;
  }
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, s->sum, 2 * s->n, MPI_DOUBLE, MPI_SUM, g->comm));
  for (int i = 0; i < s->n; ++i)
    if (s->sum[2 * i] > 0.0) {
      s->acc[2 * i] += h * s->sum[2 * i + 1] / s->sum[2 * i];
      s->acc[2 * i + 1] += h;
    }
  if (t < s->t_next * (1 - 1e-12)) return 0;
  MPM_CALL(write_window(s, t));
  while (s->t_next <= t * (1 + 1e-12)) s->t_next += s->interval;
  return 0;
}

void fluid_surface_free(fluid_surface *s) {
  free(s->x), free(s->coord), free(s->side), free(s->sum), free(s->acc);
  mpm_diag_close(&s->csv);
  memset(s, 0, sizeof *s);
}
