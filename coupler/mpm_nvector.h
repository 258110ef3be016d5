/* Compiled vector operations for the serial N_Vectors of the ODE state.
 *
 * Debian's SUNDIALS 6.4.1 packages build the serial N_Vector without optimisation (every
 * element goes through the stack), which made ARKODE's per-step vector work cost about as
 * much as a P2G. mpm_nvector_fast_ops() replaces the operations ARKODE's ERKStep uses
 * with plain loops compiled here: an ops-table specialisation of the vector (the SUNDIALS
 * object pattern), inherited by every clone ARKODE makes. Each operation does the same
 * arithmetic in the same order as the SUNDIALS serial implementation, including its
 * special cases (a = 1, a = -1, a = b, ...), so results are bit for bit the same; the
 * single-pass linear combinations add the terms of each element in the same order as
 * SUNDIALS' one-vector-at-a-time loops. */
#ifndef MPM_NVECTOR_H
#define MPM_NVECTOR_H

#include <nvector/nvector_serial.h>

/* Install the compiled operations (including the fused linear combination and scaled
 * additions) on a serial vector. */
void mpm_nvector_fast_ops(N_Vector v);

/* w = 1 / (rtol |y| + atol) over every serial subvector of the MPIManyVectors y and w: ARKODE's
 * scalar-tolerance error weights (the same operations in the same order), in one pass
 * instead of four. */
void mpm_nvector_weights(N_Vector y, N_Vector w, double rtol, double atol);

#endif
