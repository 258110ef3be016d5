/* Structural material models: an object with an ops table, registered by name (the PETSc
 * XXXSetType pattern). A model file exports only its ops table; solid_material_register.c
 * lists the built-ins, so a new model is one file plus one line there.
 *
 * Stress is evaluated over a batch of particles (an index list into component-major
 * arrays), never one call per particle. */
#ifndef SOLID_MATERIAL_H
#define SOLID_MATERIAL_H

#include "mpm_config.h"
#include "mpm_types.h"

typedef struct solid_material solid_material;

/* Input and output of a stress evaluation. Tensors are component-major with stride n:
 * component (r, c) of particle i is at T[(r*dim + c)*n + i]. */
typedef struct solid_stress_batch {
  int dim;
  mpm_lidx n;          /* stride of the particle arrays */
  mpm_lidx count;      /* particles in the batch */
  const mpm_lidx *idx; /* their indices */
  const double *F;     /* deformation gradient */
  const double *V0;    /* reference volume */
  double *vsig;        /* out: current volume times Cauchy stress, V sigma */
} solid_stress_batch;

typedef struct solid_material_ops {
  const char *name;
  /* Read and check the parameters from case section `section` (e.g. "solid.bar"). */
  int (*create)(solid_material *mat, const mpm_config *cfg, const char *section);
  void (*stress)(const solid_material *mat, const solid_stress_batch *b);
  /* Largest elastic wave speed at density rho (for the stable step). */
  double (*wave_speed)(const solid_material *mat, double rho);
  /* Stored energy per reference volume at F (for the energy diagnostics). */
  double (*energy_density)(const solid_material *mat, int dim, const double *F);
  void (*destroy)(solid_material *mat);
} solid_material_ops;

struct solid_material {
  const solid_material_ops *ops;
  void *content;
};

/* Create the model registered as `type`; an unknown name is an input error listing the
 * registered names. */
int solid_material_create(solid_material **mat, const char *type, const mpm_config *cfg,
                          const char *section);
void solid_material_destroy(solid_material **mat);

/* Registered names joined by '|' (for the case-file schema). */
const char *solid_material_names(void);

#endif
