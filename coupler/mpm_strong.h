/* Strong coupling of the serial staggered scheme: sub-iterations within a coupling step until
 * the load the solid was given matches the load the gas then gives up, with Aitken's dynamic
 * under-relaxation (Irons and Tuck 1969; Kuettler and Wall 2008).
 *
 * A coupling step t0 -> t1 = t0 + H, with q_k the trial load rate (N per node):
 *   1. the solid advances under the momentum still owed at t0 plus H q_k;
 *   2. the gas advances against the solid's new state and gives up H g_k;
 *   3. the residual r_k = g_k - q_k; the step is converged when |r_k| <= tolerance |g_k| (2-norms
 *      over the owned nodes), else both modules go back to their state at t0 and
 *      q_{k+1} = q_k + w_k r_k, with w_1 = coupling.relaxation and
 *      w_k = -w_{k-1} r_{k-1}.(r_k - r_{k-1}) / |r_k - r_{k-1}|^2 (limited to [-1, 1]).
 * The predictor q_1 is the converged g of the step before (0 at the start).
 *
 * Momentum. The interface accounting of mpm_interface.h is untouched: the solid receives what
 * it was given, the gas's impulse is added to what is owed, so whatever a last iteration leaves
 * unmatched (H r_K, at most the tolerance) stays owed to the next step; the balance holds to
 * roundoff whether or not the iterations converged. A step whose particle set changed under a
 * retried substep (the step loop's open faces and migration run between a module's substeps)
 * cannot go back to its start: it keeps the sub-iteration it reached, with a warning. A step that
 * reaches coupling.iterations without converging is accepted with a warning (the first few are
 * named; the run's count is reported at the end).
 *
 * State. The predictor is interface state carried between steps: it is the interface's `prev`
 * (mpm_interface.h), which checkpoints store, so a restart continues bitwise. */
#ifndef MPM_STRONG_H
#define MPM_STRONG_H

#include "mpm_partitioned.h"

typedef struct mpm_strong mpm_strong;

/* Sub-iterations for pp (most `iterations` per step, relative tolerance, first relaxation). */
int mpm_strong_new(mpm_strong **s, mpm_partitioned *pp, int iterations, double tolerance,
                   double relaxation);
/* Logs the run's iteration figures (rank 0) and frees s; accepts NULL. */
void mpm_strong_destroy(mpm_strong **s);

/* One strongly coupled serial step t0 -> t1 (before mpm_partitioned_end). Collective. */
int mpm_strong_step(mpm_strong *s, mpm_timescheme *ts, double t0, double t1);

#endif
