/* The solid's constraints and loads: walls and clamps (nodes held, listed once at build), rigid
 * bodies (nodes inside their moving region held at their velocity; their particles moved with
 * it), and surface tractions (a constant force on the tagged surface particles). See
 * solid_internal.h. */
#include "solid_internal.h"

#include "mpm_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int solid_in_clamp(const solid_content *sc, const double *x) {
  for (int k = 0; k < sc->nclamps; ++k)
    if (mpm_region_contains(sc->clamp[k], x)) return 1;
  return 0;
}

/* Tractions: the force of a tagged particle is t A_p with A_p = h^(dim-1), h = dx/ppc the
 * particle spacing: its share of the loaded face, if the traction's region covers exactly the
 * outermost particle layer there. Then the total force on a face aligned with the axes is t
 * times the face's area exactly, whatever the region's own extent (a region's surface area is
 * not the loaded area: a box around the end of a bar has five other faces). On a slanted or
 * curved face the layer is a staircase and the total is too large by up to |n_x| + |n_y|
 * (+ |n_z|) for unit normal n, so load axis-aligned faces. A particle is on its body's
 * surface if one of its 2 dim lattice neighbours (at +-h along an axis) is outside the body's
 * region; a tagged particle that is not (a region two layers deep, or inside the body) is
 * recorded, and seeding then fails naming the traction. Rigid bodies are not loaded: their
 * motion is prescribed. */
void solid_traction_force(solid_content *sc, const mpm_region *body, int dim, double h,
                          const double *xp, mpm_gidx id, double *f) {
  const double area = pow(h, dim - 1);
  for (int k = 0; k < sc->ntractions; ++k) {
    solid_traction *tr = &sc->traction[k];
    if (!mpm_region_contains(tr->region, xp)) continue;
    int surface = 0;
    for (int d = 0; d < dim && !surface; ++d)
      for (int side = -1; side <= 1 && !surface; side += 2) {
        double y[3] = {xp[0], xp[1], dim == 3 ? xp[2] : 0.0};
        y[d] += side * h;
        surface = !mpm_region_contains(body, y);
      }
    if (!surface && (tr->off_id < 0 || id < tr->off_id)) {
      tr->off_id = id;
      memcpy(tr->off_x, xp, sizeof tr->off_x);
    }
    tr->tagged++;
    for (int d = 0; d < dim; ++d) {
      f[d] += tr->t[d] * area;
      tr->force[d] += tr->t[d] * area;
    }
  }
}

/* Does the rigid body hold the node of global index gi at time t: is the node inside the
 * body's region translated by v t? Along a periodic axis the body wraps: the node's canonical
 * image (index in [0, ncells)) moved back by v t is wrapped into [lo, hi) before the test, and
 * a point on the seam lo is tried at hi as well. */
static int rigid_holds(const solid_body *body, const mpm_grid *g, const int *gi, double t) {
  double x[3] = {0, 0, 0};
  int seam = 0;
  for (int d = 0; d < g->dim; ++d) {
    if (!g->periodic[d]) {
      x[d] = g->lo[d] + gi[d] * g->dx - body->v[d] * t;
      continue;
    }
    const int n = g->ncells[d], k = ((gi[d] % n) + n) % n;
    const double len = g->hi[d] - g->lo[d];
    double y = fmod(g->lo[d] + k * g->dx - body->v[d] * t - g->lo[d], len);
    if (y < 0) y += len;
    x[d] = g->lo[d] + y;
    seam |= y == 0.0;
  }
  if (mpm_region_contains(body->region, x)) return 1;
  if (!seam) return 0;
  for (int d = 0; d < g->dim; ++d)
    if (g->periodic[d] && x[d] == g->lo[d]) x[d] = g->hi[d];
  return mpm_region_contains(body->region, x);
}

