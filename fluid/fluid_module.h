/* The gas MPM module: compressible ideal gas as particles on the shared grid.
 *
 * State fields: x (dim), v (dim), J = V / V0 (1), e, the specific internal energy (1), and C
 * (dim*dim), the APIC affine velocity, when transfer.velocity = apic. Other fields: m (mass),
 * V0 (reference volume), divv (tr D of the last RHS evaluation), D (dim*dim, the strain rate of
 * the last RHS, only with viscosity), and the output fields rho, p, mach, T and s (density,
 * pressure, Mach number, temperature and specific entropy), refreshed before every snapshot
 * and checkpoint. */
#ifndef FLUID_MODULE_H
#define FLUID_MODULE_H

#include "mpm_config.h"
#include "mpm_module.h"

/* Add the keys of the [fluid] and [gas.NAME] sections to cfg. */
int fluid_add_schema(mpm_config *cfg);

/* Build the module over grid with its own phase of nodal fields. With seed = 1 the gas
 * regions are seeded; with seed = 0 the particle set starts empty (a restart fills it). *m
 * is NULL if the case has no [gas.*] section. Collective. */
int fluid_module_create(mpm_module **m, const mpm_config *cfg, mpm_grid *grid, int seed);

struct mpm_hier;

/* Put the module's phase on the refinement hierarchy h (mpm_hier.h, built over its grid after
 * the modules; NULL: refined, but no region yet): refuse, naming the key, every gas setting the
 * finer levels do not carry (docs/refinement.md), then with seed = 1 reseed the finer regions at
 * their levels' spacing. From then on the particles follow the levels (fluid_relevel.c).
 * Collective. */
int fluid_module_refine(mpm_module *m, const mpm_config *cfg, struct mpm_hier *h, int seed);

/* 1 if the gas reads a solid's particles (mpm_module.h, beside): its grid pressure beside a
 * solid (fluid/fluid_gridp_solid.c); else 0. */
int fluid_module_reads_beside(const mpm_module *m);

/* 1 if the gas's forces on the nodes where it has no mass belong to the solid there (the hybrid
 * pressure beside a solid, fluid/fluid_gridp_solid.c): the coupler hands them over. */
int fluid_module_hands_over(const mpm_module *m);

/* A regrid: move the module onto the new hierarchy h (may be NULL); fluid_module_follow then
 * moves the particles onto its levels. */
void fluid_module_rehier(mpm_module *m, struct mpm_hier *h);

/* Split and merge the particles onto the levels of the module's hierarchy, as after every step
 * (fluid_relevel.c); *changed is set when the set changed. Collective. */
int fluid_module_follow(mpm_module *m, int *changed);

/* A regrid's criterion (one of the list refine.criterion). */
typedef enum {
  FLUID_REFINE_DENSITY,
  FLUID_REFINE_COMPRESSION,
  FLUID_REFINE_VORTICITY,
  FLUID_REFINE_STARVATION,
  FLUID_REFINE_PROXIMITY
} fluid_refine_criterion;

/* The refinement flags over the level-0 spans (node-centred cells) of the global lattice, x
 * fastest, n[d] spans per axis (ncells along a periodic axis, ncells + 1 otherwise), from the
 * gas binned by each particle's nearest node: a span is flagged, with its axis neighbour, where
 * across the face between them the density changes by more than threshold times the smaller
 * (density), the normal velocity falls by more than threshold times the smaller sound speed
 * (compression: shocks and steepening waves), or a tangential velocity jumps by more than that
 * (vorticity: shear layers, h |omega| > threshold c); or a span holding fewer than threshold
 * level-0 particles (starvation: a particle of size level l counts 2^(-dim l)) whose 2 dim axis
 * neighbours all hold gas (not the gas's edge); or a span that comes within threshold (a length,
 * >= 0) of an obstacle (proximity: its centre's signed distance to the nearest obstacle, over the
 * periodic images, below threshold plus the span's half-diagonal; the obstacles are static, so
 * no padding for their motion). flag has prod n[d] bytes. One rank. */
int fluid_refine_flags(const mpm_module *m, fluid_refine_criterion criterion, double threshold,
                       const int *n, unsigned char *flag);

#endif
