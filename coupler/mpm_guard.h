/* The blow-up guard: stops a run that has gone unstable, under every time method, instead of
 * letting it run on with a collapsing step or an exploding energy.
 *
 * A run is stopped (MPM_ERR_UNPHYSICAL, one message naming the criterion and the key that
 * sets it) when
 *   - the total energy is not finite, or, from the 20th step on, exceeds time.energy_growth
 *     times the largest total energy of the first half of the steps taken so far: an
 *     instability grows the energy geometrically, by a factor per step, so the ratio over
 *     half the run grows without bound, while energy that loads or open faces feed in grows
 *     like a power of time (a factor 2^p over half the run for t^p: 4 for a body falling from
 *     rest), and a scene that starts without energy (at rest, loaded later) is no exception;
 *   - from the 20th step on, the kinetic energy exceeds time.kinetic_growth times the larger
 *     of the largest kinetic energy of the first half of the steps taken so far and
 *     MPM_GUARD_KINETIC_FLOOR times the largest total energy so far: the same test on the
 *     energy that blows up first. A velocity mode can grow from the internal energy of a gas,
 *     which dominates the total, and leave the total flat (issue 55: a gas column beside a
 *     slab, the kinetic energy x1e6 from an acoustic level, exit 0). Such a mode rises from
 *     roundoff early in the run and saturates near 10 % of the total within a few of its
 *     e-folding times, so over half the run it grows by hundreds only: a gas column of 0.5 m
 *     beside an elastic slab at 400 cells per metre (usl) grew its kinetic energy from 2e-5 to
 *     0.12 of the total from t = 2.4 to 4.5 at a ratio of at most 221 over half the run. The
 *     default is hence 100, not energy_growth's 1000 (which let it run on): it stops that run
 *     at t = 3.9, at 4.7 % of the total. Motion a load starts from rest grows like t^p, 2^p
 *     over half the run; over 265 runs of 22 tests (every shipped case among them) the largest
 *     ratio was 11 (an adaptive pair's first steps, which grow the step from a tiny one). The
 *     floor 1e-5 means a mode counts only once it holds 100 x 1e-5 = 0.1 % of the total energy
 *     (Mach 0.06 in a gas at rest): roundoff motion of a scene at rest (1e-30 of the total, and
 *     what roundoff grows to) never does, nor the spurious flow particle shifting leaves beside
 *     farfield faces (a ratio of 83 against the first half alone, 7 with the floor);
 *   - for time.collapse_steps accepted steps in a row, the step was below time.collapse_ratio
 *     times the CFL step of the state the run started from (steps cut short to land on an
 *     output or checkpoint time do not count, and do not break a streak).
 * All are checked after every accepted step, from the totals the diagnostics already sum (the
 * kinetic energy is their `kinetic` column), and under a partitioned time scheme after every
 * coupling step. A restart starts the history afresh from the checkpoint's state. A
 * step of zero length (the time too large for the step: t + h == t) stops the run whatever
 * the thresholds, since it would repeat forever. */
#ifndef MPM_GUARD_H
#define MPM_GUARD_H

#include "mpm_config.h"

/* The kinetic energy's floor, as a fraction of the largest total energy (see above). */
#define MPM_GUARD_KINETIC_FLOOR 1e-5

typedef struct mpm_guard {
  double ratio, growth, kgrowth; /* the thresholds (0: that criterion off) */
  int window;                    /* steps in a row */
  double h0;                     /* CFL step of the starting state (0: nothing limits it) */
  int low;                       /* current streak of collapsed steps */
  long n, cap;                   /* steps seen, and the capacity of emax and kmax */
  double *emax; /* emax[k]: the largest |total energy| over the first k + 1 steps */
  double *kmax; /* kmax[k]: the largest kinetic energy over the first k + 1 steps */
} mpm_guard;

extern const mpm_key_spec mpm_guard_keys[];
extern const int mpm_guard_nkeys;

/* Read the thresholds; h0 is the CFL step, e0 the total and k0 the kinetic energy of the
 * starting state. */
int mpm_guard_init(mpm_guard *g, const mpm_config *cfg, double h0, double e0, double k0);
void mpm_guard_free(mpm_guard *g);

/* After an accepted step of size h that ended at t (cut_short: it was shortened to land on a
 * stop time) with total energy `energy` and kinetic energy `kinetic`: 0, or the failure.
 * Collective values only (every rank decides alike). */
int mpm_guard_check(mpm_guard *g, double t, long step, double h, int cut_short, double energy,
                    double kinetic);

#endif
