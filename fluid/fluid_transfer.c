/* The classic step's grid-to-particle transfer for the gas, with its energy balance.
 *
 * Over a step h the grid velocity goes from v_i^n to v_i^{n+1} = v_i^n + h a_i. The stress
 * works on the time-centred nodal velocity vbar_i = v_i^n + h a_i / 2: the particles' internal
 * energy takes h (V sigma : grad vbar) / m, and summed over the particles that is exactly
 * minus the change of the grid's kinetic energy, sum_i m_i (|v^{n+1}|^2 - |v^n|^2) / 2 (less
 * the work of gravity). The particles' own kinetic energy changes by a different amount,
 * because the transfer is not the grid's: FLIP adds h sum S a_i to v_p, PIC replaces v_p by
 * sum S v_i^{n+1}, APIC by that and an affine velocity. The difference (grid minus particles)
 * is split over the particles as heat, each share non-negative for FLIP/PIC blends:
 *
 *   FLIP: h^2 / 2 (sum S |a_i|^2 - |sum S a_i|^2), the spread of the nodal accelerations
 *         a particle reads (sums to the difference because sum_p m_p a_p . v_p =
 *         sum_i a_i . (m v)_i);
 *   PIC:  (sum S |v_i^{n+1}|^2 - |sum S v_i^{n+1}|^2) / 2, the spread of the velocities it
 *         reads, plus sum S |v_p - v_i^n|^2 / 2, the spread of its velocity about the nodal
 *         velocities it deposited into;
 *   blend a: (1 - a) FLIP + a PIC + a (1 - a) |v_FLIP - v_PIC|^2 / 2 (the convexity of |v|^2).
 *
 * APIC deposits an affine velocity the particle's |v|^2 does not count, so its share is the
 * plain difference sum S (|v_i^{n+1}|^2 - |v_i^n|^2) / 2 - (|v_new|^2 - |v_p|^2) / 2: exact in
 * sum, but not of one sign per particle.
 *
 * Every identity holds with walls (held components have v = a = 0; mirrored pad nodes fold
 * their deposits into their images), so a closed box conserves total energy to roundoff.
 *
 * Walls and FLIP. A wall holds its nodes' normal velocity at zero by setting v and a there, so
 * FLIP's increment h sum S a_i never takes back a velocity a particle has into the wall: a
 * particle at the wall keeps it (its position moves with the held nodes, so it stays), and
 * what the nodes above it push towards the wall adds to it step after step. On the main job a
 * particle in the stagnation corner at the bar's foot reached 10 km/s into the floor, set the
 * step and fed the coupling's energy booking. So where the FLIP velocity points into a wall
 * face (and in the tangential components a no-slip face holds), its share of the new velocity
 * is scaled by 1 - w, w the particle's weight on the face's nodes (its 1-D weight on the face
 * plane: 3/4 for a quadratic B-spline on the wall, 0 beyond one and a half cells): what PIC
 * reads from the held nodes. A wall only pushes, so a particle moving away from it keeps its
 * velocity: damping that too (or pulling the particle towards sum S v^{n+1} both ways) took
 * 4 % (2 %) off the lift on the wedge's ramp, whose flow turns up at the floor. The kinetic
 * energy removed becomes the particle's heat, so the identities above still hold.
 *
 * The ERK pairs' method of lines has the same blind spot (dv/dt = sum S a_i). There the rule
 * is a rate in the right-hand side (fluid_wall_rate_mol), so that the right-hand side stays a
 * function of the state alone and the pairs keep their order: the velocity into a wall face
 * relaxes at the rate (1 - keep) 2 c / dx, twice a cell's acoustic rate scaled by the same
 * weight, and de/dt takes the kinetic energy it removes (at c / dx the first layer of
 * test_gas_conservation's floor case kept 0.12 of the speed into the floor at t = 0.05; at
 * 2 c / dx 0.003, and at most 0.012 later, below the ringing of the layers above it). Applied
 * instead as the classic scaling after each accepted step, it made the damping depend on the step:
 * the piston's coupling error under MRIStep fell at order 0.27 instead of 2 (test_timeschemes_mri).
 * The rate is Lipschitz in the state (the weight is a B-spline of the position, and the normal
 * term vanishes as the velocity into the face does), with a kink in its derivative where that
 * velocity changes sign: a step across it errs at O(h^2) locally, and a particle crosses a finite
 * number of times, so the global error keeps order 2 but higher orders are not guaranteed (as
 * with the B-spline's kinks in the positions; measured 1.96-2.98 for bs32 on the piston). It is
 * explicit-stable: h c / dx is at most time.cfl < 1 and 1 - keep < 1, so h times the rate stays
 * below 2 time.cfl < 2, the end of euler's and ralston21's real stability interval (bs32's ends at
 * -2.5); with fluid.stable_step = neighbourhood a hot particle's own c may exceed the
 * neighbourhood's signal speed, and there the bound is the neighbourhood's.
 *
 * The PIC share as a rate. fluid.pic_fraction a is the share of a step of h_pic = 0.4 h_limit,
 * the step the gas takes alone at time.cfl = 0.4 (mpmfsi's default), h_limit its own stability
 * limit (mpm_module.h). A step h takes a_h = 1 - (1 - a)^(h / h_pic), the share that damps as
 * much per unit time, whatever sets the step (a step within roundoff of h_pic takes a itself).
 * Blended at a per step, PIC damps the particles' departure from the grid velocity by
 * (1 - a)^(t / h), so the gas's damping followed its step, not its physics:
 * - beside a stiff solid under monolithic coupling, at a tenth of its own step, the gas was
 *   damped ten times as fast as under multirate, and the two schemes solved different gases
 *   (the shock-loaded panel at 1 mm, the gas's steps seven times the panel's: tips 28 % apart at
 *   0.1 ms; 3 % with the rate);
 * - stated at the gas's own step at the run's time.cfl (the rate's first form, until
 *   2026-11-29), halving time.cfl still doubled the damping per unit time, and the solution
 *   did not converge as the step fell: on the panel at 1 mm (monolithic, usl) the tip at 0.3 ms
 *   was 555, 578, 617 and 766 um at time.cfl 0.4, 0.2, 0.1 and 0.025, each halving moving it
 *   more than the one before; the tip history's error against time.cfl = 0.05 fell at order
 *   0.3 (1.22e-4, 0.99e-4 m at 0.4, 0.2), and at order 1.04 without the share (1.30e-5,
 *   0.63e-5 m).
 * test_pic_rate checks the rate itself, at a quarter of the gas's step and at another time.cfl.
 * A gas that sets its own step at time.cfl = 0.4 is blended exactly as before. The heat shares
 * above hold for any blend, so the energy balance is unchanged. (Particle shifting is a rate
 * already: fluid_shift.c.)
 *
 * On a refinement hierarchy (mpm_hier.h) every nodal field above lives on every level: vbar on
 * each level's nodes (composite, since v and a are after the prolongation), the scalars formed
 * on each level's nodes and then prolonged into the inactive ones (a particle must read
 * sum_i w_ip s_i over the composite weights w it deposited with, or the shares' sums break;
 * |v|^2 of a prolonged v is not the prolongation of |v|^2), and the G2P reads the particle's
 * level (mpm_hier_g2p_from). The wall rule weighs a particle of level l at spacing h_l: no
 * level-l node lies on the wall (a knot there), so w is the weight a node on the wall would have
 * on a uniform grid of spacing h_l (the fine twin's rule; WALL_NODE below). The method of lines'
 * rate (fluid_wall_rate_mol) weighs it the same way and relaxes at 2 c / h_l, the rate of that
 * uniform grid (the global step is over h_l too, so the bound on h times the rate above holds
 * level by level). Weighed on level 0's nodes at 2 c / dx (until 2026-12-03) a pulse reflected
 * in a level-1 band touching a slip wall kept 0.986 of the uniform fine twin's energy, now
 * 0.9997 (test_refine_walls_pulse). */
