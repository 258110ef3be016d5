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
 * the first layer reads 0.38 there and the second 0.62), with n the outward unit normal
 * -grad(sum S_i m_i) at x_p and r_p = |F^T n| V0_p^(1/dim) / 2 its current half-width along n
 * (with the reference width, the faces of a pre-stressed slab sat 3e-5 off and the gas beside it
 * moved). Its face point is x_p + r_p n: on a straight face exactly the face, whatever the
 * particle spacing along it. The face points of one particle cell and face direction merge
 * into one point (find_points). A point whose stencil holds gas on less than half its weight is
 * dropped (no gas there to tie).
 *
 * The constraint. At point q, with c_q(phase) the stencil weights over the nodes where that
 * phase has mass, normalised to sum 1 (so that a point beside the phase's edge reads the
 * phase's own velocity), n_q . (v_g(x_q) - v_s(x_q)) = 0. A node whose mass is below
 * SHARP_NEAR_EMPTY of the phase's fullest node in the stencil reads with its weight scaled by
 * that ratio (add_point). Why: the row's cost to the multipliers, c_k^2 / m_k, grows without
 * bound as a node's last particle leaves its reach while c_k stays finite. When a soft slab's
 * face moved half a cell off a node, the solid's tail node held 1e-4 of a particle's mass but a
 * tenth of the point's weight; the constraint was met by that node alone, no particle felt it,
 * and the gas passed through the face (2 cells in 0.25 s, first layer p +36 %). On a face a
 * quarter cell from the particles (a node's tail: 1/64 of the fullest) the rows are unchanged.
 * Impulses lambda_q n_q c_q: the gas loses and the solid gains the same momentum at every point, so
 * momentum balances to roundoff; the multipliers solve A lambda = g, A = C_g M_g^-1 C_g^T + C_s
 * M_s^-1 C_s^T (symmetric, positive semi-definite; points that repeat a face's rows make it
 * singular, see find_points and solve). The domain's walls act after the impulses, as under the
 * other schemes: a wall takes as its reaction what they gave a component it holds, so the exchange
 * stays balanced (masking those components out of the rows instead broke the balance by 3e-5 of the
 * interface force on the main job, where the bar stands on the floor). The impulses only remove the
 * phases' relative normal velocity at the points: they take kinetic energy away, never add it (as
 * an inelastic impact does). Where the solid's clamp holds a node the gas follows it
 * (MPM_COUPLING_HOLDS).
 *
 * Deep inside the solid the phases share the centre-of-mass velocity (tie_inside).
 *
 * The method of lines (the ERK pairs). A particle moves with the nodal velocity but its own
 * velocity takes the nodal acceleration only (mpm_coupling.h). So each RHS makes the points'
 * normal velocities equal (the positions' kinematics, no force) and then their normal
 * accelerations, the latter with the drift of the phases' deposited velocities u = mv / m
 * relaxed at the rate k = relax_rate (coupling.mol_rate, MPM_COUPLING_RATE):
 * n . (a_g - a_s)(x_q) = -k n . (u_g - u_s)(x_q). The same matrix, two solves, applied together
 * (apply); the forces of the second are the interface's, equal and opposite. Deep inside the solid
 * the phases share the centre-of-mass velocity and acceleration, and relax their own velocities
 * node by node.
 *
 * The gauge. Each phase's field ends at the face, and so does the particles' quadrature of the
 * ambient pressure over the gas's last columns: with no PIC share (the ERK pairs) it grows a
 * transverse mode there from roundoff. physics.gauge_pressure at the ambient pressure takes it
 * out of both phases' forces (fluid/fluid_gauge.c); the test and the docs run sharp with it.
 *
 * Multirate. The scheme needs nothing of its own there. Under the classic update the gas's held
 * cycle solves the same multipliers against the held solid, whose share is captured and handed
 * to the solid's substeps as their load (mpm_cycle.c, mpm_partitioned.h); under MRIStep the
 * ties belong to the slow right-hand side, the joint cycle less the solid's own rates.
 *
 * Limits (refused at input): usl, musl or an ERK pair (not euler or ssprk2, whose RHS gets no
 * relaxation rate) with coupling.time = monolithic or multirate (staggered is not measured); no
 * refinement hierarchy. The cost: per
 * solve three preconditioned conjugate-gradient passes whose every iteration clears, deposits,
 * sums over the halo and gathers back 2 dim nodal arrays of the whole box. */
#include "mpm_coupling.h"
#include "mpm_error.h"
#include "mpm_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { SHARP_STENCIL = MPM_GRID_STENCIL_MAX };

/* Surface test: the solid's interpolated nodal mass one particle width outside a particle, over
 * the seeded material's, below which the particle is on the surface. */
#define SHARP_FILL 0.5
/* The share of a point's stencil weight on gas nodes below which the point is dropped. */
#define SHARP_GAS_SHARE 0.5
/* A phase's node whose mass is below this fraction of the phase's fullest node in a point's
 * stencil reads into the point's row with its weight scaled by the ratio (add_point). */
#define SHARP_NEAR_EMPTY 0.01
/* ... of the fullest node within this many nodes along each axis (tie_near_empty). */
#define SHARP_REACH 2
/* |grad m_s| dx / m_s below which a node counts as deep inside the solid (tie_inside). */
#define SHARP_INSIDE 0.02
/* Conjugate gradients: relative residual and iteration cap. */
#define SHARP_TOL    1e-12
#define SHARP_MAX_IT 200
/* The shift of A, relative to its largest diagonal entry (solve). */
#define SHARP_SHIFT  1e-10
#define SHARP_REFINE 2

typedef struct sharp {
  int f_m, f_V0, f_F;     /* the solid's mass, reference volume and deformation gradient */
  int npt, cap;           /* interface points on this rank */
  struct candidate *cand; /* the surface particles' points before the merge */
  int ncand, ccap;
  mpm_lidx *node;                          /* SHARP_STENCIL box nodes per point */
  double *cg, *cs;                         /* their normalised weights for the gas and the solid */
  double *n;                               /* MPM_MAX_DIM per point: the unit normal */
  double *lam, *r, *p, *Ap, *z, *dinv, *g; /* per point */
  double *nod; /* 2 dim nnodes: the deposited impulses per mass, gas then solid */
  double *nod_ptr[2 * MPM_MAX_DIM];
  double *sync_ptr[2 * (2 * MPM_MAX_DIM + 1)]; /* the phases' m_i, v_i (and a_i), halo fill */
  double *ju; /* per point: the acceleration's jump (method of lines) */
  double *dv; /* 2 dim nnodes: the velocity tie's spread (method of lines) */
} sharp;

static const mpm_key_spec sharp_keys[] = {
    MPM_COUPLING_MOL_RATE_KEY("velocity, traction and sharp")};

static int sharp_create(mpm_coupling *c, const mpm_config *cfg) {
  const char *method, *time;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "euler") == 0 || strcmp(method, "ssprk2") == 0)
    return mpm_config_fail(cfg, "coupling.scheme",
                           "sharp runs with usl, musl or an ERK pair (bs32, ...): under %s the "
                           "phases' own velocities get no relaxation and drift apart; use "
                           "velocity or traction with %s",
                           method, method);
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  if (strcmp(time, "monolithic") != 0 && strcmp(time, "multirate") != 0)
    return mpm_config_fail(
        cfg, mpm_config_has(cfg, "coupling.time") ? "coupling.time" : "coupling.scheme",
        "sharp is measured under coupling.time = monolithic and multirate only; use one of "
        "them, or velocity or traction with %s",
        time);
  sharp *s;
  MPM_ALLOC(s, 1);
  c->content = s;
  return 0;
}

