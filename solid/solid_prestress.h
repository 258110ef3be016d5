/* The initial stress of a solid body (keys initial_stress and initial_pressure), realised in
 * the terms of the body's material model, so that the stress the model computes at the seeded
 * state is the given Cauchy stress sigma0:
 *  - a total model (elastic, or plastic with its elastic part) starts from an elastic pure
 *    stretch F0 (symmetric, positive definite) with stress(F0) / det F0 = sigma0 at unit
 *    reference volume, solved by Newton's method with the model's own stress();
 *  - a rate-form model starts from F = I with its stress state sigma = sigma0;
 *  - a model with history must stay elastic at F0 (commit() leaves its fresh history alone);
 *  - a rigid body carries no stress, so the keys are input errors for it.
 * The body is seeded where it is (its current configuration): mass = density x seeded volume,
 * reference volume V0 = seeded volume / det F0, so the current volume V0 det F0 is the seeded
 * one and a gas at the same pressure beside the body balances it exactly on the grid. */
#ifndef SOLID_PRESTRESS_H
#define SOLID_PRESTRESS_H

#include "mpm_config.h"
#include "solid_material.h"

#include <stddef.h>

typedef struct solid_prestress {
  double F0[9];     /* initial deformation gradient, dim x dim row-major (I without prestress) */
  double J0;        /* det F0 */
  double sigma0[9]; /* initial "sigma" state of a rate-form model (dim x dim), else 0 */
} solid_prestress;

/* Read the initial stress keys of body `section` with model mat and realise them; without the
 * keys the state is F0 = I, sigma0 = 0. Bad input (both keys, a rigid body, a tensor of the
 * wrong size, non-symmetric or non-finite values, a stress the model cannot take) is one
 * mpm_config_fail line naming the key. */
int solid_prestress_read(solid_prestress *ps, const mpm_config *cfg, const char *section,
                         const solid_material *mat, int dim);

/* Realise the symmetric Cauchy stress sigma0 (dim x dim, row-major) with model mat (not rigid).
 * Returns 0, or MPM_ERR_INPUT with the reason in why (a phrase for a message; nothing is
 * logged). */
int solid_prestress_solve(solid_prestress *ps, const solid_material *mat, int dim,
                          const double *sigma0, char *why, size_t nwhy);

#endif
