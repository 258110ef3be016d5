/* `sharp`: separate fields that meet at the solid's surface only. The gas and the solid each
 * solve on their own nodal field; the normal velocities of the two fields, each interpolated at
 * points on the solid's surface, are then made equal there by equal and opposite nodal
 * impulses (a Lagrange multiplier per point, solved by conjugate gradients).
 *
 * Why. `velocity`, `contact` and `traction` tie the phases at every node both have mass on: the
 * solid's B-spline tail a cell into the gas and the gas's a cell into the solid. One C1 field
 * across a material interface cannot carry the kink of the exact velocity there (the strain
 * jumps with the impedance), so coupled frequencies converge at first order only
 * (docs/verification.md, the resonator: +0.169, +0.100, +0.054, +0.027 % at 50 to 400 cells/m).
 * A 1-D Galerkin model of the same discretisation (quadratic B-splines, two particles per cell,
 * lumped mass) gives +0.159, +0.090, +0.048, +0.024 % with one field, and -0.044, -0.011,
 * -0.0027, -0.0007 % (second order) with two fields tied at the interface point alone.
 *
 * Interface points. A solid particle p lies on the surface where the solid's nodal mass,
 * interpolated one particle width outside it, x_p + 2 r_p n, fills less than half of what the
 * seeded material gives (sum S_i m_i < rho_0 dx^dim / 2, rho_0 = m_p / V0_p; on a straight face
 * the first layer reads 0.38 there and the second 0.62), with r_p = V0_p^(1/dim) / 2 and n the
 * outward unit normal -grad(sum S_i m_i) at x_p. Its point is x_q = x_p + r_p n, the face of its
 * cell: on a straight face exactly the face, whatever the particle spacing along it. A point
 * whose stencil holds gas on less than half its weight is dropped (no gas there to tie).
 *
 * The constraint. At point q, with c_q(phase) the stencil weights over the nodes where that
 * phase has mass, normalised to sum 1 (so that a point beside the phase's edge reads the
 * phase's own velocity), n_q . (v_g(x_q) - v_s(x_q)) = 0. Impulses lambda_q n_q c_q: the gas
 * loses and the solid gains the same momentum at every point, so momentum balances to roundoff;
 * the multipliers solve A lambda = g, A = C_g M_g^-1 C_g^T + C_s M_s^-1 C_s^T (symmetric,
 * positive semi-definite; redundant points along a face make it singular but consistent). A
 * component that a domain wall fixes at a node is left to the wall (infinite mass). The
 * impulses only remove the phases' relative normal velocity at the points: they take kinetic
 * energy away, never add it (as an inelastic impact does). Where the solid's clamp holds a node
 * the gas follows it (MPM_COUPLING_HOLDS).
 *
 * Limits (refused at input): the classic update (usl, musl) with coupling.time = monolithic; no
 * refinement hierarchy. The cost: per step a conjugate-gradient solve whose every iteration
 * deposits the points' impulses, sums and fills the halo of 2 dim nodal arrays of the whole box,
 * and gathers them back. */
#include "mpm_coupling.h"
#include "mpm_error.h"
#include "mpm_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { SHARP_STENCIL = MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT * MPM_SHAPE_MAX_SUPPORT };

/* Surface test: the solid's interpolated nodal mass one particle width outside a particle, over
 * the seeded material's, below which the particle is on the surface. */
#define SHARP_FILL 0.5
/* The share of a point's stencil weight on gas nodes below which the point is dropped. */
#define SHARP_GAS_SHARE 0.5
/* Conjugate gradients: relative residual and iteration cap. */
#define SHARP_TOL    1e-12
#define SHARP_MAX_IT 200

