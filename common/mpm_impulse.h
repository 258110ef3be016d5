/* Nodal constraints as impulses, and the bookkeeping of the forces they exert: shared by the
 * gas's static obstacles (fluid/fluid_obstacle.c) and the coupling schemes (coupler/).
 *
 * A constraint replaces a node's velocity v by v' (and, in the method of lines, its
 * acceleration a by a'). In the classic update (step h > 0) the change is an impulse over the
 * step: the acceleration takes it too, a' = a + (v' - v) / h, whatever a' was asked for, so that
 * v^n = v - h a is unchanged (the transfer reads the time-centred velocity from it) and FLIP
 * (which adds h sum S a), PIC and APIC (which read v) all see the same change. The force on the
 * node's material is m (a' - a) either way; summed over the nodes a rank owns and reduced, it is
 * the rate at which the constraint changes the phase's momentum, exactly.
 *
 * Which RHS made a step. A report after an accepted step wants the forces of the RHS that made
 * it. The classic update's fixed-step ERK evaluates its one stage at the end of the previous
 * step and reuses it: when a step is accepted the latest record belongs to its end (the next
 * step's stage), so the one before is the step's. The adaptive pairs report their last stage
 * (the end of the step for the first-same-as-last pairs). Two records are kept: a RHS at a new
 * time starts a new one, a re-evaluation at the same time replaces the latest. */
#ifndef MPM_IMPULSE_H
#define MPM_IMPULSE_H

#include "mpm_grid.h"

/* Set node l of ph to v' = v1 (dim values) and, in the method of lines (h = 0), a' = a1 (NULL
 * keeps a); in the classic update a' = a + (v1 - v) / h. Writes m (a' - a) to force (dim values)
 * and the energy rate it puts into the node's material, component by component, to power (dim
 * values), as the gas's energy balance counts it: classic, force . (v^n + v') / 2
 * (time-centred); method of lines, force . v + m a . (v - v') (the particles gain a' . m v, the
 * stress works on v'). */
static inline void mpm_impulse_apply_parts(mpm_grid_phase *ph, int dim, mpm_lidx l,
                                           const double *v1, const double *a1, double h,
                                           double *force, double *power) {
  const double m = ph->m_i[l];
  for (int d = 0; d < dim; ++d) {
    const double v0 = ph->v_i[d][l], a0 = ph->a_i[d][l];
    const double da = h > 0 ? (v1[d] - v0) / h : (a1 ? a1[d] - a0 : 0.0);
    ph->v_i[d][l] = v1[d];
    ph->a_i[d][l] = a0 + da;
    force[d] = m * da;
    power[d] =
        h > 0 ? force[d] * 0.5 * (v0 - h * a0 + v1[d]) : force[d] * v0 + m * a0 * (v0 - v1[d]);
  }
}

/* The same, returning the power summed over the components. */
static inline double mpm_impulse_apply(mpm_grid_phase *ph, int dim, mpm_lidx l, const double *v1,
                                       const double *a1, double h, double *force) {
  double parts[MPM_MAX_DIM], power = 0.0;
  mpm_impulse_apply_parts(ph, dim, l, v1, a1, h, force, parts);
  for (int d = 0; d < dim; ++d) power += parts[d];
  return power;
}

/* The times of the two records and which is the latest. */
typedef struct mpm_rhs_records {
  double t[2];
  int set[2], classic[2];
  int latest;
} mpm_rhs_records;

/* A RHS at time t with step h (0: method of lines) begins: the index of the record to fill,
 * which the caller clears (the latest again if t is its time, else the other). */
static inline int mpm_rhs_records_begin(mpm_rhs_records *r, double t, double h) {
  if (r->set[r->latest] && r->t[r->latest] != t) r->latest ^= 1;
  const int k = r->latest;
  r->t[k] = t, r->set[k] = 1, r->classic[k] = h > 0;
  return k;
}

/* The index of the record of the RHS that made the step accepted at t. */
static inline int mpm_rhs_records_pick(const mpm_rhs_records *r, double t) {
  const int cur = r->latest, prev = cur ^ 1;
  return r->classic[cur] && r->t[cur] >= t && r->set[prev] ? prev : cur;
}

#endif