/* A rigid body holds every box node inside its moving region (rigid_holds) at its velocity v,
 * with zero acceleration: a clamp that moves. The rule is geometric, so each rank applies it
 * to all its box nodes, owned and ghost, and gets what any other decomposition gets. Along a
 * non-periodic axis only the nodes of the translated bounding box (and one more layer, against
 * rounding in the index conversion; the test decides) are visited; along a periodic axis,
 * all. */
void solid_hold_rigid_nodes(const solid_body *body, mpm_grid *g, int phase, double t) {
  mpm_grid_phase *ph = &g->phase[phase];
  const int dim = g->dim;
  double lo[3], hi[3];
  int first[3] = {0, 0, 0}, last[3] = {0, 0, 0}, gi[3] = {0, 0, 0};
  mpm_region_bounds(body->region, lo, hi);
  for (int d = 0; d < dim; ++d) {
    const double shift = body->v[d] * t, b0 = g->box_lo[d], b1 = g->box_lo[d] + g->box_n[d] - 1;
    first[d] = (int)b0, last[d] = (int)b1;
    if (g->periodic[d]) continue;
    /* clamped in floating point, so a far-away region cannot overflow the conversion */
    first[d] = (int)fmin(fmax(floor((lo[d] + shift - g->lo[d]) / g->dx) - 1.0, b0), b1 + 1.0);
    last[d] = (int)fmax(fmin(ceil((hi[d] + shift - g->lo[d]) / g->dx) + 1.0, b1), b0 - 1.0);
  }
  for (gi[2] = first[2]; gi[2] <= last[2]; ++gi[2])
    for (gi[1] = first[1]; gi[1] <= last[1]; ++gi[1])
      for (gi[0] = first[0]; gi[0] <= last[0]; ++gi[0]) {
        if (!rigid_holds(body, g, gi, t)) continue;
        const mpm_lidx l = mpm_grid_local_index(g, gi);
        for (int d = 0; d < dim; ++d) ph->v_i[d][l] = body->v[d], ph->a_i[d][l] = 0.0;
      }
}

/* Clamped particles keep their place and velocity, which is zero: they are seeded at rest
 * whatever their body's velocity (solid_module.c). A clamp over a body given a velocity kept it
 * on its particles, and their P2G put that momentum on the nodes at the clamp's edge, which the
 * clamp does not hold: where the solid advances those nodes alone (multirate's held exchange)
 * they moved at it, stretching the face layer of a clamped slab by 13 % and pulling the gas
 * into it (tests/verification/test_multirate_face.py). Their deformation gradient (and stress)
 * still follows the grid: those at the edge of a clamp carry the reaction stress, which a
 * frozen F would drop, turning the clamp's edge into a hinge. */
void solid_hold_fixed(const mpm_particles *p, int f_fixed, double *ydot) {
  const double *fixed = mpm_particles_comp(p, f_fixed, 0);
  for (int c = 0; c < 2 * p->dim; ++c) /* the x and v fields */
    for (mpm_lidx i = 0; i < p->n; ++i)
      if (fixed[i] != 0.0) ydot[(size_t)c * p->n + i] = 0.0;
}

/* Entries idx[0..count) of ncomp component arrays with stride n (component c at a + c n) take
 * the values val[c], or 0 if val is NULL. */
static void set_entries(double *a, mpm_lidx n, int ncomp, const mpm_lidx *idx, mpm_lidx count,
                        const double *val) {
  for (int c = 0; c < ncomp; ++c) {
    double *ac = a + (size_t)c * n;
    const double x = val ? val[c] : 0.0;
    for (mpm_lidx k = 0; k < count; ++k) ac[idx[k]] = x;
  }
}

/* A rigid body's particles move with its velocity whatever the grid says: dx/dt = v,
 * dv/dt = 0, dF/dt = 0, and under APIC dC/dt = 0 (C stays 0: no velocity gradient). A rigid
 * body has no rate-form stress, so its sigma rate stays 0. Particles are grouped by body as
 * in this RHS's P2G. */
