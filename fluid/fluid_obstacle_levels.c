/* Static obstacles on every level of a refinement hierarchy, and their ghosts with the grid
 * pressure (fluid_obstacle.h, fluid_gridp.c; docs/refinement.md).
 *
 * Constraint. Level l's obstacle nodes are its active nodes with phi < band h_l (the band in
 * level l's cells, as level 0's in its own), constrained after the solve on every level with
 * level 0's rule (slip or no-slip, the hold below FLUID_OBSTACLE_HOLD of the level's heaviest
 * constrained node: the masses of a level scale with h_l^dim). The active nodes are the composite
 * basis's unknowns; the prolongation then fills the inactive nodes from the constrained ones.
 *
 * Span ghost. With the grid pressure the nodal pressure p_j (the volume-weighted mean) is zero on
 * the massless nodes inside a body, so the nodes near its surface miss the pressure of their
 * neighbours inside, as with the particles' quadrature (fluid_obstacle.h, ghost pressure). The
 * ghosts are those massless nodes: with U_j = 1 on them (0 elsewhere) and u_h = sum_j N_j U_j,
 * each node i with mass takes the ghost force p_i integral of u_h grad N_i, the pressure of its
 * own node acting where the gas is missing, as a ghost point of level 0's lattice does. With
 * p_j = p on every node with mass, p_h + p u_h = p over the body's reach, so a uniform pressure
 * gives no nodal force: gas at rest stays at rest. On a hierarchy U is set on the active nodes,
 * prolonged, integrated over each level's spans and restricted, like the pressure itself.
 *
 * Force. The body takes minus the ghost forces, the momentum its constraint removes, and the
 * forces of the empty (massless too: with the grid pressure a massless node inside the body has
 * one, whose partners the gas took) or light nodes of its reach, on every level; level 0's reach
 * is fluid_obstacle.c's, a finer level's its constrained nodes.
 *
 * Ranks (mpm_hier.h, ranks). The finer levels are alike on every rank (their deposits summed
 * over the ranks): every rank constrains them and takes their ghost forces alike, and rank 0
 * alone books what they give to the bodies (forces, surface samples), so that the sums over the
 * ranks (fluid_obstacles_report, fluid_surface_step) count each once; level 0 books its owned
 * nodes. The ghost span integrals on the finer levels are the grid pressure's split
 * (fluid_gridp.c: rank 0 integrates them, the restriction sums the ranks).
 *
 * Invariant: without a hierarchy and without the grid pressure nothing here runs. */
#include "fluid_obstacle.h"

#include "mpm_bc.h"
#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Does this rank book what level l >= 1 gives to the bodies (rank 0 alone: the level is alike on
 * every rank)? */
static int books_level(const fluid_obstacles *o) {
  return o->hier->rank == 0;
}

/* x reflected into the domain of g across every non-periodic face it lies beyond (the walls: a
 * node beyond one mirrors a node inside). */
static void reflect_in(const mpm_grid *g, double *x) {
  for (int d = 0; d < g->dim; ++d) {
    if (g->periodic[d]) continue;
    if (x[d] < g->lo[d]) x[d] = 2.0 * g->lo[d] - x[d];
    if (x[d] > g->hi[d]) x[d] = 2.0 * g->hi[d] - x[d];
  }
}

/* The position of box node n of level grid lg. */
static void node_x(const mpm_grid *lg, mpm_lidx n, double *x) {
  int gi[MPM_MAX_DIM];
  mpm_grid_node_global(lg, n, gi);
  for (int d = 0; d < MPM_MAX_DIM; ++d) x[d] = d < lg->dim ? lg->lo[d] + gi[d] * lg->dx : 0.0;
}

/* The smallest phi over the obstacles at x (its obstacle into *which). */
static double phi_min(const fluid_obstacles *o, const mpm_grid *g0, const double *x, int *which) {
  double best = HUGE_VAL;
  for (int k = 0; k < o->count; ++k) {
    const double phi = fluid_obstacle_phi(&o->ob[k].sdf, g0, x, NULL);
    if (phi < best) best = phi, *which = k;
  }
  return best;
}

/* inside[l] and nob[l] of level l (grid lg). */
static int mark_inside(fluid_obstacles *o, int l, const mpm_grid *g0, const mpm_grid *lg) {
  MPM_ALLOC(o->inside[l], lg->nnodes);
  MPM_ALLOC(o->nob[l], lg->nnodes);
  for (mpm_lidx n = 0; n < lg->nnodes; ++n) {
    double x[3];
    int k = 0;
    node_x(lg, n, x);
    reflect_in(g0, x);
    o->inside[l][n] = phi_min(o, g0, x, &k) < 0.0;
    o->nob[l][n] = -1;
  }
  return 0;
}