static void sharp_destroy(mpm_coupling *c) {
  sharp *s = c->content;
  if (s) {
    free(s->node), free(s->cg), free(s->cs), free(s->n), free(s->cand);
    free(s->lam), free(s->r), free(s->p), free(s->Ap), free(s->z), free(s->dinv), free(s->g);
    free(s->ju), free(s->dv);
    free(s->nod);
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
  MPM_ALLOC(s->dv, (size_t)(2 * dim) * (size_t)c->grid->nnodes);
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
  double **vec[8] = {&s->lam, &s->r, &s->p, &s->Ap, &s->z, &s->dinv, &s->g, &s->ju};
  for (int k = 0; k < 8; ++k) MPM_CALL(grow((void **)vec[k], sizeof **vec[k] * cap));
  s->cap = (int)cap;
  return 0;
}

/* A surface particle's point, before the merge: its face point, its normal and its key (the
 * particle's cell and the axis and sign its normal points along most). */
typedef struct candidate {
  long long key;
  double x[MPM_MAX_DIM], n[MPM_MAX_DIM];
} candidate;

static int by_key(const void *a, const void *b) {
  const long long ka = ((const candidate *)a)->key, kb = ((const candidate *)b)->key;
  return (ka > kb) - (ka < kb);
}

/* Add the point at x with the unit normal n, if its stencil holds gas on SHARP_GAS_SHARE of its
 * weight and any solid. */
static int add_point(mpm_coupling *c, const double *x, const double *n) {
  sharp *s = c->content;
  const int dim = c->grid->dim;
  MPM_CALL(room(s, s->npt + 1));
  const int q = s->npt;
  mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
  double *cg = s->cg + (size_t)q * SHARP_STENCIL, *cs = s->cs + (size_t)q * SHARP_STENCIL;
  double w[SHARP_STENCIL];
  const int count = mpm_grid_point_stencil(c->grid, x, nq, w, NULL);
  if (!count) return 0;
  const mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                                 mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  double *cw[2] = {cg, cs}, share = 0.0;
  for (int f = 0; f < 2; ++f) {
    const mpm_role role = f == 0 ? MPM_ROLE_FLUID : MPM_ROLE_SOLID;
    double full = 0.0, sum = 0.0;
    for (int k = 0; k < count; ++k)
      if (mpm_coupling_has_mass(c, role, nq[k])) {
        full = fmax(full, ph[f]->m_i[nq[k]]);
        if (f == 0) share += w[k];
      }
    for (int k = 0; k < count; ++k) {
      const double m = mpm_coupling_has_mass(c, role, nq[k]) ? ph[f]->m_i[nq[k]] : 0.0;
      cw[f][k] = w[k] * fmin(1.0, m / (SHARP_NEAR_EMPTY * full));
      sum += cw[f][k];
    }
    if (!(sum > 0.0)) return 0;
    for (int k = 0; k < count; ++k) cw[f][k] /= sum;
  }
  if (!(share >= SHARP_GAS_SHARE)) return 0;
  for (int k = count; k < SHARP_STENCIL; ++k) nq[k] = 0, cg[k] = cs[k] = 0.0;
  for (int d = 0; d < MPM_MAX_DIM; ++d) s->n[(size_t)q * MPM_MAX_DIM + d] = d < dim ? n[d] : 0.0;
  s->npt++;
  return 0;
}

/* Does the gas have mass on a node within a cell of x along every axis (the 3^dim nodes around
 * the nearest one)? A surface particle's face point has gas in its stencil; a particle two
 * cells or more inside the solid has none around it, and is passed over without its stencils. */
static int gas_near(const mpm_coupling *c, const double *x) {
  const mpm_grid *g = c->grid;
  const int dim = g->dim;
  int near[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) near[d] = mpm_shape_floor((x[d] - g->lo[d]) / g->dx + 0.5);
  for (int k = 0; k < (dim == 3 ? 27 : 9); ++k) {
    int gi[MPM_MAX_DIM];
    int inside = 1;
    for (int d = 0, r = k; d < dim; ++d, r /= 3) {
      gi[d] = near[d] + r % 3 - 1;
      inside &= gi[d] >= g->box_lo[d] && gi[d] < g->box_lo[d] + g->box_n[d];
    }
    if (inside && mpm_coupling_has_mass(c, MPM_ROLE_FLUID, mpm_grid_local_index(g, gi))) return 1;
  }
  return 0;
}

/* The surface particles' face points (see the header), as candidates. */
static int find_candidates(mpm_coupling *c) {
  sharp *s = c->content;
  const mpm_grid *g = c->grid;
  const int dim = g->dim;
  const mpm_particles *p = c->module[MPM_ROLE_SOLID]->particles;
  const mpm_grid_phase *ps = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const double *m = mpm_particles_comp(p, s->f_m, 0), *V0 = mpm_particles_comp(p, s->f_V0, 0);
  const double cell = pow(g->dx, dim);
  s->ncand = 0;
  for (mpm_lidx i = 0; i < p->n; ++i) {
    mpm_lidx node[SHARP_STENCIL];
    double w[SHARP_STENCIL], dw[SHARP_STENCIL][MPM_MAX_DIM], x[MPM_MAX_DIM], y[MPM_MAX_DIM];
    for (int d = 0; d < dim; ++d) x[d] = mpm_particles_comp(p, 0, d)[i];
    if (!gas_near(c, x)) continue;
    int count = mpm_grid_point_stencil(g, x, node, w, dw);
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
    count = mpm_grid_point_stencil(g, y, node, w, NULL);
    double fill = 0.0;
    for (int k = 0; k < count; ++k) fill += w[k] * ps->m_i[node[k]];
    if (!count || !(fill < SHARP_FILL * full)) continue;
    if (s->ncand == s->ccap) {
      const int cap = 2 * s->ccap + 64;
      candidate *grown = realloc(s->cand, sizeof *grown * (size_t)cap);
      if (!grown) MPM_FAIL_OOM(sizeof *grown * (size_t)cap);
      s->cand = grown, s->ccap = cap;
    }
    candidate *k = &s->cand[s->ncand++];
    int axis = 0;
    long long key = 0;
    for (int d = 0; d < dim; ++d) {
      if (fabs(n[d]) > fabs(n[axis])) axis = d;
      key = key * (g->ncells[dim - 1 - d] + 2) +
            mpm_shape_floor((x[dim - 1 - d] - g->lo[dim - 1 - d]) / g->dx) + 1;
    }
    k->key = key * 2 * MPM_MAX_DIM + 2 * axis + (n[axis] > 0.0);
    for (int d = 0; d < MPM_MAX_DIM; ++d)
      k->x[d] = d < dim ? x[d] + r * n[d] : 0.0, k->n[d] = d < dim ? n[d] : 0.0;
  }
  return 0;
}

/* The interface points: one per surface cell and face direction, the mean of its surface
 * particles' face points and normals. One point per particle (two per cell along a face at
 * ppc 2) outnumbers the nodes that carry the face's velocity, which made A singular and the
 * solve stall at a relative residual of 1e-5 at the corners of cases/fsi_box.ini; the key is the
 * particle's own cell, so that the merge is the same on any number of ranks. */
static int find_points(mpm_coupling *c) {
  sharp *s = c->content;
  const int dim = c->grid->dim;
  MPM_CALL(find_candidates(c));
  if (s->ncand > 1) qsort(s->cand, (size_t)s->ncand, sizeof *s->cand, by_key);
  s->npt = 0;
  for (int a = 0, b; a < s->ncand; a = b) {
    double x[MPM_MAX_DIM] = {0}, n[MPM_MAX_DIM] = {0}, norm = 0.0;
    for (b = a; b < s->ncand && s->cand[b].key == s->cand[a].key; ++b)
      for (int d = 0; d < dim; ++d) x[d] += s->cand[b].x[d], n[d] += s->cand[b].n[d];
    for (int d = 0; d < dim; ++d) x[d] /= b - a, norm += n[d] * n[d];
    if (!(norm > 0.0)) continue;
    for (int d = 0; d < dim; ++d) n[d] /= sqrt(norm);
    MPM_CALL(add_point(c, x, n));
  }
  return 0;
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
      for (mpm_lidx l = 0; l < g->nnodes; ++l) u[l] = u[l] != 0.0 ? u[l] / ph[f]->m_i[l] : 0.0;
    }
  return mpm_grid_halo_forward(g, s->nod_ptr, 2 * dim);
}