#include "fluid_internal.h"

#include "mpm_error.h"
#include "mpm_hier.h"
#include "mpm_kernels.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The time.cfl at whose step fluid.pic_fraction is stated (see the file comment). */
#define FLUID_PIC_CFL 0.4

/* The PIC share of a step of size h (see the file comment). */
static double pic_share(const mpm_module *m, double pic, double h) {
  const double r = m->h_limit > 0.0 ? h / (FLUID_PIC_CFL * m->h_limit) : 1.0;
  if (!(pic > 0.0 && pic < 1.0) || fabs(r - 1.0) <= 1e-12) return pic;
  return -expm1(r * log1p(-pic));
}

/* The classic transfer's nodal fields on every level of the gas (level 0 alone without a
 * hierarchy): the time-centred velocity vbar and the scalars the G2P interpolates, each a
 * composite field (an inactive node holds the prolongation of its parents), in level 0's
 * fc->node and a finer level's fc->lnode[l], (dim + 3) nnodes each. */
typedef struct classic_nodal {
  int nlev;
  double *node[MPM_HIER_MAX_LEVELS];
  mpm_hier_nodal vbar;
  mpm_hier_scalars s; /* scalar k of level l; level 0's are also in the G2P's arguments */
} classic_nodal;

static const mpm_grid *level_grid(const mpm_module *m, int l) {
  return l ? m->hier->level[l].grid : m->grid;
}