void solid_move_rigid(const solid_content *sc, const mpm_particles *p, double *ydot) {
  const int dim = p->dim;
  const mpm_lidx n = p->n, *idx = sc->idx;
  for (int b = 0; b < sc->nbodies; idx += sc->count[b++]) {
    if (!sc->body[b].region) continue;
    const mpm_lidx count = sc->count[b];
    set_entries(ydot + (size_t)p->offset[F_X] * n, n, dim, idx, count, sc->body[b].v);
    set_entries(ydot + (size_t)p->offset[F_V] * n, n, dim, idx, count, NULL);
    set_entries(ydot + (size_t)p->offset[F_F] * n, n, dim * dim, idx, count, NULL);
    if (sc->lay.f_C >= 0)
      set_entries(ydot + (size_t)p->offset[sc->lay.f_C] * n, n, dim * dim, idx, count, NULL);
  }
}

/* MUSL's new particle velocities v (dim arrays with stride n): a rigid body's keep its v. */
void solid_rigid_velocity(const solid_content *sc, int dim, mpm_lidx n, double *v) {
  const mpm_lidx *idx = sc->idx;
  for (int b = 0; b < sc->nbodies; idx += sc->count[b++])
    if (sc->body[b].region) set_entries(v, n, dim, idx, sc->count[b], sc->body[b].v);
}

/* A clamp holds the nodes nearest its boundary: a node is held if the region contains it or
 * a point half a cell from it along an axis. Holding only the nodes strictly inside puts
 * the effective root of a clamped bar up to a cell inside the clamp (B-splines do not
 * interpolate), a first-order error that dominated CSM1 (tip uy +8.7 % at dx = 5 mm, against
 * +2.8 % when the node line at the clamp's face is held). With wall set (a finer level of a
 * hierarchy, g0 its level 0), a point on or beyond a wall does not count: there the level's nodes
 * lie half a cell off the wall, and the clamp acts through its pad nodes (hold_clamped). */
static int clamps_node(const solid_content *sc, const double *x, double half, int dim,
                       const mpm_grid *g0, const unsigned char (*wall)[2]) {
  if (solid_in_clamp(sc, x)) return 1;
  for (int d = 0; d < dim; ++d)
    for (int s = -1; s <= 1; s += 2) {
      double y[3] = {x[0], x[1], x[2]};
      y[d] += s * half;
      if (wall && ((wall[d][0] && y[d] <= g0->lo[d]) || (wall[d][1] && y[d] >= g0->hi[d])))
        continue;
      if (solid_in_clamp(sc, y)) return 1;
    }
  return 0;
}

static void node_x(const mpm_grid *g, mpm_lidx l, double *x) {
  int gi[MPM_MAX_DIM];
  mpm_grid_node_global(g, l, gi);
  for (int d = 0; d < g->dim; ++d) x[d] = g->lo[d] + gi[d] * g->dx;
}

/* Add every node of grid g that a clamp holds to c: level 0's grid (h NULL; its nodes on a wall
 * are held with the rest, its pad nodes are the wall's), or finer level l of hierarchy h. There
 * a wall is a knot, its nearest nodes half a cell inside and beyond it: a pad node whose point
 * on the wall, between it and its mirror, lies in a clamp mirrors it with every component negated
 * (a no-slip patch: zero velocity on the wall there, as a clamp holds level 0's wall node),
 * where the wall alone would mirror it slip; interior nodes are held by the rule above, the
 * wall's plane left out. A pad node beyond two walls (a corner) is left to the walls: a clamp
 * reaching into a corner mirrors its pads there with the walls' masks, not all components. */