typedef struct sharp {
  int f_m, f_V0, f_F;       /* the solid's mass, reference volume and deformation gradient */
  int npt, cap;             /* interface points on this rank */
  mpm_lidx *node;           /* SHARP_STENCIL box nodes per point */
  double *cg, *cs;          /* their normalised weights for the gas and the solid */
  double *n;                /* MPM_MAX_DIM per point: the unit normal */
  double *lam, *r, *p, *Ap; /* per point */
  double *nod;              /* 2 dim nnodes: the deposited impulses per mass, gas then solid */
  double *nod_ptr[2 * MPM_MAX_DIM];
  double *sync_ptr[2 * (MPM_MAX_DIM + 1)]; /* the phases' m_i and v_i, for the halo fill */
} sharp;

static int sharp_create(mpm_coupling *c, const mpm_config *cfg) {
  const char *method, *time;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "usl") != 0 && strcmp(method, "musl") != 0)
    return mpm_config_fail(cfg, "coupling.scheme",
                           "sharp needs the classic update (time.method = usl or musl): its "
                           "interface impulses act on the step's new nodal velocities; use "
                           "velocity or traction with %s",
                           method);
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  if (strcmp(time, "monolithic") != 0)
    return mpm_config_fail(
        cfg, mpm_config_has(cfg, "coupling.time") ? "coupling.time" : "coupling.scheme",
        "sharp ties both phases' fields in one nodal solve and needs "
        "coupling.time = monolithic; use velocity or traction with %s",
        time);
  sharp *s;
  MPM_ALLOC(s, 1);
  c->content = s;
  return 0;
}

static void sharp_destroy(mpm_coupling *c) {
  sharp *s = c->content;
  if (s) {
    free(s->node), free(s->cg), free(s->cs), free(s->n);
    free(s->lam), free(s->r), free(s->p), free(s->Ap), free(s->nod);
  }
  free(s);
  c->content = NULL;
}

static int sharp_setup(mpm_coupling *c) {
  sharp *s = c->content;
  const mpm_particles *p = c->module[MPM_ROLE_SOLID]->particles;
  s->f_m = mpm_particles_find(p, "m"), s->f_V0 = mpm_particles_find(p, "V0");
  s->f_F = mpm_particles_find(p, "F");
  if (s->f_m < 0 || s->f_V0 < 0 || s->f_F < 0)
    MPM_FAIL(MPM_ERR_INTERNAL, "the solid has no m, V0 or F field");
  const int dim = c->grid->dim;
  MPM_ALLOC(s->nod, (size_t)(2 * dim) * (size_t)c->grid->nnodes);
  for (int k = 0; k < 2 * dim; ++k) s->nod_ptr[k] = s->nod + (size_t)k * c->grid->nnodes;
  return 0;
}

static int grow(void **ptr, size_t bytes) {
  void *grown = realloc(*ptr, bytes);
  if (!grown) MPM_FAIL_OOM(bytes);
  *ptr = grown;
  return 0;
}

/* Room for n points, keeping those found. */
static int room(sharp *s, int n) {
  if (n <= s->cap) return 0;
  const size_t cap = (size_t)n + (size_t)n / 4 + 16;
  MPM_CALL(grow((void **)&s->node, sizeof *s->node * cap * SHARP_STENCIL));
  MPM_CALL(grow((void **)&s->cg, sizeof *s->cg * cap * SHARP_STENCIL));
  MPM_CALL(grow((void **)&s->cs, sizeof *s->cs * cap * SHARP_STENCIL));
  MPM_CALL(grow((void **)&s->n, sizeof *s->n * cap * MPM_MAX_DIM));
  double **vec[4] = {&s->lam, &s->r, &s->p, &s->Ap};
  for (int k = 0; k < 4; ++k) MPM_CALL(grow((void **)vec[k], sizeof **vec[k] * cap));
  s->cap = (int)cap;
  return 0;
}

/* The stencil of x: box nodes, weights and weight derivatives along each axis (per unit xi);
 * its size, or 0 where it leaves the box. */
