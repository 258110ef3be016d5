/* Particle shifting of the gas (fluid.shift = kappa, every fluid.shift_every accepted steps).
 *
 * Why. A gas particle carries its own volume J V0, and the pressure it exerts follows from it;
 * nothing in the MPM update ties that volume to how far the particle actually is from its
 * neighbours. Under strong expansion (a rarefaction fan's tail, a near vacuum, the wake of a
 * bluff body) the particles drift into clusters a few cells apart: each cluster moves with the
 * nodal velocity it shares, the particles' volumes still describe the smooth expanding gas, and
 * no pressure force pushes a cluster apart. The nodal density then alternates between a few
 * times the true value and near zero, an error that does not fall under refinement (measured on
 * the double rarefaction: L1 density 0.027-0.029 at 200, 400 and 800 cells).
 *
 * What. The particles' volumes, spread onto the nodes with the shape functions, give the
 * nodal volume fraction phi_i = sum_p S_i(x_p) J_p V0_p / dx^dim, which is 1 wherever the
 * particles tile the gas as their volumes say. Each particle moves down its gradient,
 *   delta x_p = -kappa dx (c_p + |v_p|) h sum_i phi_i grad S_i(x_p),
 * h the step (times shift_every), each component capped at a quarter of a cell: a cluster
 * (phi > 1) spreads into the thinned space around it (phi < 1). It is a diffusion of the
 * positions at the rate D = kappa dx (c + |v|), as in the particle shifting of SPH, so that the
 * shift per unit of simulated time does not depend on the step: a run whose step falls (hot
 * particles somewhere) does not shift more. The fastest particle moves kappa CFL dx^2 |grad phi|
 * per step. (A first form without the rate, kappa dx^2 per step, broke the double rarefaction
 * at kappa = 0.075, 200 cells: its step fell fourfold early on and the extra shifts per unit
 * time pushed the gas out of the fans, L1 density 0.14.) Only positions change: mass, momentum,
 * total energy and the gas's volume are unchanged exactly. In uniform gas phi is 1 and nothing
 * moves.
 *
 * When. With fluid.shift_expansion = J_min > 0 only particles that have expanded, J >= J_min
 * since they were seeded, move (by default every particle moves). In uniform gas shifting only
 * adds noise (measured on uniform Mach 2.5 flow along a slip wall: an RMS pressure deviation of
 * 1.1 % with every particle shifted against 0.1 % without; J_min = 1.2 keeps the 0.1 %), but
 * the hot, compressed particles in front of a thin plate need it (with J_min = 1.2 the plate of
 * cases/plate_across.ini blew up at dx = 0.005, t = 0.24). The volume fraction counts every
 * particle.
 *
 * Where. At a non-periodic domain face the volume fraction is folded about the face (the
 * images of the particles beyond it are counted), so a wall or an open face does not read as
 * a void that pulls the gas across it. A particle whose stencil reaches a node holding another
 * phase's mass (a solid next to the gas) or an obstacle's constrained node, or whose new
 * position would lie in an obstacle or outside the domain, does not move: the gas's volume
 * alone does not describe those places. A particle alone in its cell moves only within it, so
 * that no shift empties a cell (where the merges and splits run rarely, cells thin to one
 * particle, and shifting them out fed a cascade of refills that broke the gas up: the double
 * rarefaction's L1 density error reached 0.25 at 200 cells with merges and splits every 30
 * steps and refill every step).
 *
 * Decomposition. The deposit is summed over the ranks by the reverse halo, folded by the ranks
 * owning the faces, and copied back to the ghosts; then every particle moves from owned data,
 * and migration takes those that left their rank's cells to their owners. */
#include "fluid_internal.h"

#include "mpm_cells.h"
#include "mpm_error.h"
#include "mpm_particles.h"
#include "mpm_shape.h"

#include <math.h>
#include <string.h>