/* out_q = n_q . (C_g w_g + sign C_s w_s)(x_q): with spread's arrays and sign 1, A applied to
 * spread's multipliers (gather); with the phases' v_i or a_i and sign -1, their jumps. */
static void normal_sums(const mpm_coupling *c, double *const *wg, double *const *ws, double sign,
                        double *out) {
  const sharp *s = c->content;
  const int dim = c->grid->dim;
  for (int q = 0; q < s->npt; ++q) {
    const mpm_lidx *nq = s->node + (size_t)q * SHARP_STENCIL;
    const double *n = s->n + (size_t)q * MPM_MAX_DIM;
    const double *cg = s->cg + (size_t)q * SHARP_STENCIL, *cs = s->cs + (size_t)q * SHARP_STENCIL;
    double sum = 0.0;
    for (int k = 0; k < SHARP_STENCIL; ++k)
      for (int d = 0; d < dim; ++d)
        sum += n[d] * (cg[k] * wg[d][nq[k]] + sign * cs[k] * ws[d][nq[k]]);
    out[q] = sum;
  }
}

/* out_q = n_q . (C_g u_g + C_s u_s)(x_q) from spread's arrays. */
static void gather(const mpm_coupling *c, double *out) {
  const sharp *s = c->content;
  normal_sums(c, s->nod_ptr, s->nod_ptr + c->grid->dim, 1.0, out);
}

