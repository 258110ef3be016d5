/* Structural material models: an object with an ops table, registered by name (the PETSc
 * XXXSetType pattern). A model file exports only its ops table; solid_material_register.c
 * lists the built-ins, so a new model is one file plus one line there.
 *
 * Four kinds of model fit the one interface:
 *  - total (hyperelastic, small-strain elastic): Cauchy stress from F alone;
 *  - rate form (hypoelastic): the stress is part of the ODE state (field "sigma", nrate
 *    components) and the model gives its rate from the velocity gradient L;
 *  - with history (J2 plasticity): per-particle history values (field "hist", nhistory
 *    components) that stay fixed during a step; stress() performs the return mapping from the
 *    stage's F and the committed history without changing it, and commit() stores the
 *    returned state once a step is accepted;
 *  - rigid (flag `rigid`): no stress; the solid module prescribes the body's motion.
 * Everything is evaluated over a batch of particles (an index list into component-major
 * arrays), never one call per particle.
 *
 * Plane strain is the 2-D convention: F, L and sigma are 2 x 2 and the out-of-plane stretch
 * is 1. A model that needs out-of-plane history (plasticity) keeps it in its history. */
#ifndef SOLID_MATERIAL_H
#define SOLID_MATERIAL_H

#include "mpm_config.h"
#include "mpm_types.h"

typedef struct solid_material solid_material;

/* Arrays of a batch. Tensors are component-major with stride n: component (r, c) of
 * particle i is at T[(r*dim + c)*n + i]; history component k at hist[k*n + i]. */
typedef struct solid_batch {
  int dim;
  mpm_lidx n;          /* stride of the particle arrays */
  mpm_lidx count;      /* particles in the batch */
  const mpm_lidx *idx; /* their indices */
  const double *F;     /* deformation gradient (dim*dim) */
  const double *V0;    /* reference volume */
  const double *sigma; /* rate-form stress state (dim*dim), or NULL */
  double *hist;        /* history (nhistory): read by stress, written by commit; or NULL */
  const double *L;     /* velocity gradient (dim*dim), for rate(); else NULL */
  double *out;         /* stress(): V sigma (dim*dim); rate(): d sigma / dt (dim*dim) */
} solid_batch;

typedef struct solid_material_ops {
  const char *name;
  /* Read and check the parameters of case section `section` (e.g. "solid.bar"); errors go
   * through mpm_config_fail so they name the file, line and key. */
  int (*create)(solid_material *mat, const mpm_config *cfg, const char *section, int dim);
  /* Current volume times Cauchy stress. */
  void (*stress)(const solid_material *mat, const solid_batch *b);
  /* Largest elastic wave speed at reference density rho (for the stable step). */
  double (*wave_speed)(const solid_material *mat, double rho);
  /* Stored elastic energy per reference volume at particle i of the batch arrays. */
  double (*energy_density)(const solid_material *mat, const solid_batch *b, mpm_lidx i);
  void (*destroy)(solid_material *mat);
  /* Optional: history components per particle (0 if NULL) and their initial values. */
  int (*nhistory)(int dim);
  void (*init_history)(const solid_material *mat, const solid_batch *b);
  /* Optional: after an accepted step, store the returned state in b->hist. */
  void (*commit)(const solid_material *mat, const solid_batch *b);
  /* Optional, rate-form models only: d sigma/dt from b->sigma and b->L into b->out. Such a
   * model keeps its stress in the "sigma" state field, which starts at zero (or at the body's
   * initial stress, solid_prestress.h). */
  void (*rate)(const solid_material *mat, const solid_batch *b);
  /* 1 if the model is only valid for small strains and rotations (it is then checked for
   * objectivity to first order only). */
  int small_strain;
  /* 1 for a rigid body: no stress, F = I, its particles move with the body's constant
   * velocity and the grid nodes inside its region (moving with it) take that velocity; the
   * solid module does the motion (the model gives zero stress and a wave speed of 0). */
  int rigid;
} solid_material_ops;

struct solid_material {
  const solid_material_ops *ops;
  void *content;
  int dim;
};

/* Create the model registered as `type`; an unknown name is an input error listing the
 * registered names. */
int solid_material_create(solid_material **mat, const char *type, const mpm_config *cfg,
                          const char *section, int dim);
void solid_material_destroy(solid_material **mat);

/* Registered names joined by '|' (for the case-file schema). */
const char *solid_material_names(void);
/* Number of registered models and the ops of model k (for the conformance suite). */
int solid_material_count(void);
const solid_material_ops *solid_material_ops_at(int k);

#endif