/* vbar = v^{n+1} - h a / 2 on every node of every level, into c (its arrays set up here). On a
 * hierarchy v and a are composite after the prolongation, and so is vbar, node by node (the
 * prolongation is linear). */
static int centred_velocity(mpm_module *m, double h, classic_nodal *c) {
  fluid_content *fc = m->content;
  memset(c, 0, sizeof *c);
  c->nlev = m->hier ? m->hier->nlevels : 1;
  for (int l = 0; l < c->nlev; ++l) {
    const mpm_grid *g = level_grid(m, l);
    const mpm_grid_phase *ph = &g->phase[m->phase];
    const size_t nn = (size_t)g->nnodes;
    if (l && !fc->lnode[l]) MPM_ALLOC(fc->lnode[l], (size_t)(g->dim + 3) * nn);
    c->node[l] = l ? fc->lnode[l] : fc->node;
    for (int d = 0; d < g->dim; ++d) {
      double *vb = c->node[l] + (size_t)d * nn;
      for (mpm_lidx k = 0; k < g->nnodes; ++k) vb[k] = ph->v_i[d][k] - 0.5 * h * ph->a_i[d][k];
      c->vbar.v_i[l][d] = vb;
    }
  }
  return 0;
}

/* APIC's new affine velocity is that of v^{n+1} = vbar + h a / 2: add h/2 C(a). */
static int apic_half_step(mpm_module *m, const double *y, double h, double *C) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid_phase *ph = &m->grid->phase[m->phase];
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  double *Ca = fc->tscratch + (size_t)(dim + 3) * n, *dummy = Ca + (size_t)dim * dim * n;
  mpm_g2p_args a = {.n = n, .lp = fc->lp, .C_out = Ca};
  mpm_hier_nodal acc = {{{NULL}}};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n;
    a.v_i[d] = ph->a_i[d];
    a.a_i[d] = ph->a_i[d];
    a.v_out[d] = dummy + (size_t)d * n;
    a.a_out[d] = dummy + (size_t)(dim + d) * n;
    for (int l = 0; m->hier && l < m->hier->nlevels; ++l)
      acc.v_i[l][d] = level_grid(m, l)->phase[m->phase].a_i[d];
  }
  if (m->hier)
    MPM_CALL(mpm_hier_g2p_from(m->hier, m->phase, &a, &acc, NULL));
  else
    mpm_kernels_get(dim)->g2p(m->grid, &a);
  for (size_t k = 0; k < (size_t)dim * dim * (size_t)n; ++k) C[k] += 0.5 * h * Ca[k];
  return 0;
}

