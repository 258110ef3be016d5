/* Where the particles sit in the refinement hierarchy (mpm_hier.h), for the output and the
 * diagnostics: each particle's level and the particle count of every level.
 *
 * Invariants: a particle's level is mpm_hier_level_of at its position (the particle field "x"),
 * the level it deposits on and reads; the counts are those levels tallied, so they sum to p->n. */
#include "mpm_hier.h"

/* The position components of p (the field "x"). */
static void positions(const mpm_hier *h, const mpm_particles *p, const double **x) {
  const int fx = mpm_particles_find(p, "x");
  for (int d = 0; d < h->dim; ++d) x[d] = mpm_particles_comp(p, fx, d);
}

static int level_at(const mpm_hier *h, const double *const *x, mpm_lidx i) {
  double xp[MPM_MAX_DIM] = {0, 0, 0};
  for (int d = 0; d < h->dim; ++d) xp[d] = x[d][i];
  return mpm_hier_level_of(h, xp);
}

void mpm_hier_particle_levels(const mpm_hier *h, const mpm_particles *p, double *level) {
  const double *x[MPM_MAX_DIM];
  positions(h, p, x);
  for (mpm_lidx i = 0; i < p->n; ++i) level[i] = level_at(h, x, i);
}

void mpm_hier_count_levels(const mpm_hier *h, const mpm_particles *p, double *count) {
  const double *x[MPM_MAX_DIM];
  positions(h, p, x);
  for (mpm_lidx i = 0; i < p->n; ++i) count[level_at(h, x, i)] += 1.0;
}
