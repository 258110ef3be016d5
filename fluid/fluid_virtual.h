/* Virtual gas particles: points that carry only a pressure, standing in for gas (or a body's
 * reaction) the particle set lacks next to a boundary. They are rebuilt at every RHS: the
 * open faces continue the particle columns beyond the face (fluid_boundary.c), the obstacles
 * mirror the particles near their surface (fluid_obstacle.c). Their stress -p I (times their
 * volume) is deposited like a particle's into a grid phase of their own, and the nodal forces
 * are added to the gas's after the reverse halo exchange. They have no mass or momentum, and
 * the forces of one point sum to zero over the nodes (the gradients of a partition of unity
 * do), so they move no momentum into or out of the gas: they shape where the pressure acts.
 * Private to fluid/. */
#ifndef FLUID_VIRTUAL_H
#define FLUID_VIRTUAL_H

#include "mpm_grid.h"

typedef struct fluid_virtual {
  int phase;       /* grid phase of their forces; -1: unused (no boundary needs them) */
  mpm_lidx n, cap; /* points in use and room */
  double *x;       /* positions, 3 per point */
  double *Vp;      /* volume times pressure, per point */
  double *work;    /* deposit scratch: component-major x, V sigma, zero m and v */
  mpm_lidx work_cap;
} fluid_virtual;

/* Give the points a grid phase (at build, on every rank, when a boundary may use them). */
int fluid_virtual_init(fluid_virtual *v, mpm_grid *grid);
/* Empty the set (at the start of every RHS). */
static inline void fluid_virtual_clear(fluid_virtual *v) {
  v->n = 0;
}
/* Append a point at x (dim components) of volume V at pressure p. */
int fluid_virtual_add(fluid_virtual *v, int dim, const double *x, double V, double p);
/* Deposit the points' stress into their phase (nothing if unused). */
int fluid_virtual_deposit(fluid_virtual *v, mpm_grid *grid, double lp);
/* After the gas's reverse halo: sum the points' forces over the ranks (into their phase's f) and
 * add them to f of the gas phase, except at the nodes skip[0 .. nskip) (box indices; NULL: none).
 * Collective: every rank calls it when any rank may have points. */
int fluid_virtual_forces(fluid_virtual *v, mpm_grid *grid, int gas_phase, const mpm_lidx *skip,
                         mpm_lidx nskip);
void fluid_virtual_free(fluid_virtual *v);

#endif
