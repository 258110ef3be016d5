/* Hierarchies shared by the refinement tests (test_hier_basis.c, test_hier_transfer.c), on one
 * rank:
 *   HIER_L2   2-D, domain [0, 2]^2, dx = 0.1; level 1 an L (two boxes) with its re-entrant
 *             corner at (1.05, 1.05) (boxes snap outwards to whole level-0 spans).
 *   HIER_L3D  3-D, domain [0, 1.2]^3, dx = 0.1; level 1 an L prism, re-entrant edge along z.
 *   HIER_3LEV 2-D, domain [0, 2]^2, dx = 0.1; level 1 the square [0.4, 1.6]^2, level 2 an L
 *             inside it with its re-entrant corner at (1.0, 1.0).
 * Random points are drawn half over the domain, half over the refined boxes' hull, so every
 * level gets many. */
#ifndef HIER_FIXTURE_H
#define HIER_FIXTURE_H

#include "mpm_hier.h"
#include "mpm_random.h"

#include <stdio.h>
#include <string.h>

typedef enum { HIER_L2, HIER_L3D, HIER_3LEV, HIER_NCASES } hier_case;

typedef struct fixture {
  mpm_grid *grid;
  mpm_hier *h;
  int phase;
  double hull_lo[3], hull_hi[3]; /* the refined boxes' hull */
} fixture;

static const char *const hier_case_name[HIER_NCASES] = {"2-D L", "3-D L", "2-D 3 levels"};

/* Build case c; nproc 1 on MPI_COMM_SELF. Returns 0 on success. */
static inline int fixture_make(fixture *f, hier_case c) {
  memset(f, 0, sizeof *f);
  const int dim = c == HIER_L3D ? 3 : 2, nproc[3] = {1, 1, 1};
  const double lo[3] = {0, 0, 0}, hi2[3] = {2, 2, 2}, hi3[3] = {1.2, 1.2, 1.2};
  if (mpm_grid_new(&f->grid, MPI_COMM_SELF, dim, lo, dim == 3 ? hi3 : hi2, 0.1, MPM_SHAPE_QUADRATIC,
                   nproc))
    return 1;
  if (mpm_grid_add_phase(f->grid, "test", &f->phase)) return 1;
  mpm_hier_box b[3];
  int nbox = 2, nlev = 2;
  if (c == HIER_L2) {
    b[0] = (mpm_hier_box){1, {0.5, 0.5}, {1.5, 1.0}};
    b[1] = (mpm_hier_box){1, {0.5, 0.5}, {1.0, 1.5}};
  } else if (c == HIER_L3D) {
    b[0] = (mpm_hier_box){1, {0.3, 0.3, 0.3}, {0.9, 0.6, 0.9}};
    b[1] = (mpm_hier_box){1, {0.3, 0.3, 0.3}, {0.6, 0.9, 0.9}};
  } else {
    b[0] = (mpm_hier_box){1, {0.4, 0.4}, {1.6, 1.6}};
    b[1] = (mpm_hier_box){2, {0.7, 0.7}, {1.3, 1.0}};
    b[2] = (mpm_hier_box){2, {0.7, 0.7}, {1.0, 1.3}};
    nbox = 3, nlev = 3;
  }
  for (int d = 0; d < dim; ++d) {
    f->hull_lo[d] = b[0].lo[d] - 0.2, f->hull_hi[d] = b[0].hi[d] + 0.2;
    for (int k = 1; k < nbox; ++k) {
      f->hull_lo[d] = fmin(f->hull_lo[d], b[k].lo[d] - 0.2);
      f->hull_hi[d] = fmax(f->hull_hi[d], b[k].hi[d] + 0.2);
    }
  }
  char why[256];
  const int rc = mpm_hier_new(&f->h, f->grid, nlev, b, nbox, 1, why, sizeof why);
  if (rc) fprintf(stderr, "fixture %s: %s\n", hier_case_name[c], why);
  return rc;
}

static inline void fixture_free(fixture *f) {
  mpm_hier_destroy(&f->h);
  mpm_grid_destroy(&f->grid);
}

/* Random point k: even k over the domain, odd k over the refined hull. */
static inline void fixture_point(const fixture *f, uint64_t *rng, int k, double *x) {
  const mpm_grid *g = f->grid;
  for (int d = 0; d < 3; ++d) x[d] = 0.0;
  for (int d = 0; d < g->dim; ++d) {
    const double a = k % 2 ? f->hull_lo[d] : g->lo[d], b = k % 2 ? f->hull_hi[d] : g->hi[d];
    x[d] = a + (b - a) * mpm_test_uniform(rng);
  }
}

/* Position along d of node l (box index) of level lev. */
static inline double fixture_node_x(const fixture *f, int lev, mpm_lidx l, int d) {
  const mpm_grid *g = f->h->level[lev].grid;
  for (int e = 0; e < d; ++e) l /= g->box_n[e];
  return g->lo[d] + (g->box_lo[d] + (int)(l % g->box_n[d])) * g->dx;
}

#endif