/* Scalar j of the heat shares on the nodes of level l into s: |a|^2, |v^{n+1}|^2 or |v^n|^2. */
static void level_scalar(const mpm_module *m, const classic_nodal *c, int l, int j, double h,
                         double *s) {
  const mpm_grid *g = level_grid(m, l);
  const mpm_grid_phase *ph = &g->phase[m->phase];
  const double *const *vbar = c->vbar.v_i[l];
  const double half = j == 1 ? 0.5 * h : -0.5 * h; /* v^{n+1} or v^n from vbar */
  for (mpm_lidx k = 0; k < g->nnodes; ++k) {
    double sum = 0.0;
    for (int d = 0; d < g->dim; ++d) {
      const double q = j == 0 ? ph->a_i[d][k] : vbar[d][k] + half * ph->a_i[d][k];
      sum += q * q;
    }
    s[k] = sum;
  }
}

/* The nodal scalars the heat shares need, |a|^2, |v^{n+1}|^2 and |v^n|^2 (FLIP needs the first,
 * a PIC share or APIC the other two), set up for interpolation in the G2P pass a: out[j]
 * receives scalar j at the particles. On a hierarchy each is computed on every node of a level
 * and then its inactive nodes take the prolongation of their parents, level 1 first: the
 * particles then read sum_i w_ip s_i over the composite weights they deposited with, on which
 * the heat shares' identities rest (a node's |v|^2 is not the prolongation of its parents'). */
static void nodal_scalars(mpm_module *m, classic_nodal *c, double h, double **out,
                          mpm_g2p_args *a) {
  const fluid_content *fc = m->content;
  const int dim = m->grid->dim, flip = !fc->tr.apic, pic = fc->tr.apic || fc->tr.pic > 0;
  for (int j = 0; j < 3; ++j) {
    if ((j == 0 && !flip) || (j > 0 && !pic)) continue;
    const int k = a->nscalar;
    for (int l = 0; l < c->nlev; ++l) {
      double *s = c->node[l] + (size_t)(dim + k) * level_grid(m, l)->nnodes;
      level_scalar(m, c, l, j, h, s);
      if (l) mpm_hier_prolong_level(m->hier, l, &c->s.s_i[l - 1][k], &s, 1);
      c->s.s_i[l][k] = s;
    }
    a->s_i[k] = c->s.s_i[0][k];
    a->s_out[a->nscalar++] = out[j];
  }
}

/* fluid.pressure = grid: the nodal volume rate of vbar on every level (and the pressure
 * relaxation's fields), more scalars of a, into fluid_gridp_rate_out (fluid_gridp_work reads
 * them). */
static int gridp_scalar(mpm_module *m, classic_nodal *c, mpm_g2p_args *a) {
  fluid_content *fc = m->content;
  if (!fc->gridp) return 0;
  mpm_hier_scalars r;
  MPM_CALL(fluid_gridp_nodal_rate(m, &c->vbar, &r));
  int ns;
  double *const *out = fluid_gridp_rate_out(fc, &ns);
  /* At most 3 heat scalars before these (nodal_scalars) and 4 of the grid pressure. */
  _Static_assert(3 + 4 <= MPM_KERNELS_MAX_SCALARS, "the classic G2P's scalars");
  assert(a->nscalar + ns <= MPM_KERNELS_MAX_SCALARS);
  for (int j = 0; j < ns; ++j) {
    const int k = a->nscalar++;
    for (int l = 0; l < c->nlev; ++l) c->s.s_i[l][k] = r.s_i[l][j];
    a->s_i[k] = r.s_i[0][j];
    a->s_out[k] = out[j];
  }
  return 0;
}