static int dot(const mpm_coupling *c, const double *a, const double *b, double *out) {
  const sharp *s = c->content;
  double sum = 0.0;
  for (int q = 0; q < s->npt; ++q) sum += a[q] * b[q];
  MPM_CALL_MPI(MPI_Allreduce(&sum, out, 1, MPI_DOUBLE, MPI_SUM, c->grid->comm));
  return 0;
}

/* A's diagonal, A_qq = sum_k (c_g,k^2 / m_g,k + c_s,k^2 / m_s,k) (n_q a unit vector), into diag;
 * its largest value over the ranks in *amax. */
static int diagonal(const mpm_coupling *c, double *diag, double *amax) {
  const sharp *s = c->content;
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const mpm_grid_phase *so = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  double big = 0.0;
  for (int q = 0; q < s->npt; ++q) {
    double a = 0.0;
    for (int k = 0; k < SHARP_STENCIL; ++k) {
      const size_t at = (size_t)q * SHARP_STENCIL + (size_t)k;
      const mpm_lidx l = s->node[at];
      if (s->cg[at] != 0.0) a += s->cg[at] * s->cg[at] / g->m_i[l];
      if (s->cs[at] != 0.0) a += s->cs[at] * s->cs[at] / so->m_i[l];
    }
    diag[q] = a, big = fmax(big, a);
  }
  MPM_CALL_MPI(MPI_Allreduce(&big, amax, 1, MPI_DOUBLE, MPI_MAX, c->grid->comm));
  return 0;
}