/* The 1-D weights of a particle's stencil along each axis and the box index of its first
 * node (a dummy third axis of weight 1 in 2-D), and the cell holding the particle. */
typedef struct shift_stencil {
  int sup, nz;
  mpm_lidx first, sy, sz, cell; /* cell: box index of its lower corner node */
  int cc[3];                    /* the cell's global coordinates */
  double w[3][MPM_SHAPE_MAX_SUPPORT], dw[3][MPM_SHAPE_MAX_SUPPORT];
} shift_stencil;

/* The stencil at x; the weights' derivatives only if with_dw (the deposit reads none). The
 * cell is mpm_cells_coord's, from the same quotient (x - lo) / dx. */
static void stencil_at(const mpm_grid *g, double lp, const double *x, int with_dw,
                       shift_stencil *s) {
  double xi[3] = {0, 0, 0};
  int base[3] = {0, 0, 0};
  s->sup = mpm_shape_support(g->shape), s->nz = g->dim == 3 ? s->sup : 1;
  s->cc[2] = 0;
  for (int d = 0; d < g->dim; ++d) {
    xi[d] = (x[d] - g->lo[d]) / g->dx;
    const int c = mpm_shape_floor(xi[d]);
    s->cc[d] = c < 0 ? 0 : c >= g->ncells[d] ? g->ncells[d] - 1 : c;
  }
  mpm_shape_eval(g->shape, g->dim, xi, lp, base, s->w, s->dw);
  for (int d = 0; with_dw && d < g->dim; ++d)
    for (int k = 0; k < s->sup; ++k) s->dw[d][k] /= g->dx;
  if (g->dim == 2) s->w[2][0] = 1.0, s->dw[2][0] = 0.0;
  s->sy = g->box_n[0], s->sz = (mpm_lidx)g->box_n[0] * g->box_n[1];
  s->first = mpm_grid_local_index(g, base);
  s->cell = mpm_grid_local_index(g, s->cc);
}

/* The loops below take the stencil's extent as arguments, so that the 2-D quadratic case,
 * called with literals (SHIFT_DISPATCH), is unrolled; the sums are the same either way. */
#define SHIFT_INLINE static inline __attribute__((always_inline))
#define SHIFT_DISPATCH(call, s)                                                                    \
  ((s)->sup == 3 && (s)->nz == 1 ? call(3, 1) : call((s)->sup, (s)->nz))

/* Add S_i(x_p) V to phi at every node of the stencil. */
SHIFT_INLINE void deposit_n(const shift_stencil *s, double V, double *phi, int sup, int nz) {
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < sup; ++b) {
      double *row = phi + s->first + b * s->sy + c * s->sz;
      const double wbc = s->w[1][b] * s->w[2][c] * V;
      for (int a = 0; a < sup; ++a) row[a] += s->w[0][a] * wbc;
    }
}

static void stencil_deposit(const shift_stencil *s, double V, double *phi) {
#define DEPOSIT(sup, nz) deposit_n(s, V, phi, sup, nz)
  SHIFT_DISPATCH(DEPOSIT, s);
#undef DEPOSIT
}

/* sum_i phi_i grad S_i(x_p). */
SHIFT_INLINE void gradient_n(const shift_stencil *s, const double *phi, double *grad, int sup,
                             int nz) {
  grad[0] = grad[1] = grad[2] = 0.0;
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < sup; ++b) {
      const double *row = phi + s->first + b * s->sy + c * s->sz;
      double r0 = 0.0, r1 = 0.0;
      for (int a = 0; a < sup; ++a) r0 += row[a] * s->dw[0][a], r1 += row[a] * s->w[0][a];
      grad[0] += r0 * s->w[1][b] * s->w[2][c];
      grad[1] += r1 * s->dw[1][b] * s->w[2][c];
      grad[2] += r1 * s->w[1][b] * s->dw[2][c];
    }
}