/* The new velocity and the heat share of particle i (see the file comment). */
static double new_velocity(const fluid_content *fc, int dim, double h, double pic, const double *v,
                           const double *a, const double *vhat, double *const *sc, mpm_lidx i,
                           double *vnew) {
  const double al = fc->tr.apic ? 1.0 : pic;
  double v2 = 0, a2 = 0, vP2 = 0, vvn = 0, dFP2 = 0;
  for (int d = 0; d < dim; ++d) {
    const double vF = v[d] + h * a[d], vP = vhat[d];
    vnew[d] = (1.0 - al) * vF + al * vP;
    v2 += v[d] * v[d], a2 += a[d] * a[d], vP2 += vP * vP;
    vvn += v[d] * (vP - h * a[d]); /* v_p . sum S v_i^n */
    dFP2 += (vF - vP) * (vF - vP);
  }
  if (fc->tr.apic) return 0.5 * (sc[1][i] - sc[2][i]) - 0.5 * (vP2 - v2);
  double heat = (1.0 - al) * 0.5 * h * h * (sc[0][i] - a2);
  if (al > 0)
    heat += al * (0.5 * (sc[1][i] - vP2) + 0.5 * (v2 - 2.0 * vvn + sc[2][i])) +
            0.5 * al * (1.0 - al) * dFP2;
  return heat;
}

/* The wall faces the rule of the file comment acts on (slip and no-slip), each with the band
 * of positions its nodes reach, found once per pass: most particles are far from every wall,
 * and a comparison with the band's edges rejects them without the division below. */
typedef struct wall_face {
  int ax, side, no_slip, F; /* F: the face's node index along ax */
  double lo, hi;            /* a particle outside (lo, hi) along ax has no weight on it */
} wall_face;

typedef struct wall_faces {
  int n;
  wall_face f[2 * MPM_MAX_DIM];
} wall_faces;

static void wall_faces_of(const fluid_content *fc, const mpm_grid *g, wall_faces *w) {
  /* The band is a little wider than the reach, so that roundoff in the comparison never
   * rejects a particle the exact test in wall_keep would keep. */
  const double reach = (0.5 * mpm_shape_support(g->shape) + fc->lp) * (1.0 + 1e-9) * g->dx;
  w->n = 0;
  for (int ax = 0; ax < g->dim; ++ax)
    for (int side = 0; side < 2; ++side) {
      const mpm_wall k = fc->walls.face[ax][side];
      if (k != MPM_WALL_SLIP && k != MPM_WALL_NO_SLIP) continue;
      const int F = side ? g->ncells[ax] : 0;
      const double x = g->lo[ax] + F * g->dx;
      w->f[w->n++] = (wall_face){ax, side, k == MPM_WALL_NO_SLIP, F, x - reach, x + reach};
    }
}

/* On a level l >= 1 no node lies on a wall face (it is a knot between two nodes: mpm_hier.h,
 * walls); the rule then weighs a particle as a uniform grid of the level's spacing would, on a
 * node at the face: the B-spline at (x - x_face) / h_l, evaluated about this node index. */
#define WALL_NODE 4

/* The level whose spacing the wall rule weighs particle i at: its position's (the RHS's
 * fc->lev, fluid_av_lengths), 0 without a hierarchy. */
static int wall_level(const mpm_module *m, mpm_lidx i) {
  const fluid_content *fc = m->content;
  return m->hier ? fc->lev[i] : 0;
}

/* The wall rule of the file comment: into keep[d], the factor on the FLIP share of velocity
 * component d of a particle at xp (1 away from the walls), on level `level` (0 unrefined).
 * Returns whether any is below 1. */
static int wall_keep(const fluid_content *fc, const mpm_grid *g, const wall_faces *w, int level,
                     const double *xp, const double *vF, double *keep) {
  const int dim = g->dim;
  const double reach = 0.5 * mpm_shape_support(g->shape) + fc->lp;
  int any = 0;
  for (int d = 0; d < dim; ++d) keep[d] = 1.0;
  for (int q = 0; q < w->n; ++q) {
    const wall_face *f = &w->f[q];
    const int ax = f->ax;
    if (!(xp[ax] > f->lo && xp[ax] < f->hi)) continue;
    double xi = (xp[ax] - g->lo[ax]) / g->dx;
    int F = f->F;
    if (level > 0) /* (the band above is level 0's, wider than level l's: it only prefilters) */
      xi = (xp[ax] - (g->lo[ax] + f->F * g->dx)) / ldexp(g->dx, -level) + WALL_NODE, F = WALL_NODE;
    if (fabs(xi - F) >= reach) continue;
    double wt[MPM_SHAPE_MAX_SUPPORT], dw[MPM_SHAPE_MAX_SUPPORT];
    const int s = F - mpm_shape_1d(g->shape, xi, fc->lp, wt, dw);
    if (s < 0 || s >= MPM_SHAPE_MAX_SUPPORT || wt[s] <= 0.0) continue;
    for (int d = 0; d < dim; ++d) {
      const int into = f->side ? vF[d] > 0.0 : vF[d] < 0.0; /* the normal: only into the wall */
      if ((d == ax && into) || (d != ax && f->no_slip)) keep[d] *= 1.0 - wt[s], any = 1;
    }
  }
  return any;
}