/* lam += (A + delta I)^-1 r by conjugate gradients preconditioned with the diagonal
 * (dinv: 1 / (A_qq + delta)), from a zero correction; r is overwritten. */
static int pcg(mpm_coupling *c, double delta) {
  sharp *s = c->content;
  double rz0, rz, pAp;
  for (int q = 0; q < s->npt; ++q) s->z[q] = s->dinv[q] * s->r[q], s->p[q] = s->z[q];
  MPM_CALL(dot(c, s->r, s->z, &rz0));
  rz = rz0;
  for (int it = 0; it < SHARP_MAX_IT && rz > SHARP_TOL * SHARP_TOL * rz0 && rz > 0.0; ++it) {
    MPM_CALL(spread(c, s->p));
    gather(c, s->Ap);
    for (int q = 0; q < s->npt; ++q) s->Ap[q] += delta * s->p[q];
    MPM_CALL(dot(c, s->p, s->Ap, &pAp));
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
    for (int q = 0; q < s->npt; ++q) {
      s->lam[q] += alpha * s->p[q], s->r[q] -= alpha * s->Ap[q];
      s->z[q] = s->dinv[q] * s->r[q];
    }
    double rz1;
    MPM_CALL(dot(c, s->r, s->z, &rz1));
    for (int q = 0; q < s->npt; ++q) s->p[q] = s->z[q] + rz1 / rz * s->p[q];
    rz = rz1;
  }
  return 0;
}