static void stencil_gradient(const shift_stencil *s, const double *phi, double *grad) {
#define GRADIENT(sup, nz) gradient_n(s, phi, grad, sup, nz)
  SHIFT_DISPATCH(GRADIENT, s);
#undef GRADIENT
}

/* Does the stencil reach a node where the nodal array mk is positive? */
SHIFT_INLINE int touches_n(const shift_stencil *s, const double *mk, int sup, int nz) {
  int any = 0;
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < sup; ++b) {
      const double *row = mk + s->first + b * s->sy + c * s->sz;
      for (int a = 0; a < sup; ++a) any |= row[a] > 0.0;
    }
  return any;
}

static int stencil_touches(const shift_stencil *s, const double *mk) {
#define TOUCHES(sup, nz) touches_n(s, mk, sup, nz)
  return SHIFT_DISPATCH(TOUCHES, s);
#undef TOUCHES
}

/* Fold phi about the domain faces this rank holds: phi(j) + phi(-j) at both, j counted from
 * the face node along d. Each pair once, from its node at j >= 0: the pairs of one axis are
 * disjoint, so the slab of nodes at j is visited in any order. */
static void fold_faces(const mpm_grid *g, double *phi) {
  for (int d = 0; d < g->dim; ++d) {
    if (g->periodic[d]) continue;
    mpm_lidx stride = 1; /* between neighbours along d; the slab: inner x outer nodes */
    for (int e = 0; e < d; ++e) stride *= g->box_n[e];
    const mpm_lidx outer = g->nnodes / (stride * g->box_n[d]);
    for (int side = 0; side < 2; ++side) {
      if (g->coord[d] != (side ? g->nproc[d] - 1 : 0)) continue;
      const int face = side ? g->ncells[d] : 0;
      for (int j = 0; j <= g->pad; ++j) {
        const int at = face + j - g->box_lo[d], mirror = face - j - g->box_lo[d];
        if (at < 0 || at >= g->box_n[d] || mirror < 0 || mirror >= g->box_n[d]) continue;
        for (mpm_lidx o = 0; o < outer; ++o)
          for (mpm_lidx a = 0; a < stride; ++a) {
            const mpm_lidx base = o * stride * g->box_n[d] + a;
            const mpm_lidx l = base + at * stride, lm = base + mirror * stride;
            const double sum = j == 0 ? 2.0 * phi[l] : phi[l] + phi[lm];
            phi[l] = sum, phi[lm] = sum;
          }
      }
    }
  }
}

/* Does the particle's stencil reach a node where another phase holds mass? (The gas's own
 * scratch phase for fluid.mol_damping holds the gas's mass: not another phase.) */
static int near_other_phase(const mpm_module *m, const shift_stencil *s) {
  const mpm_grid *g = m->grid;
  const fluid_content *fc = m->content;
  for (int k = 0; k < g->nphases; ++k)
    if (k != m->phase && k != fc->filter_phase && g->phase[k].m_i &&
        stencil_touches(s, g->phase[k].m_i))
      return 1;
  return 0;
}

static int inside_domain(const mpm_grid *g, double *x) {
  mpm_grid_wrap(g, x);
  for (int d = 0; d < g->dim; ++d)
    if (!g->periodic[d] && !(x[d] >= g->lo[d] && x[d] < g->hi[d])) return 0;
  return 1;
}

/* Is x in a cell this rank owns? */
static int owns_cell(const mpm_grid *g, const double *x) {
  for (int d = 0; d < g->dim; ++d) {
    const int c = mpm_cells_coord(g, d, x[d]);
    if (c < g->cell_split[d][g->coord[d]] || c >= g->cell_split[d][g->coord[d] + 1]) return 0;
  }
  return 1;
}