/* The G2P of the classic step: vhat, a_p, L, C and the scalars at the particles of state y. */
static int classic_g2p(mpm_module *m, const double *y, double h, const fluid_step_out *o,
                       double *const *ap, double **sc) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  classic_nodal c;
  MPM_CALL(centred_velocity(m, h, &c));
  mpm_g2p_args a = {.n = n, .lp = fc->lp, .L_out = o->L, .C_out = o->C};
  for (int d = 0; d < dim; ++d) {
    a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n;
    a.v_i[d] = c.vbar.v_i[0][d];
    a.a_i[d] = m->grid->phase[m->phase].a_i[d];
    a.v_out[d] = o->vhat[d];
    a.a_out[d] = ap[d];
  }
  nodal_scalars(m, &c, h, sc, &a);
  MPM_CALL(gridp_scalar(m, &c, &a));
  if (m->hier)
    MPM_CALL(mpm_hier_g2p_from(m->hier, m->phase, &a, &c.vbar, &c.s));
  else
    mpm_kernels_get(dim)->g2p(m->grid, &a);
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx i = 0; i < n; ++i) o->vhat[d][i] += 0.5 * h * ap[d][i];
  if (o->C) MPM_CALL(apic_half_step(m, y, h, o->C));
  return 0;
}

int fluid_classic_transfer(mpm_module *m, const double *y, double h, const fluid_step_out *o) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  double *ap[MPM_MAX_DIM] = {NULL}, *sc[3];
  for (int d = 0; d < dim; ++d) ap[d] = fc->tscratch + (size_t)d * n;
  for (int j = 0; j < 3; ++j) sc[j] = fc->tscratch + (size_t)(dim + j) * n;
  wall_faces w;
  wall_faces_of(fc, g, &w);
  const double pic = pic_share(m, fc->tr.pic, h);
  MPM_CALL(classic_g2p(m, y, h, o, ap, sc));
  for (mpm_lidx i = 0; i < n; ++i) {
    double v[MPM_MAX_DIM], acc[MPM_MAX_DIM], vh[MPM_MAX_DIM], vn[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) {
      v[d] = y[(size_t)(p->offset[FLUID_V] + d) * n + i];
      acc[d] = ap[d][i], vh[d] = o->vhat[d][i];
    }
    o->heat[i] = new_velocity(fc, dim, h, pic, v, acc, vh, sc, i, vn);
    double xp[MPM_MAX_DIM], vF[MPM_MAX_DIM], keep[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d)
      xp[d] = y[(size_t)(p->offset[FLUID_X] + d) * n + i], vF[d] = v[d] + h * acc[d];
    if (!fc->tr.apic && wall_keep(fc, g, &w, wall_level(m, i), xp, vF, keep))
      for (int d = 0; d < dim; ++d) {
        double damped = vn[d] - (1.0 - keep[d]) * (1.0 - pic) * vF[d];
        /* With a PIC share the blend may already point elsewhere: never push it further or
         * past zero, so the heat is never negative (with FLIP alone, damped = keep vn). */
        if (damped * vn[d] <= 0.0) damped = 0.0;
        if (fabs(damped) > fabs(vn[d])) damped = vn[d];
        o->heat[i] += 0.5 * (vn[d] * vn[d] - damped * damped);
        vn[d] = damped;
      }
    for (int d = 0; d < dim; ++d) o->vnew[d][i] = vn[d];
  }
  return 0;
}