/* Solve A lam = g (g: the points' normal velocity jumps, in jump). A may be singular (points
 * whose rows repeat, as at a corner); the shift delta = SHARP_SHIFT max diag A makes each solve
 * definite (without one, the roundoff outside A's range grew lam to 1e21 at a shock's impact),
 * and SHARP_REFINE passes of iterative refinement, lam += (A + delta I)^-1 (g - A lam), remove
 * its bias on A's range (each pass by a factor delta / A) and leave the rest bounded: the shift
 * alone left the gas against a pre-stressed slab moving at 5e-10 c after 1,000 steps.
 * Collective: every rank iterates alike. */
static int solve(mpm_coupling *c, const double *jump) {
  sharp *s = c->content;
  double amax;
  MPM_CALL(diagonal(c, s->dinv, &amax));
  const double delta = SHARP_SHIFT * amax;
  for (int q = 0; q < s->npt; ++q) s->dinv[q] = 1.0 / (s->dinv[q] + delta), s->lam[q] = 0.0;
  for (int pass = 0; pass <= SHARP_REFINE; ++pass) {
    if (pass == 0) {
      for (int q = 0; q < s->npt; ++q) s->r[q] = jump[q];
    } else {
      MPM_CALL(spread(c, s->lam));
      gather(c, s->r);
      for (int q = 0; q < s->npt; ++q) s->r[q] = jump[q] - s->r[q];
    }
    MPM_CALL(pcg(c, delta));
  }
  return 0;
}

/* Deep inside the solid, where |grad m_s| dx < SHARP_INSIDE m_s (two cells or more from a face;
 * the node a cell inside a straight face gives 0.25), gas that got there shares the velocity of
 * the centre of mass with the solid, as under `traction`: the points tie the fields at the
 * surface only, and a gas particle that crossed it would otherwise pass through the solid. Gas
 * outside the solid does not reach those nodes (its stencil ends 1.25 cells beyond its last
 * particle), so the linear interface is left as the points make it. In the method of lines
 * (h = 0) the acceleration of the centre of mass too, and the phases' own velocities relax
 * towards each other at the rate k, by equal and opposite forces k mu (u_g - u_s), as the
 * shared nodes of `velocity` do (mpm_coupling.h). */
static void tie_inside(mpm_coupling *c, double h) {
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const int dim = c->grid->dim;
  const double k = h > 0 ? 0.0 : c->relax_rate;
  for (mpm_lidx l = 0; l < c->grid->nnodes; ++l) {
    double n[MPM_MAX_DIM], v[MPM_MAX_DIM], as[MPM_MAX_DIM], ag[MPM_MAX_DIM];
    if (!mpm_coupling_shared(c, l) || mpm_coupling_solid_surface(c, l, SHARP_INSIDE, n)) continue;
    const double ms = s->m_i[l], mg = g->m_i[l], mu = ms * mg / (ms + mg);
    for (int d = 0; d < dim; ++d) {
      const double a = (ms * s->a_i[d][l] + mg * g->a_i[d][l]) / (ms + mg);
      const double f = k * mu * (g->v_i[d][l] - s->v_i[d][l]); /* (v_i = mv / m here) */
      v[d] = (ms * s->v_i[d][l] + mg * g->v_i[d][l]) / (ms + mg);
      as[d] = a + f / ms, ag[d] = a - f / mg;
    }
    mpm_coupling_exchange(c, MPM_ROLE_FLUID, l, v, ag, h);
    mpm_coupling_exchange(c, MPM_ROLE_SOLID, l, v, as, h);
  }
}

/* Where both phases have mass and one of them holds less than SHARP_NEAR_EMPTY of its fullest
 * node within SHARP_REACH nodes, that phase's normal velocity (and, in the method of lines, its
 * normal acceleration) moves towards the centre of mass's by the share beta = 1 - m /
 * (SHARP_NEAR_EMPTY full), the other phase taking the opposite momentum; n is the solid's normal
 * at the node. Along the normal only, as the points tie: blending every component held the gas
 * beside the main job's rigid bar like a no-slip layer (its stand-off 3.3-4.0 mm further out,
 * its drag 5.0 % above the slip obstacle's against 1.7 % below). Why: such a node is a phase's
 * spline tail across the face (the gas's inside the solid, the solid's in the gas), which the
 * points' rows barely read (add_point) but the phase's last particles do, through their rates.
 * Left free, the gas's tail node beyond a soft slab's moving face took the outward push of the
 * gas's pressure on its own (1.38 against the face's 1.19 at t = 0.3), and the first gas column
 * expanded into the face (p / p* 0.53 at t = 0.35). The blend is continuous in the mass; on a
 * face a quarter cell from the particles (the resonator, the near-rigid slab) no node is that
 * empty. Needs the ghosts' m_i, v_i (a_i) filled; leaves the ghosts stale (the caller refills
 * them). */