static int hold_clamped(const solid_content *sc, const mpm_grid *g, const mpm_hier *h, int l,
                        mpm_node_constraints *c) {
  const unsigned char all = (unsigned char)((1u << g->dim) - 1);
  const unsigned char(*wall)[2] = h ? (const unsigned char(*)[2])h->wall : NULL;
  const mpm_grid *g0 = h ? h->level[0].grid : g;
  for (mpm_lidx n = 0; n < g->nnodes; ++n) {
    double x[3] = {0, 0, 0};
    node_x(g, n, x);
    int pad = 0, axis = -1;
    mpm_lidx mirror = -1;
    for (int d = 0; h && d < g->dim; ++d) {
      const mpm_lidx s = mpm_hier_wall_mirror(h, l, d, n);
      if (s >= 0) ++pad, axis = d, mirror = s;
    }
    if (pad == 1) {
      double y[3] = {x[0], x[1], x[2]}; /* the wall's point between n and its mirror, exactly */
      y[axis] = x[axis] < g0->lo[axis] ? g0->lo[axis] : g0->hi[axis];
      if (solid_in_clamp(sc, y)) MPM_CALL(mpm_constraints_add_mirror(c, n, mirror, all));
    }
    if (!pad && clamps_node(sc, x, 0.5 * g->dx, g->dim, g0, wall))
      MPM_CALL(mpm_constraints_add(c, n, all));
  }
  return 0;
}

/* Walls on the domain faces and clamped regions ([clamp.NAME] geometry = ...): the nodes
 * they hold, listed once. */
int solid_read_constraints(mpm_module *m, const mpm_config *cfg) {
  solid_content *sc = m->content;
  const mpm_grid *g = m->grid;
  mpm_walls walls;
  MPM_CALL(mpm_walls_from_config(&walls, cfg, g->dim));
  MPM_CALL(mpm_constraints_add_walls(&sc->cons, &walls, g));
  const char *const *names;
  int count;
  MPM_CALL(mpm_config_instances(cfg, "clamp", &names, &count));
  if (count == 0) return 0;
  MPM_ALLOC(sc->clamp, count);
  for (int k = 0; k < count; ++k) {
    char key[160];
    const char *geom;
    snprintf(key, sizeof key, "clamp.%s.geometry", names[k]);
    MPM_CALL(mpm_config_get_string(cfg, key, &geom));
    MPM_CALL(mpm_region_from_config(&sc->clamp[k], cfg, g->dim, geom));
    sc->nclamps = k + 1;
  }
  return hold_clamped(sc, g, NULL, 0, &sc->cons);
}

int solid_clamp_levels(mpm_module *m) {
  solid_content *sc = m->content;
  for (int l = 1; l < MPM_HIER_MAX_LEVELS; ++l) mpm_constraints_free(&sc->lcons[l]); /* (clears) */
  for (int l = 1; m->hier && sc->nclamps > 0 && l < m->hier->nlevels; ++l)
    MPM_CALL(hold_clamped(sc, m->hier->level[l].grid, m->hier, l, &sc->lcons[l]));
  return 0;
}

/* A rigid body's velocity and region (read on restarts too: the nodes it holds follow from
 * them and the time). */
int solid_read_rigid(mpm_module *m, const mpm_config *cfg, solid_body *body) {
  solid_content *sc = m->content;
  char key[160];
  const char *geom;
  solid_key(key, sizeof key, body->section, "velocity_field");
  if (mpm_config_has(cfg, key))
    return mpm_config_fail(cfg, key,
                           "a rigid body moves with one constant velocity; give velocity = "
                           "vx vy [vz] instead");
  MPM_CALL(solid_body_velocity(cfg, body->section, m->grid->dim, body->v));
  solid_key(key, sizeof key, body->section, "geometry");
  MPM_CALL(mpm_config_get_string(cfg, key, &geom));
  MPM_CALL(mpm_region_from_config(&body->region, cfg, m->grid->dim, geom));
  sc->nrigid++;
  return 0;
}