/* The active nodes of level l >= 1 with phi < band h_l, per obstacle, and the reach (each node
 * once, with the first obstacle that constrains it). */
static int find_level_nodes(fluid_obstacles *o, int l, const mpm_grid *g0, const mpm_grid *lg,
                            const unsigned char *act) {
  const int dim = lg->dim;
  const double band = o->band * lg->dx;
  int *mark;
  MPM_ALLOC(mark, lg->nnodes);
  for (mpm_lidx n = 0; n < lg->nnodes; ++n) mark[n] = -1;
  for (int k = 0; k < o->count; ++k) {
    fluid_obstacle *ob = &o->ob[k];
    mpm_lidx count = 0;
    for (int pass = 0; pass < 2; ++pass) {
      count = 0;
      for (mpm_lidx n = 0; n < lg->nnodes; ++n) {
        double x[3], nrm[3];
        if (!act[n]) continue;
        node_x(lg, n, x);
        if (!(fluid_obstacle_phi(&ob->sdf, g0, x, nrm) < band)) continue;
        if (pass) {
          ob->fine[l].node[count] = n;
          memcpy(ob->fine[l].normal + (size_t)dim * count, nrm, sizeof *nrm * (size_t)dim);
          if (mark[n] < 0) mark[n] = k;
        }
        ++count;
      }
      if (!pass) {
        ob->fine[l].node = malloc(sizeof(mpm_lidx) * (size_t)(count + 1));
        ob->fine[l].normal = malloc(sizeof(double) * (size_t)(dim * count + 1));
        if (!ob->fine[l].node || !ob->fine[l].normal) {
          free(mark);
          MPM_FAIL_OOM((double)count * (sizeof(mpm_lidx) + dim * sizeof(double)));
        }
      }
    }
    ob->fine[l].count = count;
  }
  mpm_lidx n_reach = 0;
  for (mpm_lidx n = 0; n < lg->nnodes; ++n) n_reach += mark[n] >= 0;
  o->rnode[l] = malloc(sizeof(mpm_lidx) * (size_t)(n_reach + 1));
  o->rob[l] = malloc(sizeof(int) * (size_t)(n_reach + 1));
  if (!o->rnode[l] || !o->rob[l]) {
    free(mark);
    MPM_FAIL_OOM((double)n_reach * (sizeof(mpm_lidx) + sizeof(int)));
  }
  o->rcount[l] = 0;
  for (mpm_lidx n = 0; n < lg->nnodes; ++n)
    if (mark[n] >= 0) o->rnode[l][o->rcount[l]] = n, o->rob[l][o->rcount[l]++] = mark[n];
  free(mark);
  return 0;
}

void fluid_obstacles_levels_free(fluid_obstacles *o) {
  for (int l = 0; l < MPM_HIER_MAX_LEVELS; ++l) {
    free(o->inside[l]), free(o->nob[l]), free(o->rnode[l]), free(o->rob[l]);
    o->inside[l] = NULL, o->nob[l] = NULL, o->rnode[l] = NULL, o->rob[l] = NULL;
    o->rcount[l] = 0;
    for (int k = 0; k < o->count; ++k) {
      free(o->ob[k].fine[l].node), free(o->ob[k].fine[l].normal);
      o->ob[k].fine[l].node = NULL, o->ob[k].fine[l].normal = NULL, o->ob[k].fine[l].count = 0;
    }
  }
  o->hier = NULL, o->nlev = 1;
}

int fluid_obstacles_levels(fluid_obstacles *o, const mpm_grid *grid, const mpm_hier *h, int span) {
  fluid_obstacles_levels_free(o);
  if (o->count == 0) return 0;
  o->span = span, o->hier = h, o->nlev = h ? h->nlevels : 1;
  for (int l = 0; span && l < o->nlev; ++l)
    MPM_CALL(mark_inside(o, l, grid, l ? h->level[l].grid : grid));
  for (int l = 1; l < o->nlev; ++l)
    MPM_CALL(find_level_nodes(o, l, grid, h->level[l].grid, h->level[l].active));
  return 0;
}

void fluid_obstacles_span_mask(const fluid_obstacles *o, int l, const mpm_grid *g, const double *M,
                               const unsigned char *act, double *U) {
  const unsigned char *in = o->inside[l];
  for (mpm_lidx n = 0; n < g->nnodes; ++n)
    U[n] = in && in[n] && (!act || act[n]) && !(M[n] > 0.0) ? 1.0 : 0.0;
}