static void tie_near_empty(mpm_coupling *c, double h) {
  const mpm_grid *g = c->grid;
  const int dim = g->dim;
  mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                           mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  const mpm_role role[2] = {MPM_ROLE_FLUID, MPM_ROLE_SOLID};
  const mpm_lidx stride[3] = {1, g->box_n[0], (mpm_lidx)g->box_n[0] * (dim > 1 ? g->box_n[1] : 1)};
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!mpm_coupling_shared(c, l)) continue;
    int gi[MPM_MAX_DIM] = {0}, lo[MPM_MAX_DIM] = {0}, hi[MPM_MAX_DIM] = {0};
    for (int d = 0; d < dim; ++d) {
      gi[d] = (int)(l / stride[d] % g->box_n[d]);
      lo[d] = gi[d] >= SHARP_REACH ? -SHARP_REACH : -gi[d];
      hi[d] = gi[d] + SHARP_REACH < g->box_n[d] ? SHARP_REACH : g->box_n[d] - 1 - gi[d];
    }
    double full[2] = {0.0, 0.0};
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const mpm_lidx nb = l + i + j * stride[1] + k * stride[2];
          for (int f = 0; f < 2; ++f) full[f] = fmax(full[f], ph[f]->m_i[nb]);
        }
    double n[MPM_MAX_DIM];
    for (int f = 0; f < 2; ++f) {
      const double beta = 1.0 - ph[f]->m_i[l] / (SHARP_NEAR_EMPTY * full[f]);
      if (!(beta > 0.0)) continue;
      if (!mpm_coupling_solid_normal(c, l, n)) break;
      const mpm_grid_phase *me = ph[f], *other = ph[1 - f];
      const double m = me->m_i[l], mo = other->m_i[l];
      double jv = 0.0, ja = 0.0, v[2][MPM_MAX_DIM], a[2][MPM_MAX_DIM];
      for (int d = 0; d < dim; ++d) {
        jv += n[d] * (other->v_i[d][l] - me->v_i[d][l]);
        if (h == 0) ja += n[d] * (other->a_i[d][l] - me->a_i[d][l]);
      }
      const double dv = beta * mo / (m + mo) * jv, da = beta * mo / (m + mo) * ja;
      for (int d = 0; d < dim; ++d) {
        v[0][d] = me->v_i[d][l] + dv * n[d], v[1][d] = other->v_i[d][l] - m / mo * dv * n[d];
        a[0][d] = h > 0 ? 0.0 : me->a_i[d][l] + da * n[d];
        a[1][d] = h > 0 ? 0.0 : other->a_i[d][l] - m / mo * da * n[d];
      }
      mpm_coupling_exchange(c, role[f], l, v[0], h > 0 ? NULL : a[0], h);
      mpm_coupling_exchange(c, role[1 - f], l, v[1], h > 0 ? NULL : a[1], h);
      break;
    }
  }
}

/* out_q = n_q . (C_g w_g - C_s w_s)(x_q), w the phases' nodal v_i (0) or a_i (1). */
static void jumps(const mpm_coupling *c, int accel, double *out) {
  const mpm_grid_phase *g = mpm_coupling_phase(c, MPM_ROLE_FLUID);
  const mpm_grid_phase *so = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  normal_sums(c, accel ? g->a_i : g->v_i, accel ? so->a_i : so->v_i, -1.0, out);
}

/* The multipliers of the jumps g, spread to the nodes: per unit nodal mass, what the gas loses
 * and the solid gains (spread), copied into `into` (2 dim nnodes) unless NULL. Collective. */