static int stencil(const mpm_grid *g, const double *x, mpm_lidx *node, double *w,
                   double (*dw)[MPM_MAX_DIM]) {
  const int dim = g->dim, sup = mpm_shape_support(g->shape);
  int base[MPM_MAX_DIM];
  double xi[MPM_MAX_DIM], wt[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT],
      dwt[MPM_MAX_DIM][MPM_SHAPE_MAX_SUPPORT];
  for (int d = 0; d < dim; ++d) xi[d] = (x[d] - g->lo[d]) / g->dx;
  mpm_shape_eval(g->shape, dim, xi, 0.0, base, wt, dwt);
  const int count = dim == 1 ? sup : dim == 2 ? sup * sup : sup * sup * sup;
  for (int k = 0; k < count; ++k) {
    int gi[MPM_MAX_DIM];
    double W = 1.0;
    for (int d = 0, r = k; d < dim; r /= sup, ++d) {
      gi[d] = base[d] + r % sup;
      if (gi[d] < g->box_lo[d] || gi[d] >= g->box_lo[d] + g->box_n[d]) return 0;
      W *= wt[d][r % sup];
    }
    for (int e = 0; dw && e < dim; ++e) {
      double D = 1.0;
      for (int d = 0, r = k; d < dim; r /= sup, ++d) D *= d == e ? dwt[d][r % sup] : wt[d][r % sup];
      dw[k][e] = D;
    }
    node[k] = mpm_grid_local_index(g, gi), w[k] = W;
  }
  return count;
}

/* The interface points of this rank's solid particles (see the header). */
static int find_points(mpm_coupling *c) {
  sharp *s = c->content;
  const mpm_grid *g = c->grid;
  const int dim = g->dim;
  const mpm_particles *p = c->module[MPM_ROLE_SOLID]->particles;
  const mpm_grid_phase *ps = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const double *m = mpm_particles_comp(p, s->f_m, 0), *V0 = mpm_particles_comp(p, s->f_V0, 0);
  const double cell = pow(g->dx, dim);
  s->npt = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    mpm_lidx node[SHARP_STENCIL];
    double w[SHARP_STENCIL], dw[SHARP_STENCIL][MPM_MAX_DIM], x[MPM_MAX_DIM], y[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, 0, d)[i];
    int count = stencil(g, x, node, w, dw);
    double grad[MPM_MAX_DIM] = {0}, norm = 0.0;
    for (int k = 0; k < count; ++k)
      for (int d = 0; d < dim; ++d) grad[d] += dw[k][d] * ps->m_i[node[k]];
    for (int d = 0; d < dim; ++d) norm += grad[d] * grad[d];
    if (!(norm > 0.0)) continue;
    norm = sqrt(norm);
    double n[MPM_MAX_DIM], Ftn = 0.0;
    for (int d = 0; d < dim; ++d) n[d] = -grad[d] / norm;
    for (int b = 0; b < dim; ++b) { /* (F^T n)_b: the reference cell's stretch along n */
      double sum = 0.0;
      for (int a = 0; a < dim; ++a) sum += mpm_particles_comp(p, s->f_F, a * dim + b)[i] * n[a];
      Ftn += sum * sum;
    }
    const double r = 0.5 * pow(V0[i], 1.0 / dim) * sqrt(Ftn), full = m[i] / V0[i] * cell;
    for (int d = 0; d < dim; ++d) y[d] = x[d] + 2.0 * r * n[d];
    count = stencil(g, y, node, w, NULL);
    double fill = 0.0;
    for (int k = 0; k < count; ++k) fill += w[k] * ps->m_i[node[k]];
    if (!count || !(fill < SHARP_FILL * full)) continue;
    for (int d = 0; d < dim; ++d) y[d] = x[d] + r * n[d];
    MPM_CALL(room(s, s->npt + 1));
    const int q = s->npt;
    mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
    double *cg = s->cg + (size_t)q * SHARP_STENCIL, *cs = s->cs + (size_t)q * SHARP_STENCIL;
    if (!(count = stencil(g, y, nq, w, NULL))) continue;
    double wg = 0.0, ws = 0.0;
    for (int k = 0; k < count; ++k) {
      cg[k] = mpm_coupling_has_mass(c, MPM_ROLE_FLUID, nq[k]) ? w[k] : 0.0;
      cs[k] = mpm_coupling_has_mass(c, MPM_ROLE_SOLID, nq[k]) ? w[k] : 0.0;
      wg += cg[k], ws += cs[k];
    }
    if (!(wg >= SHARP_GAS_SHARE) || !(ws > 0.0)) continue;
    for (int k = 0; k < SHARP_STENCIL; ++k) {
      if (k >= count) nq[k] = 0, cg[k] = cs[k] = 0.0;
      cg[k] /= wg, cs[k] /= ws;
    }
    for (int d = 0; d < MPM_MAX_DIM; ++d) s->n[(size_t)q * MPM_MAX_DIM + d] = d < dim ? n[d] : 0.0;
    s->npt++;
  }
  return 0;
}