/* The obstacle nearest to box node n of level l (found once). */
static int nearest_of(fluid_obstacles *o, int l, const mpm_grid *g, mpm_lidx n) {
  if (o->count == 1) return 0;
  if (o->nob[l][n] < 0) {
    double x[3];
    int k = 0;
    node_x(g, n, x);
    reflect_in(o->hier ? o->hier->level[0].grid : g, x);
    phi_min(o, o->hier ? o->hier->level[0].grid : g, x, &k);
    o->nob[l][n] = k;
  }
  return o->nob[l][n];
}

void fluid_obstacles_span_force(fluid_obstacles *o, int l, mpm_grid *g, int phase, const double *P,
                                const double *M, const unsigned char *act,
                                const double *const *GH) {
  const int dim = g->dim;
  mpm_grid_phase *ph = &g->phase[phase];
  double *rec = o->f[o->rec.latest];
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    if ((act && !act[n]) || !(M[n] > 0.0)) continue;
    int any = 0;
    for (int d = 0; d < dim; ++d) any |= GH[d][n] != 0.0;
    if (!any) continue;
    const int owned = l > 0 ? books_level(o) : o->own[n];
    double *f = rec + (size_t)dim * (owned ? nearest_of(o, l, g, n) : 0);
    for (int d = 0; d < dim; ++d) {
      ph->f_i[d][n] += P[n] * GH[d][n];
      if (owned) f[d] -= P[n] * GH[d][n];
    }
  }
}

void fluid_obstacles_span_surface(fluid_obstacles *o, const mpm_grid *const *grids,
                                  const double *const *M, const double *const *MP) {
  for (int k = 0; k < o->count; ++k) {
    fluid_surface *s = &o->ob[k].surf;
    if (s->n == 0) continue;
    memset(s->sum, 0, sizeof *s->sum * 2 * (size_t)s->n);
    for (int i = 0; i < s->n; ++i) {
      const double x[3] = {s->x[2 * i], s->x[2 * i + 1], 0.0};
      const int l = o->hier ? mpm_hier_level_of(o->hier, x) : 0;
      if (l > 0 && !books_level(o)) continue;
      fluid_surface_sample_point(s, i, grids[l], M[l], MP[l], l ? NULL : o->own);
    }
  }
}

void fluid_obstacles_span_rate(const mpm_grid *g, int phase, const double *M,
                               const unsigned char *act, const double *const *GH, double *D) {
  const mpm_grid_phase *ph = &g->phase[phase];
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    if ((act && !act[n]) || !(M[n] > 0.0)) continue;
    for (int d = 0; d < g->dim; ++d) D[n] -= ph->v_i[d][n] * GH[d][n];
  }
}

/* Level l >= 1: the empty or light nodes of the reach hand their force to the body, then every
 * obstacle's nodes are constrained (fluid_obstacles_apply does level 0). */
static void apply_level(fluid_obstacles *o, int l, int phase, double h, int record) {
  record = record && books_level(o);
  mpm_grid *g = o->hier->level[l].grid;
  mpm_grid_phase *ph = &g->phase[phase];
  const int dim = g->dim;
  double mmax = 0.0, scratch[3];
  for (mpm_lidx k = 0; k < o->rcount[l]; ++k) mmax = fmax(mmax, ph->m_i[o->rnode[l][k]]);
  for (mpm_lidx k = 0; record && k < o->rcount[l]; ++k) {
    const mpm_lidx n = o->rnode[l][k];
    if ((!o->span && !(ph->m_i[n] > 0.0)) || ph->m_i[n] > ph->m_empty) continue;
    double *f = o->f[o->rec.latest] + (size_t)dim * o->rob[l][k];
    for (int d = 0; d < dim; ++d) f[d] += ph->f_i[d][n];
  }
  for (int k = 0; k < o->count; ++k) {
    const fluid_obstacle *ob = &o->ob[k];
    double *f = record ? o->f[o->rec.latest] + (size_t)dim * k : scratch;
    fluid_obstacle_constrain(ob->fine[l].node, ob->fine[l].normal, NULL, ob->fine[l].count,
                             ob->no_slip, ph, dim, h, o->hold * mmax, o->coast, f, NULL);
  }
}

int fluid_obstacles_apply_levels(fluid_obstacles *o, int phase, double h, int record) {
  for (int l = 1; l < o->nlev; ++l) apply_level(o, l, phase, h, record);
  return 0;
}
