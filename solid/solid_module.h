/* The solid MPM module: bodies seeded from case-file geometry, each with its own material
 * model, integrated as x, v and F on the particles, held by walls, clamps and rigid bodies
 * (material rigid: a prescribed constant velocity, holding the grid nodes inside the body),
 * and loaded by surface tractions ([traction.NAME]).
 *
 * State fields: x (dim), v (dim), F (dim*dim), and sigma (dim*dim) when a body's model is in
 * rate form. Other fields: m (mass), V0 (reference volume), body (index of the [solid.NAME]
 * section the particle came from), hist when a body's model has history variables, fixed
 * (1 inside a clamp) when the case has clamps, and fext (dim: the constant external force
 * of a particle tagged by a traction, N) when the case has tractions. */
#ifndef SOLID_MODULE_H
#define SOLID_MODULE_H

#include "mpm_config.h"
#include "mpm_module.h"

/* Add the keys of [solid.NAME] sections (material names from the registry) to cfg. */
int solid_add_schema(mpm_config *cfg);

/* Build the module over grid with its own phase of nodal fields. With seed = 1 the bodies
 * are seeded from their geometry; with seed = 0 the particle set starts empty (a restart
 * fills it). *m is NULL if the case has no [solid.*] section. Collective. */
int solid_module_create(mpm_module **m, const mpm_config *cfg, mpm_grid *grid, int seed);

struct mpm_hier;

/* The solid on the static refinement hierarchy h (solid_refine.c; docs/refinement.md): refuses
 * what the slice does not carry (an input error naming the key), puts the module's phase on h,
 * and, with seed = 1, drops the level-0 particles inside the finer regions and seeds each
 * level's region at its own spacing. */
int solid_module_refine(mpm_module *m, const mpm_config *cfg, struct mpm_hier *h, int seed);

/* Beside a gas (the coupling on the hierarchy, mpm_refine.h): does every particle of the solid
 * lie inside the finest level's region with `cells` finest cells to spare along every axis
 * (every point of the cube of half-side cells h_finest around it on the finest level)? If not,
 * an input error naming the offending body's geometry key. */
int solid_refine_inside(const mpm_module *m, const mpm_config *cfg, int cells);

/* A regrid beside a gas (mpm_refine.h): flag[s] = 1 on the spans s of level 0's flag lattice
 * (n[d] spans per axis, span i around node i, as fluid_refine_flags) that hold a particle of
 * the solid on some rank, 0 elsewhere. */
int solid_refine_spans(const mpm_module *m, const int *n, unsigned char *flag);

/* Put the solid on the regridded hierarchy h (its particles stay as they are; its clamps hold
 * the new levels' nodes). */
int solid_module_rehier(mpm_module *m, struct mpm_hier *h);

#endif