static int multipliers(mpm_coupling *c, const double *g, double *into) {
  sharp *s = c->content;
  MPM_CALL(solve(c, g));
  MPM_CALL(spread(c, s->lam));
  if (into) memcpy(into, s->nod, sizeof *into * (size_t)(2 * c->grid->dim) * c->grid->nnodes);
  return 0;
}

/* Apply the spread multipliers, one exchange per node and phase: dv (2 dim nnodes, NULL: none)
 * to the velocities (in the classic update an impulse over the step h; in the method of lines
 * the positions' kinematics) and da (NULL: none) to the accelerations (a force). In the method
 * of lines the velocity and acceleration change in one exchange, which books the force's power
 * at the deposited velocity and the module's own force's on the kinematic correction
 * (common/mpm_impulse.h); two exchanges in turn would book it at a corrected velocity. */
static void apply(mpm_coupling *c, const double *dv, const double *da, double h) {
  const mpm_grid *grid = c->grid;
  const int dim = grid->dim;
  const size_t nn = (size_t)grid->nnodes;
  mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                           mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  const mpm_role role[2] = {MPM_ROLE_FLUID, MPM_ROLE_SOLID};
  const double sign[2] = {-1.0, 1.0};
  for (mpm_lidx l = 0; l < grid->nnodes; ++l)
    for (int f = 0; f < 2; ++f) {
      double v[MPM_MAX_DIM], a[MPM_MAX_DIM], change = 0.0;
      for (int d = 0; d < dim; ++d) {
        const size_t at = (size_t)(f * dim + d) * nn + (size_t)l;
        const double uv = dv ? dv[at] : 0.0, ua = da ? da[at] : 0.0;
        v[d] = ph[f]->v_i[d][l] + sign[f] * uv;
        a[d] = ph[f]->a_i[d][l] + sign[f] * ua, change += fabs(uv) + fabs(ua);
      }
      if (change > 0.0) mpm_coupling_exchange(c, role[f], l, v, da ? a : NULL, h);
    }
}

static int sharp_after_solve(mpm_coupling *c, double t, double h, mpm_pass pass) {
  (void)t, (void)pass;
  sharp *s = c->content;
  mpm_grid *g = c->grid;
  const int dim = g->dim;
  mpm_grid_phase *ph[2] = {mpm_coupling_phase(c, MPM_ROLE_FLUID),
                           mpm_coupling_phase(c, MPM_ROLE_SOLID)};
  tie_inside(c, h);
  /* The hooks see summed values on the owned nodes only: fill the ghosts the stencils read. */
  int nsync = 0;
  for (int f = 0; f < 2; ++f) {
    s->sync_ptr[nsync++] = ph[f]->m_i;
    for (int d = 0; d < dim; ++d) s->sync_ptr[nsync++] = ph[f]->v_i[d];
    for (int d = 0; h == 0 && d < dim; ++d) s->sync_ptr[nsync++] = ph[f]->a_i[d];
  }
  MPM_CALL(mpm_grid_halo_forward(g, s->sync_ptr, nsync));
  tie_near_empty(c, h);
  MPM_CALL(mpm_grid_halo_forward(g, s->sync_ptr, nsync));
  MPM_CALL(find_points(c));
  jumps(c, 0, s->g); /* n . (v_g - v_s) at the points; in the method of lines v = u = mv / m */
  if (h > 0) {
    MPM_CALL(multipliers(c, s->g, NULL));
    apply(c, s->nod, NULL, h);
    return 0;
  }
  MPM_CALL(multipliers(c, s->g, s->dv));
  jumps(c, 1, s->ju); /* n . (a_g - a_s), the drift relaxed: n . (a_g - a_s) = -k n . (u_g - u_s) */
  for (int q = 0; q < s->npt; ++q) s->ju[q] += c->relax_rate * s->g[q];
  MPM_CALL(multipliers(c, s->ju, NULL));
  apply(c, s->dv, s->nod, h);
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
            "nodal impulses (usl, musl, the ERK pairs; monolithic or multirate)",
    .needs = MPM_COUPLING_NORMALS | MPM_COUPLING_HOLDS | MPM_COUPLING_RATE,
    .keys = sharp_keys,
    .nkeys = sizeof sharp_keys / sizeof sharp_keys[0],
    .ops = &sharp_ops,
};
