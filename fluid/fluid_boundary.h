/* Open faces of the gas: supersonic inflow and outflow, characteristic subsonic inflow and
 * outflow, and a non-reflecting far field (the [boundary] kinds inflow, outflow,
 * subsonic_inflow, subsonic_outflow, farfield), with the free-stream state of [freestream].
 * Private to fluid/; see fluid_boundary.c for the method. */
#ifndef FLUID_BOUNDARY_H
#define FLUID_BOUNDARY_H

#include "mpm_bc.h"
#include "mpm_config.h"
#include "mpm_module.h"

#include "fluid_virtual.h"

extern const mpm_key_spec fluid_boundary_keys[];
extern const int fluid_boundary_nkeys;

typedef struct fluid_open fluid_open;

/* Build the open faces of walls on the module's grid (NULL *open if there is none); marks
 * them in m->open. The gas constants come from gamma; ppc is the seeding lattice. */
int fluid_open_new(fluid_open **open, mpm_module *m, const mpm_config *cfg, const mpm_walls *walls,
                   double gamma, int ppc);
void fluid_open_destroy(fluid_open **open);

/* In P2G: the virtual particles beyond the faces that continue the particle columns (all
 * but inflow), appended to virt. y is the module's state. */
int fluid_open_p2g(fluid_open *open, mpm_module *m, const double *y, fluid_virtual *virt);
/* Does a face continue the particle columns (so the module needs virtual particles)? */
int fluid_open_uses_virtual(const fluid_open *open);
/* freestream.exterior = gauge: add the gauge points' forces (deposited by fluid_open_p2g) at
 * the nodes whose stencil crosses a face, after the gas's reverse halo. Collective. */
int fluid_open_gauge_forces(fluid_open *open, mpm_module *m);
/* Before the nodal update (first pass only) at time t: add the force of the exterior
 * lattice of the inflow faces to the nodal forces. */
int fluid_open_forces(fluid_open *open, mpm_module *m, double t);
/* The grid pressure's boundary term of the open faces (fluid.pressure = grid, in place of the
 * exterior lattice and the copies): F[d][i] -= integral over each face this rank owns of N_i
 * p_b n_d, p_b the face's boundary pressure from the nodal pressure P and velocity v (box
 * arrays of g, level 0's, ghosts filled). The caller sums the ghosts into their owners. */
int fluid_open_grid_forces(fluid_open *open, const mpm_grid *g, const double *P,
                           const double *const *v, double *const *F);
/* The grid pressure's nodal pressure P (level 0's box array) on and beyond the open faces, as
 * fluid_open_hold sets the velocity there: the free stream's at an inflow face, extrapolated
 * linearly from the face node beyond the others. */
void fluid_open_grid_pressure(const fluid_open *open, double *P);
/* After the nodal update: hold the nodes on and beyond an inflow face at the free-stream
 * velocity; beyond the other open faces, extrapolate the face node linearly. */
void fluid_open_hold(const fluid_open *open, mpm_module *m);
/* freestream.sponge: add the absorbing layer's rates to ydot (the state's rates at y, in any
 * form of the step) for the particles within its thickness of a farfield face. Local. */
void fluid_open_sponge(const fluid_open *open, const mpm_module *m, const double *y, double *ydot);
/* Between steps (the boundary op): remove particles that left through an open face and inject
 * the free-stream layers that entered during the step h that ended at t, as an edit deferred
 * to the migration that follows. Local. */
int fluid_open_exchange(fluid_open *open, mpm_module *m, double t, double h, int *changed);

/* Between steps: a gas particle that ended a step beyond a wall face (by less than the
 * module's wall_slack, which the stage checks allow) is mirrored back inside across that
 * face. Only its position changes: mass, momentum and energy stay. A particle pressed into a
 * wall corner (a stagnation corner at a body's foot) would otherwise fail the step check and
 * make every later step retry at a fraction of its size. */
void fluid_walls_return(mpm_module *m);

#endif