void fluid_wall_rate_mol(const mpm_module *m, const double *y, double *const *vdot, double *power) {
  const fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  const mpm_grid *g = m->grid;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double gamma = fc->gas.gamma;
  const double *e = y + (size_t)p->offset[FLUID_E] * n;
  wall_faces w;
  wall_faces_of(fc, g, &w);
  for (mpm_lidx i = 0; w.n > 0 && i < n; ++i) {
    double xp[MPM_MAX_DIM] = {0}, v[MPM_MAX_DIM] = {0}, keep[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d)
      xp[d] = y[(size_t)(p->offset[FLUID_X] + d) * n + i],
      v[d] = y[(size_t)(p->offset[FLUID_V] + d) * n + i];
    const int level = wall_level(m, i);
    if (!wall_keep(fc, g, &w, level, xp, v, keep)) continue;
    const double h_l = ldexp(g->dx, -level); /* the level's spacing, wall_keep's */
    const double rate = 2.0 * sqrt(gamma * (gamma - 1.0) * fabs(e[i])) / h_l; /* 2 c / h_l */
    for (int d = 0; d < dim; ++d) {
      const double k = rate * (1.0 - keep[d]);
      vdot[d][i] -= k * v[d];
      power[i] += k * v[d] * v[d];
    }
  }
}

/* fluid.mol_damping. The method of lines moves the particles with the grid velocity and gives
 * them the grid's acceleration, so the grid sees a particle velocity only through its deposit.
 * Where the particles sit off their seeding lattice (after an acoustic pulse has passed: its
 * heavier particles expanded by 1 %), the force a uniform pressure puts on the nodes depends on
 * the particles' positions (its quadrature, sum V p grad S(x_p), is exact on the lattice only),
 * and that dependence is not symmetric: linearised about the gas at rest after the pulse, the
 * nodal stiffness K has an antisymmetric part 8 % of its size, and the grid's highest modes
 * (about 3 cells by 2.7) flutter, growing x3.8 per unit time on the pulse with farfield faces
 * (a model with K symmetrised is stable; the lumped or a consistent mass matrix is not the
 * cause, nor the step, the strain rate or the viscosity: usl at time.cfl = 0.1 grows it too).
 * Those modes carry most of their particle velocity where the deposit does not see it (the
 * lumped deposit returns 16 % of it). The damping relaxes q = (1 - P) v at k = mol_damping
 * c / dx, P the deposit-and-gather below, and filters the relaxation once more through 1 - P,
 * so that dv/dt = -(1 - P)(k q): momentum is exact (sum m (1 - P) s = 0 for any s), and since
 * P is self-adjoint in the mass-weighted product the kinetic energy removed is sum m k |q|^2,
 * which each particle takes as heat k |q|^2 >= 0. A resolved wave of wavenumber kx has
 * 1 - P ~ (kx dx)^2 / 4 per axis, squared here: the pulse's peak lost 0.07 % in four crossings
 * (1.4 % with one filter at half the rate). */

/* v = m v / m on the nn nodes of phase ph (0 where empty). */
static void mean_velocity(mpm_grid_phase *ph, mpm_lidx nn, int dim) {
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx l = 0; l < nn; ++l)
      ph->v_i[d][l] = ph->m_i[l] > 0.0 ? ph->mv_i[d][l] / ph->m_i[l] : 0.0;
}

/* The filtered velocity P s of particle velocities s: deposit m s into the filter's phase, sum
 * the ranks' halos, divide by the nodal mass and interpolate back. sum_p m_p (P s)_p =
 * sum_i (m s)_i = sum_p m_p s_p exactly, whatever the walls and other phases do, because the
 * phase holds these particles alone. */