/* Is component d of node l free (not fixed by a domain wall)? */
static int free_axis(const mpm_coupling *c, mpm_lidx l, int d) {
  return !(c->wall_axes && c->wall_axes[l] >> d & 1u);
}

/* u = M^-1 C^T lam for both phases, complete on every box node: the gas's in nod[0 .. dim),
 * the solid's in nod[dim .. 2 dim). Collective. */
static int spread(mpm_coupling *c, const double *lam) {
  sharp *s = c->content;
  mpm_grid *g = c->grid;
  const int dim = g->dim;
  const mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                                 mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  memset(s->nod, 0, sizeof *s->nod * (size_t)(2 * dim) * (size_t)g->nnodes);
  for (int q = 0; q < s->npt; ++q) {
    const mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
    const double *n = s->n + (size_t)q * MPM_MAX_DIM;
    for (int k = 0; k < SHARP_STENCIL; ++k) {
      const double wgt[2] = {s->cg[(size_t)q * SHARP_STENCIL + k],
                             s->cs[(size_t)q * SHARP_STENCIL + k]};
      for (int f = 0; f < 2; ++f)
        for (int d = 0; wgt[f] != 0.0 && d < dim; ++d)
          s->nod_ptr[f * dim + d][nq[k]] += lam[q] * n[d] * wgt[f];
    }
  }
  MPM_CALL(mpm_grid_halo_reverse(g, s->nod_ptr, 2 * dim));
  for (int f = 0; f < 2; ++f)
    for (int d = 0; d < dim; ++d) {
      double *u = s->nod_ptr[f * dim + d];
      for (mpm_lidx l = 0; l < g->nnodes; ++l)
        u[l] = u[l] != 0.0 && free_axis(c, l, d) ? u[l] / ph[f]->m_i[l] : 0.0;
    }
  return mpm_grid_halo_forward(g, s->nod_ptr, 2 * dim);
}

/* out_q = n_q . (C_g u_g + C_s u_s)(x_q) from spread's arrays. */
static void gather(const mpm_coupling *c, double *out) {
  const sharp *s = c->content;
  const int dim = c->grid->dim;
  for (int q = 0; q < s->npt; ++q) {
    const mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
    const double *n = s->n + (size_t)q * MPM_MAX_DIM;
    const double *cg = s->cg + (size_t)q * SHARP_STENCIL, *cs = s->cs + (size_t)q * SHARP_STENCIL;
    double sum = 0.0;
    for (int k = 0; k < SHARP_STENCIL; ++k)
      for (int d = 0; d < dim; ++d)
        sum += n[d] * (cg[k] * s->nod_ptr[d][nq[k]] + cs[k] * s->nod_ptr[dim + d][nq[k]]);
    out[q] = sum;
  }
}

static int dot(const mpm_coupling *c, const double *a, const double *b, double *out) {
  const sharp *s = c->content;
  double sum = 0.0;
  for (int q = 0; q < s->npt; ++q) sum += a[q] * b[q];
  MPM_CALL_MPI(MPI_Allreduce(&sum, out, 1, MPI_DOUBLE, MPI_SUM, c->grid->comm));
  return 0;
}