int fluid_shift(mpm_module *m, long step, double h, int *changed) {
  fluid_content *fc = m->content;
  if (!(fc->shift > 0.0) || step % fc->shift_every != 0) return 0;
  mpm_particles *p = m->particles;
  mpm_grid *g = m->grid;
  const int dim = g->dim;
  double *phi = fc->node;                           /* nodal scratch, (dim + 3) nnodes */
  double *count = fc->node + 2 * (size_t)g->nnodes; /* particles per cell, at its corner */
  memset(phi, 0, sizeof *phi * (size_t)g->nnodes);
  memset(count, 0, sizeof *count * (size_t)g->nnodes);
  const double *J = mpm_particles_comp(p, FLUID_J, 0), *V0 = mpm_particles_comp(p, fc->lay.f_V0, 0);
  shift_stencil s;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    double x[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, FLUID_X, d)[i];
    stencil_at(g, fc->lp, x, 0, &s);
    stencil_deposit(&s, J[i] * V0[i], phi);
    count[s.cell] += 1.0;
  }
  MPM_CALL(mpm_grid_halo_reverse(g, &phi, 1));
  fold_faces(g, phi);
  MPM_CALL(mpm_grid_halo_forward(g, &phi, 1));
  /* The obstacles' constrained nodes, marked in the next scratch block. */
  double *wall = fc->obs.count ? fc->node + g->nnodes : NULL;
  if (wall) {
    memset(wall, 0, sizeof *wall * (size_t)g->nnodes);
    for (int k = 0; k < fc->obs.count; ++k)
      for (mpm_lidx a = 0; a < fc->obs.ob[k].count; ++a) wall[fc->obs.ob[k].node[a]] = 1.0;
  }
  /* The distance a particle may travel this event: kappa dx s h, s = c + |v| its own signal
   * speed, h the step (times shift_every); the gradient is per unit volume fraction. */
  const double cell = pow(g->dx, dim), scale = fc->shift * g->dx * h * fc->shift_every / cell;
  const double gamma = fc->gas.gamma, *e = mpm_particles_comp(p, FLUID_E, 0);
  const double cap = 0.25 * g->dx;
  long moved = 0, away = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    if (J[i] < fc->shift_J) continue;
    double x[3] = {0, 0, 0}, gphi[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, FLUID_X, d)[i];
    stencil_at(g, fc->lp, x, 1, &s);
    if (near_other_phase(m, &s) || (wall && stencil_touches(&s, wall))) continue;
    stencil_gradient(&s, phi, gphi);
    double xn[3] = {0, 0, 0};
    const int alone = count[s.cell] < 2.0;
    double v2 = 0.0;
    for (int d = 0; d < dim; ++d)
      v2 += mpm_particles_comp(p, FLUID_V, d)[i] * mpm_particles_comp(p, FLUID_V, d)[i];
    const double reach = scale * (sqrt(gamma * (gamma - 1.0) * fabs(e[i])) + sqrt(v2));
    for (int d = 0; d < dim; ++d) {
      xn[d] = x[d] + fmax(-cap, fmin(cap, -reach * gphi[d]));
      if (alone) { /* a particle alone in its cell stays in it: no shift empties a cell */
        const double face = g->lo[d] + s.cc[d] * g->dx, eps = 1e-9 * g->dx;
        xn[d] = fmin(fmax(xn[d], face + eps), face + g->dx - eps);
      }
    }
    if (!inside_domain(g, xn) || fluid_obstacles_inside(&fc->obs, xn) ||
        (m->ops->reserved && m->ops->reserved(m, xn)))
      continue;
    for (int d = 0; d < dim; ++d) mpm_particles_comp(p, FLUID_X, d)[i] = xn[d];
    moved++;
    away += !owns_cell(g, xn);
  }
  long sum[2] = {moved, away};
  MPM_CALL_MPI(MPI_Allreduce(MPI_IN_PLACE, sum, 2, MPI_LONG, MPI_SUM, g->comm));
  if (sum[1] > 0) {
    int migrated = 0;
    MPM_CALL(mpm_particles_migrate(p, g, &migrated));
  }
  if (sum[0] > 0) *changed = 1;
  return 0;
}