static int filter(mpm_module *m, const double *y, double *const *s, double *const *out,
                  double *dummy, int deposited) {
  fluid_content *fc = m->content;
  const mpm_particles *p = m->particles;
  mpm_grid *g = m->grid;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  mpm_grid_phase *ph = &g->phase[fc->filter_phase];
  mpm_p2g_args a = {.n = n, .m = mpm_particles_comp(p, fc->lay.f_m, 0), .lp = fc->lp};
  for (int d = 0; d < dim; ++d) a.x[d] = y + (size_t)(p->offset[FLUID_X] + d) * n, a.v[d] = s[d];
  if (!deposited || m->hier) { /* (else fluid_p2g copied the velocities' own deposit here) */
    int rc = 0;
    if (m->hier)
      mpm_hier_phase_zero(m->hier, fc->filter_phase);
    else
      mpm_grid_phase_zero(g, fc->filter_phase);
    fluid_p2g_any(m, fc->filter_phase, &a, &rc);
    MPM_CALL(rc);
  }
  if (m->hier) mpm_hier_restrict(m->hier, fc->filter_phase);
  double *f[1 + MPM_MAX_DIM];
  f[0] = ph->m_i;
  for (int d = 0; d < dim; ++d) f[1 + d] = ph->mv_i[d];
  MPM_CALL(mpm_grid_halo_reverse(g, f, 1 + dim));
  /* No empty-node threshold: m s / m is a weighted mean of the s that reached the node. */
  for (int l = 0; l < (m->hier ? m->hier->nlevels : 1); ++l)
    mean_velocity(l ? &m->hier->level[l].grid->phase[fc->filter_phase] : ph,
                  l ? m->hier->level[l].grid->nnodes : g->nnodes, dim);
  for (int d = 0; d < dim; ++d) f[d] = ph->v_i[d];
  MPM_CALL(mpm_grid_halo_forward(g, f, dim));
  mpm_g2p_args b = {.n = n, .lp = fc->lp};
  for (int d = 0; d < dim; ++d) {
    b.x[d] = a.x[d];
    b.v_i[d] = b.a_i[d] = ph->v_i[d];
    b.v_out[d] = out[d], b.a_out[d] = dummy + (size_t)d * n;
  }
  if (!m->hier) {
    mpm_kernels_get(dim)->g2p(g, &b);
    return 0;
  }
  mpm_hier_prolong(m->hier, fc->filter_phase);
  return mpm_hier_g2p(m->hier, fc->filter_phase, &b, NULL);
}

int fluid_mol_damping(mpm_module *m, const double *y, double *const *vdot, double *power,
                      double *work) {
  const fluid_content *fc = m->content;
  if (!(fc->mol_damping > 0.0) || fc->filter_phase < 0) return 0;
  const mpm_particles *p = m->particles;
  const int dim = p->dim;
  const mpm_lidx n = p->n;
  const double gamma = fc->gas.gamma, beta = fc->mol_damping / m->grid->dx;
  const double *e = y + (size_t)p->offset[FLUID_E] * n, *v = y + (size_t)p->offset[FLUID_V] * n;
  double *vp[MPM_MAX_DIM], *q[MPM_MAX_DIM], *s[MPM_MAX_DIM], *ps[MPM_MAX_DIM];
  double *dummy = work + (size_t)3 * dim * n;
  for (int d = 0; d < dim; ++d) {
    vp[d] = (double *)v + (size_t)d * n;
    q[d] = work + (size_t)d * n, s[d] = work + (size_t)(dim + d) * n;
    ps[d] = work + (size_t)(2 * dim + d) * n;
  }
  MPM_CALL(filter(m, y, vp, q, dummy, 1)); /* q = (1 - P) v, the velocity the grid does not see */
  for (mpm_lidx i = 0; i < n; ++i) {
    const double k = beta * sqrt(gamma * (gamma - 1.0) * fabs(e[i])); /* beta c / dx */
    for (int d = 0; d < dim; ++d) {
      q[d][i] = v[(size_t)d * n + i] - q[d][i];
      s[d][i] = k * q[d][i];
      power[i] += k * q[d][i] * q[d][i];
    }
  }
  MPM_CALL(filter(m, y, s, ps, dummy, 0));
  for (int d = 0; d < dim; ++d)
    for (mpm_lidx i = 0; i < n; ++i) vdot[d][i] -= s[d][i] - ps[d][i];
  return 0;
}