/* The [traction.NAME] sections: value and region. */
int solid_read_tractions(mpm_module *m, const mpm_config *cfg) {
  solid_content *sc = m->content;
  const int dim = m->grid->dim;
  const char *const *names;
  int count;
  MPM_CALL(mpm_config_instances(cfg, "traction", &names, &count));
  if (count == 0) return 0;
  MPM_ALLOC(sc->traction, count);
  for (int k = 0; k < count; ++k) {
    solid_traction *tr = &sc->traction[k];
    char key[160];
    const char *geom;
    int nv;
    snprintf(tr->name, sizeof tr->name, "%s", names[k]);
    tr->off_id = -1;
    snprintf(key, sizeof key, "traction.%s.value", names[k]);
    MPM_CALL(mpm_config_get_reals(cfg, key, tr->t, 3, &nv));
    if (nv != dim)
      return mpm_config_fail(cfg, key, "needs %d values (one per axis), got %d", dim, nv);
    snprintf(key, sizeof key, "traction.%s.geometry", names[k]);
    MPM_CALL(mpm_config_get_string(cfg, key, &geom));
    MPM_CALL(mpm_region_from_config(&tr->region, cfg, dim, geom));
    sc->ntractions = k + 1;
  }
  return 0;
}

/* "(x, y)" or "(x, y, z)". */
static const char *show_point(char *s, size_t size, int dim, const double *x) {
  if (dim == 3)
    snprintf(s, size, "(%.6g, %.6g, %.6g)", x[0], x[1], x[2]);
  else
    snprintf(s, size, "(%.6g, %.6g)", x[0], x[1]);
  return s;
}

/* After seeding: every traction must have tagged particles, all on their bodies' surfaces.
 * Collective; the first misplaced particle (smallest id) is named whichever rank holds it. */
int solid_check_tractions(mpm_module *m, const mpm_config *cfg) {
  const solid_content *sc = m->content;
  const MPI_Comm comm = m->grid->comm;
  const int dim = m->grid->dim;
  for (int k = 0; k < sc->ntractions; ++k) {
    const solid_traction *tr = &sc->traction[k];
    char key[160];
    const char *geom;
    mpm_gidx total, off, local_off = tr->off_id < 0 ? INT64_MAX : tr->off_id;
    double x[3] = {0, 0, 0}, force[3];
    char at[96];
    snprintf(key, sizeof key, "traction.%s.geometry", tr->name);
    MPM_CALL(mpm_config_get_string(cfg, key, &geom));
    MPM_CALL_MPI(MPI_Allreduce(&tr->tagged, &total, 1, MPM_MPI_GIDX, MPI_SUM, comm));
    if (total == 0)
      return mpm_config_fail(cfg, key,
                             "region '%s' holds no particle of a deformable solid body at "
                             "seeding, so the traction would act on nothing; the region must "
                             "cover the outermost particle layer of the loaded face",
                             geom);
    MPM_CALL_MPI(MPI_Allreduce(&local_off, &off, 1, MPM_MPI_GIDX, MPI_MIN, comm));
    if (off != INT64_MAX) {
      double mine[3] = {0, 0, 0};
      if (off == tr->off_id) memcpy(mine, tr->off_x, sizeof mine);
      MPM_CALL_MPI(MPI_Allreduce(mine, x, 3, MPI_DOUBLE, MPI_SUM, comm));
      return mpm_config_fail(cfg, key,
                             "region '%s' holds the particle at %s, which is not on its "
                             "body's surface (its neighbours at one particle spacing are all "
                             "inside the body); the region must cover only the outermost "
                             "particle layer of the loaded face (thinner than dx/ppc)",
                             geom, show_point(at, sizeof at, dim, x));
    }
    MPM_CALL_MPI(MPI_Allreduce(tr->force, force, 3, MPI_DOUBLE, MPI_SUM, comm));
    mpm_log(MPM_LOG_INFO, "traction %s: %lld particles, total force %s N%s", tr->name,
            (long long)total, show_point(at, sizeof at, dim, force),
            dim == 2 ? " per unit depth" : "");
  }
  return 0;
}
