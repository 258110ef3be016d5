/* The projected dilatation of solid.NAME.dilatation = projected (solid_dilatation.c). Private
 * to solid/. */
#ifndef SOLID_DILATATION_H
#define SOLID_DILATATION_H

#include "solid_internal.h"

/* Read every body's solid.NAME.dilatation (a rigid body may not project) and, when one
 * projects, add the grid phase its deposit fills. */
int solid_dilatation_read(mpm_module *m, const mpm_config *cfg);

/* In G2P, with L (dim^2 components of n) and Fdot = L F of state y: for each projecting
 * particle replace tr L by its volume-weighted nodal projection, in L's diagonal and in Fdot
 * (Fdot += (d - tr L) / dim F). Needs this RHS's body grouping (sc->idx). Collective (halo
 * exchanges). */
int solid_dilatation_apply(mpm_module *m, const double *y, double *L, double *Fdot);

void solid_dilatation_free(solid_dilatation *dl);

#endif
