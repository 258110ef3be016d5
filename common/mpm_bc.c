/* Wall conditions and node constraints (see mpm_bc.h). */
#include "mpm_bc.h"

#include "mpm_error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WALL_CHOICES                                                                               \
  "none|slip|no_slip|periodic|inflow|outflow|subsonic_inflow|subsonic_outflow|farfield"
#define WALL_HELP                                                                                  \
  "condition on this face: none (closed to particles), slip, no_slip, periodic (with the "         \
  "opposite face), or for gas inflow, outflow (supersonic), subsonic_inflow, subsonic_outflow, "   \
  "farfield (non-reflecting; all with the [freestream] state)"

const mpm_key_spec mpm_bc_keys[] = {
    {"boundary.x_lo", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
    {"boundary.x_hi", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
    {"boundary.y_lo", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
    {"boundary.y_hi", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
    {"boundary.z_lo", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
    {"boundary.z_hi", MPM_KEY_ENUM, "none", 0, 0, 0, 0, WALL_CHOICES, WALL_HELP, 0, NULL},
};
const int mpm_bc_nkeys = (int)(sizeof mpm_bc_keys / sizeof mpm_bc_keys[0]);

static const char *const g_axes = "xyz", *const g_side[2] = {"lo", "hi"};

static const char *const g_wall_names[MPM_WALL_COUNT] = {
    "none",    "slip",    "no_slip",         "periodic",
    "inflow",  "outflow", "subsonic_inflow", "subsonic_outflow",
    "farfield"};

const char *mpm_wall_name(mpm_wall k) {
  return k >= 0 && k < MPM_WALL_COUNT ? g_wall_names[k] : "?";
}

/* A periodic face wraps onto the opposite face, so that face must wrap back. */
static int check_periodic_pairs(const mpm_walls *w, const mpm_config *cfg, int dim) {
  for (int d = 0; d < dim; ++d)
    for (int s = 0; s < 2; ++s)
      if (w->face[d][s] == MPM_WALL_PERIODIC && w->face[d][1 - s] != MPM_WALL_PERIODIC) {
        char key[32];
        snprintf(key, sizeof key, "boundary.%c_%s", g_axes[d], g_side[s]);
        return mpm_config_fail(cfg, key,
                               "a periodic face needs its opposite face %c_%s periodic too; set "
                               "both %c_lo and %c_hi to periodic",
                               g_axes[d], g_side[1 - s], g_axes[d], g_axes[d]);
      }
  return 0;
}

int mpm_walls_from_config(mpm_walls *w, const mpm_config *cfg, int dim) {
  memset(w, 0, sizeof *w);
  for (int d = 0; d < dim; ++d)
    for (int s = 0; s < 2; ++s) {
      char key[32];
      const char *v;
      snprintf(key, sizeof key, "boundary.%c_%s", g_axes[d], g_side[s]);
      MPM_CALL(mpm_config_get_string(cfg, key, &v));
      w->face[d][s] = MPM_WALL_NONE;
      for (int k = 0; k < MPM_WALL_COUNT; ++k)
        if (strcmp(v, g_wall_names[k]) == 0) w->face[d][s] = (mpm_wall)k;
    }
  MPM_CALL(check_periodic_pairs(w, cfg, dim));
  for (int d = dim; d < MPM_MAX_DIM; ++d)
    for (int s = 0; s < 2; ++s) {
      char key[32];
      const char *v;
      snprintf(key, sizeof key, "boundary.%c_%s", g_axes[d], g_side[s]);
      MPM_CALL(mpm_config_get_string(cfg, key, &v));
      if (strcmp(v, "none") != 0)
        return mpm_config_fail(cfg, key, "a %d-D domain has no %c axis; remove the key", dim,
                               g_axes[d]);
    }
  return 0;
}

void mpm_walls_periodic(const mpm_walls *w, int *periodic) {
  for (int d = 0; d < MPM_MAX_DIM; ++d)
    periodic[d] = w->face[d][0] == MPM_WALL_PERIODIC && w->face[d][1] == MPM_WALL_PERIODIC;
}

static int add_rule(mpm_node_constraints *c, mpm_lidx l, mpm_lidx source, unsigned char mask) {
  if (c->count == c->cap) {
    const mpm_lidx cap = c->cap ? 2 * c->cap : 256;
    mpm_lidx *node = realloc(c->node, sizeof *node * (size_t)cap);
    if (node) c->node = node;
    mpm_lidx *src = realloc(c->source, sizeof *src * (size_t)cap);
    if (src) c->source = src;
    unsigned char *m = realloc(c->mask, (size_t)cap);
    if (m) c->mask = m;
    if (!node || !src || !m) MPM_FAIL(MPM_ERR_MEMORY, "cannot grow the node constraints");
    c->cap = cap;
  }
  c->node[c->count] = l;
  c->source[c->count] = source;
  c->mask[c->count++] = mask;
  return 0;
}

int mpm_constraints_add(mpm_node_constraints *c, mpm_lidx l, unsigned char mask) {
  return add_rule(c, l, -1, mask);
}

int mpm_constraints_add_mirror(mpm_node_constraints *c, mpm_lidx l, mpm_lidx source,
                               unsigned char mask) {
  return add_rule(c, l, source, mask);
}

void mpm_grid_node_global(const mpm_grid *grid, mpm_lidx l, int *gi) {
  for (int d = 0; d < grid->dim; ++d) {
    gi[d] = grid->box_lo[d] + (int)(l % grid->box_n[d]);
    l /= grid->box_n[d];
  }
}

/* Components a wall of kind k on axis d constrains. */
static unsigned char wall_components(mpm_wall k, int d, int dim) {
  return k == MPM_WALL_NO_SLIP ? (unsigned char)((1u << dim) - 1) : (unsigned char)(1u << d);
}

/* Rules of one face: hold the face nodes, mirror the pad nodes beyond it. Nodes outside the
 * box (other ranks' parts of the face) are skipped. */
static int add_face(mpm_node_constraints *c, const mpm_grid *g, int d, int side,
                    unsigned char mask) {
  const int face = side == 0 ? 0 : g->ncells[d];
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[MPM_MAX_DIM];
    mpm_grid_node_global(g, l, gi);
    const int k = side == 0 ? face - gi[d] : gi[d] - face; /* distance beyond the face */
    if (k < 0) continue;
    if (k == 0) {
      MPM_CALL(add_rule(c, l, -1, mask));
      continue;
    }
    int gm[MPM_MAX_DIM];
    memcpy(gm, gi, sizeof gm);
    gm[d] = side == 0 ? face + k : face - k;
    if (gm[d] < g->box_lo[d] || gm[d] >= g->box_lo[d] + g->box_n[d]) continue;
    MPM_CALL(add_rule(c, l, mpm_grid_local_index(g, gm), mask));
  }
  return 0;
}

static void apply_pass(const mpm_node_constraints *c, mpm_grid *grid, int phase);

int mpm_constraints_add_walls(mpm_node_constraints *c, const mpm_walls *w, const mpm_grid *grid) {
  for (int d = 0; d < grid->dim; ++d)
    for (int s = 0; s < 2; ++s)
      if (w->face[d][s] == MPM_WALL_SLIP || w->face[d][s] == MPM_WALL_NO_SLIP)
        MPM_CALL(add_face(c, grid, d, s, wall_components(w->face[d][s], d, grid->dim)));
  return 0;
}

/* Faces were added axis by axis, so a corner pad node folds through the first wall into a
 * node that is still a pad node of the second wall, which then folds it inside. */
static void fold(const mpm_node_constraints *c, int dim, double *m, double *const *mv,
                 double *const *f) {
  for (mpm_lidx k = 0; k < c->count; ++k) {
    const mpm_lidx l = c->node[k], src = c->source[k];
    if (src < 0) continue;
    m[src] += m[l];
    m[l] = 0.0;
    for (int d = 0; d < dim; ++d) {
      const double sign = (c->mask[k] >> d) & 1 ? -1.0 : 1.0;
      mv[d][src] += sign * mv[d][l];
      mv[d][l] = 0.0;
      if (f) f[d][src] += sign * f[d][l], f[d][l] = 0.0;
    }
  }
}

void mpm_constraints_fold(const mpm_node_constraints *c, mpm_grid *grid, int phase) {
  mpm_grid_phase *ph = &grid->phase[phase];
  fold(c, grid->dim, ph->m_i, ph->mv_i, ph->f_i);
}

void mpm_constraints_fold_momentum(const mpm_node_constraints *c, const mpm_grid *grid, double *m,
                                   double *const *mv) {
  fold(c, grid->dim, m, mv, NULL);
}

/* One pass per axis: a corner pad node mirrors a node that is itself a pad node of another
 * wall, set in the previous pass. Clamps hold their nodes in every pass. */
void mpm_constraints_apply(const mpm_node_constraints *c, mpm_grid *grid, int phase) {
  for (int pass = 0; pass < grid->dim; ++pass) apply_pass(c, grid, phase);
}

static void apply_pass(const mpm_node_constraints *c, mpm_grid *grid, int phase) {
  mpm_grid_phase *ph = &grid->phase[phase];
  for (mpm_lidx k = 0; k < c->count; ++k) {
    const mpm_lidx l = c->node[k], src = c->source[k];
    for (int d = 0; d < grid->dim; ++d) {
      const int flip = (c->mask[k] >> d) & 1;
      if (src < 0) {
        if (flip) ph->v_i[d][l] = ph->a_i[d][l] = 0.0;
      } else {
        const double sign = flip ? -1.0 : 1.0;
        ph->v_i[d][l] = sign * ph->v_i[d][src];
        ph->a_i[d][l] = sign * ph->a_i[d][src];
      }
    }
  }
}

void mpm_constraints_free(mpm_node_constraints *c) {
  free(c->node);
  free(c->source);
  free(c->mask);
  memset(c, 0, sizeof *c);
}