/* Solve A lam = r by conjugate gradients from lam = 0 (r: the points' normal velocity jumps,
 * overwritten). Collective: every rank iterates alike. */
static int solve(mpm_coupling *c) {
  sharp *s = c->content;
  double rr0, rr, pAp;
  for (int q = 0; q < s->npt; ++q) s->lam[q] = 0.0, s->p[q] = s->r[q];
  MPM_CALL(dot(c, s->r, s->r, &rr0));
  rr = rr0;
  for (int it = 0; it < SHARP_MAX_IT && rr > SHARP_TOL * SHARP_TOL * rr0 && rr > 0.0; ++it) {
    MPM_CALL(spread(c, s->p));
    gather(c, s->Ap);
    MPM_CALL(dot(c, s->p, s->Ap, &pAp));
    if (!(pAp > 0.0)) break; /* a direction of A's null space: nothing left to remove */
    const double alpha = rr / pAp;
    for (int q = 0; q < s->npt; ++q) s->lam[q] += alpha * s->p[q], s->r[q] -= alpha * s->Ap[q];
    double rr1;
    MPM_CALL(dot(c, s->r, s->r, &rr1));
    for (int q = 0; q < s->npt; ++q) s->p[q] = s->r[q] + rr1 / rr * s->p[q];
    rr = rr1;
  }
  return 0;
}

static int sharp_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  sharp *s = c->content;
  mpm_grid *g = c->grid;
  const int dim = g->dim;
  mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                           mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  /* The hooks see summed values on the owned nodes only: fill the ghosts the stencils read. */
  int nsync = 0;
  for (int f = 0; f < 2; ++f) {
    s->sync_ptr[nsync++] = ph[f]->m_i;
    for (int d = 0; d < dim; ++d) s->sync_ptr[nsync++] = ph[f]->v_i[d];
  }
  MPM_CALL(mpm_grid_halo_forward(g, s->sync_ptr, nsync));
  MPM_CALL(find_points(c));
  for (int q = 0; q < s->npt; ++q) { /* the jumps n . (v_g - v_s) at the points */
    const mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
    const double *n = s->n + (size_t)q * MPM_MAX_DIM;
    double jump = 0.0;
    for (int k = 0; k < SHARP_STENCIL; ++k)
      for (int d = 0; d < dim; ++d)
        jump += n[d] * (s->cg[(size_t)q * SHARP_STENCIL + k] * ph[0]->v_i[d][nq[k]] -
                        s->cs[(size_t)q * SHARP_STENCIL + k] * ph[1]->v_i[d][nq[k]]);
    s->r[q] = jump;
  }
  MPM_CALL(solve(c));
  MPM_CALL(spread(c, s->lam));
  const mpm_role role[2] = {MPM_ROLE_FLUID, MPM_ROLE_SOLID};
  const double sign[2] = {-1.0, 1.0};
  for (mpm_lidx l = 0; l < g->nnodes; ++l)
    for (int f = 0; f < 2; ++f) {
      double v[MPM_MAX_DIM], change = 0.0;
      for (int d = 0; d < dim; ++d) {
        const double u = s->nod_ptr[f * dim + d][l];
        v[d] = ph[f]->v_i[d][l] + sign[f] * u, change += fabs(u);
      }
      if (change > 0.0) mpm_coupling_exchange(c, role[f], l, v, NULL, h);
    }
  return 0;
}

static const mpm_coupling_ops sharp_ops = {
    .create = sharp_create,
    .setup = sharp_setup,
    .after_solve = sharp_after_solve,
    .destroy = sharp_destroy,
};

const mpm_coupling_type coupling_sharp = {
    .name = "sharp",
    .help = "separate fields tied at the solid's surface only: the normal velocities of both "
            "fields, interpolated at points on the surface, made equal by equal and opposite "
            "nodal impulses (usl, musl; monolithic)",
    .needs = MPM_COUPLING_NORMALS | MPM_COUPLING_HOLDS,
    .ops = &sharp_ops,
};
