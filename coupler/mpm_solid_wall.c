/* The solid's surface as a moving wall for the gas (see mpm_solid_wall.h). */
#include "mpm_solid_wall.h"

#include "mpm_bc.h"
#include "mpm_error.h"
#include "mpm_shape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mpm_solid_wall {
  mpm_coupling *c;
  mpm_wall_source src;
  double h;
  double *nod;                           /* (1 + dim) nnodes: the solid's m_i and mass gradient */
  double *nod_ptr[1 + MPM_MAX_DIM];      /* into nod, complete on every box node */
  double *J[MPM_MAX_DIM];                /* per box node: the momentum the solid takes, N s */
  int f_V0;                              /* the solid's reference volume field */
  int n, cap;                            /* gathered solid particles */
  double *gx;                            /* their positions and half-widths, (dim + 1) each */
  int *counts, *displs;                  /* per rank, for the gather */
  int blo[MPM_MAX_DIM], bn[MPM_MAX_DIM]; /* the bucket lattice: cells of dx over the particles */
  int *start, *order;                    /* cell b holds order[start[b] .. start[b + 1]) */
  size_t bcap;
  unsigned char *mark; /* the box grown by the reach, for mark_near */
  size_t mcap;
};

/* ---- the gathered particles --------------------------------------------------------------- */

/* Room for count values of gx (and count / stride particles in order), keeping what they hold. */
static int ensure(mpm_solid_wall *w, int count, int stride) {
  if (count <= w->cap) return 0;
  const int cap = count + count / 4 + stride;
  double *gx = realloc(w->gx, sizeof *gx * (size_t)cap);
  if (gx) w->gx = gx;
  int *order = realloc(w->order, sizeof *order * (size_t)(cap / stride + 1));
  if (order) w->order = order;
  if (!gx || !order)
    MPM_FAIL(MPM_ERR_MEMORY, "cannot gather %d solid particles for the interface wall",
             count / stride);
  w->cap = cap;
  return 0;
}

/* Every solid particle on every rank, and along a periodic axis the images (shifted by the
 * period) of those within margin of a face, so that a search near the seam sees the solid
 * across it. */
static int gather(mpm_solid_wall *w, double margin) {
  const mpm_grid *g = w->c->grid;
  const mpm_particles *p = w->c->module[MPM_ROLE_SOLID]->particles;
  const int dim = g->dim, stride = dim + 1;
  const int mine = (int)p->n * stride;
  MPM_CALL_MPI(MPI_Allgather(&mine, 1, MPI_INT, w->counts, 1, MPI_INT, g->comm));
  int total = 0;
  for (int r = 0; r < g->size; ++r) w->displs[r] = total, total += w->counts[r];
  MPM_CALL(ensure(w, total, stride));
  double *local = w->gx + w->displs[g->rank];
  const double *V0 = mpm_particles_comp(p, w->f_V0, 0);
  for (mpm_lidx i = 0; i < p->n; ++i) {
    for (int d = 0; d < dim; ++d) local[(size_t)i * stride + d] = mpm_particles_comp(p, 0, d)[i];
    local[(size_t)i * stride + dim] = 0.5 * pow(V0[i], 1.0 / dim);
  }
  MPM_CALL_MPI(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DOUBLE, w->gx, w->counts, w->displs, MPI_DOUBLE,
                              g->comm));
  w->n = total / stride;
  for (int d = 0; d < dim; ++d) { /* images along each periodic axis, of images too (corners) */
    if (!g->periodic[d]) continue;
    const double L = g->hi[d] - g->lo[d];
    int extra = 0;
    for (int q = 0; q < w->n; ++q) {
      const double x = w->gx[(size_t)q * stride + d];
      extra += (x < g->lo[d] + margin) + (x > g->hi[d] - margin);
    }
    MPM_CALL(ensure(w, (w->n + extra) * stride, stride));
    const int n0 = w->n;
    for (int q = 0; q < n0; ++q) {
      const double *xq = w->gx + (size_t)q * stride;
      for (int side = 0; side < 2; ++side) {
        if (side ? !(xq[d] > g->hi[d] - margin) : !(xq[d] < g->lo[d] + margin)) continue;
        double *img = w->gx + (size_t)w->n++ * stride;
        memcpy(img, xq, sizeof *img * (size_t)stride);
        img[d] += side ? -L : L;
      }
    }
  }
  return 0;
}

/* The bucket cell of x, clamped to the lattice. */
static int bucket_of(const mpm_solid_wall *w, const double *x) {
  const mpm_grid *g = w->c->grid;
  int k = 0;
  for (int d = g->dim - 1; d >= 0; --d) {
    int b = mpm_shape_floor((x[d] - g->lo[d]) / g->dx) - w->blo[d];
    b = b < 0 ? 0 : b >= w->bn[d] ? w->bn[d] - 1 : b;
    k = k * w->bn[d] + b;
  }
  return k;
}

/* Sort the gathered particles by cell over their bounding box (a counting sort). */
static int bucket(mpm_solid_wall *w) {
  const mpm_grid *g = w->c->grid;
  const int dim = g->dim, stride = dim + 1;
  size_t cells = 1;
  for (int d = 0; d < dim; ++d) {
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (int q = 0; q < w->n; ++q) {
      lo = fmin(lo, w->gx[(size_t)q * stride + d]);
      hi = fmax(hi, w->gx[(size_t)q * stride + d]);
    }
    if (w->n == 0) lo = hi = g->lo[d];
    w->blo[d] = mpm_shape_floor((lo - g->lo[d]) / g->dx);
    w->bn[d] = mpm_shape_floor((hi - g->lo[d]) / g->dx) - w->blo[d] + 1;
    cells *= (size_t)w->bn[d];
  }
  if (cells + 1 > w->bcap) {
    free(w->start);
    w->bcap = 0;
    MPM_ALLOC(w->start, cells + 1);
    w->bcap = cells + 1;
  }
  memset(w->start, 0, sizeof *w->start * (cells + 1));
  for (int q = 0; q < w->n; ++q) w->start[bucket_of(w, w->gx + (size_t)q * stride) + 1]++;
  for (size_t k = 0; k < cells; ++k) w->start[k + 1] += w->start[k];
  for (int q = 0; q < w->n; ++q) w->order[w->start[bucket_of(w, w->gx + (size_t)q * stride)]++] = q;
  for (size_t k = cells; k > 0; --k) w->start[k] = w->start[k - 1];
  w->start[0] = 0;
  return 0;
}

/* ---- the source's calls ------------------------------------------------------------------- */

/* Flag the box cells within span cells along every axis of a cell that holds a solid particle:
 * the particles' cells are marked on the box grown by span, which is then dilated along each
 * axis in turn by a forward and a backward sweep (the cost follows the cells, not the particle
 * count). */
static int mark_near(mpm_solid_wall *w, int span, unsigned char value, unsigned char *cells) {
  const mpm_grid *g = w->c->grid;
  const int dim = g->dim, stride = dim + 1;
  int lo[MPM_MAX_DIM], n[MPM_MAX_DIM], nmax = 0;
  size_t total = 1, step[MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) {
    lo[d] = g->box_lo[d] - span, n[d] = g->box_n[d] + 2 * span;
    step[d] = total, total *= (size_t)n[d], nmax = MPM_MAX(nmax, n[d]);
  }
  if (total + (size_t)nmax > w->mcap) {
    free(w->mark);
    w->mcap = 0;
    MPM_ALLOC(w->mark, total + (size_t)nmax);
    w->mcap = total + (size_t)nmax;
  }
  unsigned char *m = w->mark, *line = w->mark + total;
  memset(m, 0, total);
  for (int q = 0; q < w->n; ++q) {
    size_t k = 0;
    int in = 1;
    for (int d = 0; d < dim; ++d) {
      const int c = mpm_shape_floor((w->gx[(size_t)q * stride + d] - g->lo[d]) / g->dx) - lo[d];
      in &= c >= 0 && c < n[d];
      k += (size_t)(in ? c : 0) * step[d];
    }
    if (in) m[k] = 1;
  }
  for (int a = 0; a < dim; ++a) /* every line along axis a: o runs over the other axes */
    for (size_t o = 0; o < total / (size_t)n[a]; ++o) {
      const size_t first = o / step[a] * step[a] * (size_t)n[a] + o % step[a];
      for (int i = 0; i < n[a]; ++i) line[i] = m[first + (size_t)i * step[a]];
      int last = -2 * span - 1;
      for (int i = 0; i < n[a]; ++i) {
        if (line[i]) last = i;
        m[first + (size_t)i * step[a]] = i - last <= span;
      }
      last = n[a] + 2 * span + 1;
      for (int i = n[a] - 1; i >= 0; --i) {
        if (line[i]) last = i;
        m[first + (size_t)i * step[a]] |= last - i <= span;
      }
    }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    int gi[MPM_MAX_DIM];
    size_t k = 0;
    mpm_grid_node_global(g, l, gi);
    for (int d = 0; d < dim; ++d) k += (size_t)(gi[d] - lo[d]) * step[d];
    if (m[k] && cells[l] < value) cells[l] = value;
  }
  return 0;
}

static int wall_prepare(void *ctx, double h, double reach, double range, unsigned char *cells,
                        double *lo, double *hi) {
  mpm_solid_wall *w = ctx;
  mpm_grid *g = w->c->grid;
  const mpm_grid_phase *s = mpm_coupling_phase(w->c, MPM_ROLE_SOLID);
  const int dim = g->dim;
  const size_t bytes = sizeof(double) * (size_t)g->nnodes;
  w->h = h;
  memcpy(w->nod_ptr[0], s->m_i, bytes);
  for (int d = 0; d < dim; ++d) {
    memcpy(w->nod_ptr[1 + d], s->normal_i[d], bytes);
    memset(w->J[d], 0, bytes);
  }
  MPM_CALL(mpm_grid_halo_forward(g, w->nod_ptr, 1 + dim)); /* owners hold the sums */
  /* A search reaches range + dx <= reach + dx from a gas particle, which may lie a cell beyond
   * its rank's cells; the marking reaches reach + the half-width. */
  MPM_CALL(gather(w, reach + 3.0 * g->dx));
  MPM_CALL(bucket(w));
  /* The cells within reach of a solid particle (its centre, plus its half-width). */
  double rmax = 0.0;
  for (int d = 0; d < dim; ++d) lo[d] = HUGE_VAL, hi[d] = -HUGE_VAL;
  for (int q = 0; q < w->n; ++q) {
    const double *xq = w->gx + (size_t)q * (dim + 1);
    rmax = fmax(rmax, xq[dim]);
    for (int d = 0; d < dim; ++d)
      lo[d] = fmin(lo[d], xq[d] - xq[dim]), hi[d] = fmax(hi[d], xq[d] + xq[dim]);
  }
  /* wall_at looks at the particles within range + dx: a point whose cell is more than that
   * many cells, and one, from every particle's cell finds none. */
  MPM_CALL(mark_near(w, (int)ceil((reach + rmax) / g->dx), 1, cells));
  return mark_near(w, (int)ceil((range + g->dx) / g->dx) + 1, 2, cells);
}

/* The solid's nodal sums at x over its stencil: sum S m, sum S m v, sum S grad m; 0 if x's
 * stencil leaves the box. */
static int nodal_at(const mpm_solid_wall *w, const double *x, double *m, double *mv, double *gm) {
  const mpm_grid *g = w->c->grid;
  const mpm_grid_phase *s = mpm_coupling_phase(w->c, MPM_ROLE_SOLID);
  const int dim = g->dim;
  mpm_lidx node[MPM_GRID_STENCIL_MAX];
  double W[MPM_GRID_STENCIL_MAX];
  const int count = mpm_grid_point_stencil(g, x, node, W, NULL);
  *m = 0.0;
  for (int d = 0; d < dim; ++d) mv[d] = gm[d] = 0.0;
  for (int k = 0; k < count; ++k) {
    const mpm_lidx l = node[k];
    const double ml = w->nod_ptr[0][l];
    *m += W[k] * ml;
    for (int d = 0; d < dim; ++d)
      mv[d] += W[k] * ml * s->v_i[d][l], gm[d] += W[k] * w->nod_ptr[1 + d][l];
  }
  return count > 0;
}

static int wall_at(void *ctx, const double *x, double range, double *phi, double *n, double *v) {
  const mpm_solid_wall *w = ctx;
  const mpm_grid *g = w->c->grid;
  const int dim = g->dim, stride = dim + 1;
  double m, mv[MPM_MAX_DIM], gm[MPM_MAX_DIM], len = 0.0;
  if (!nodal_at(w, x, &m, mv, gm) || !(m > 0.0)) return 0;
  for (int d = 0; d < dim; ++d) len += gm[d] * gm[d];
  len = sqrt(len);
  if (!(len > 0.0)) return 0;
  for (int d = 0; d < dim; ++d) n[d] = gm[d] / len, v[d] = mv[d] / m;
  /* The particles within range + dx: the cells within that many of x's cell. */
  const double R = range + g->dx;
  const int span = (int)ceil(R / g->dx);
  int lo[MPM_MAX_DIM], hi[MPM_MAX_DIM], count = 1;
  for (int d = 0; d < dim; ++d) {
    const int c = mpm_shape_floor((x[d] - g->lo[d]) / g->dx) - w->blo[d];
    lo[d] = MPM_MAX(c - span, 0), hi[d] = MPM_MIN(c + span + 1, w->bn[d]);
    if (hi[d] <= lo[d]) return 0;
    count *= hi[d] - lo[d];
  }
  int found = 0;
  double best = HUGE_VAL;
  for (int k = 0; k < count; ++k) {
    int cell = 0;
    for (int d = dim - 1; d >= 0; --d) {
      int r = k;
      for (int e = 0; e < d; ++e) r /= hi[e] - lo[e];
      cell = cell * w->bn[d] + lo[d] + r % (hi[d] - lo[d]);
    }
    for (int j = w->start[cell]; j < w->start[cell + 1]; ++j) {
      const double *xq = w->gx + (size_t)w->order[j] * stride;
      double r2 = 0.0, dn = 0.0;
      for (int d = 0; d < dim; ++d)
        r2 += (x[d] - xq[d]) * (x[d] - xq[d]), dn += (x[d] - xq[d]) * n[d];
      if (r2 > R * R) continue;
      found = 1;
      best = fmin(best, dn - xq[dim]);
    }
  }
  *phi = best;
  return found;
}

static double wall_impulse(void *ctx, const double *x, const double *J) {
  mpm_solid_wall *w = ctx;
  mpm_coupling *c = w->c;
  const mpm_grid *g = c->grid;
  const mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const int dim = g->dim;
  const double h = w->h;
  mpm_lidx node[MPM_GRID_STENCIL_MAX];
  double share[MPM_GRID_STENCIL_MAX], sum = 0.0, work = 0.0;
  /* (wall_at found x inside the box, with mass) */
  const int count = mpm_grid_point_stencil(g, x, node, share, NULL);
  for (int k = 0; k < count; ++k) share[k] *= w->nod_ptr[0][node[k]], sum += share[k];
  /* The work at the nodes' time-centred velocity v - h a / 2, as the solid's exchange counts
   * it (wall_finish): what the gas gains the solid loses, less the impulse's own sum J^2 / 2m. */
  for (int k = 0; k < count; ++k)
    for (int d = 0; share[k] > 0.0 && d < dim; ++d) {
      const double Jk = J[d] * (share[k] / sum);
      w->J[d][node[k]] -= Jk;
      work += Jk * (s->v_i[d][node[k]] - 0.5 * h * s->a_i[d][node[k]]);
    }
  mpm_coupling_record *r = &c->rec[c->which.latest];
  for (int d = 0; d < dim; ++d) r->force[MPM_ROLE_FLUID][d] += J[d] / h;
  r->power[MPM_ROLE_FLUID] += work / h;
  return work;
}

static int wall_finish(void *ctx) {
  mpm_solid_wall *w = ctx;
  mpm_coupling *c = w->c;
  mpm_grid *g = c->grid;
  mpm_grid_phase *s = mpm_coupling_phase(c, MPM_ROLE_SOLID);
  const int dim = g->dim;
  MPM_CALL(mpm_grid_halo_reverse(g, w->J, dim));
  /* An impulse: a' = a + J / (m h), v' = v + J / m. The force is recorded as J / h itself, not
   * as m (v' - v) / h, whose cancellation (J / m is small against v) costs digits. The power is
   * time-centred, as in mpm_impulse_apply. A component that the solid's own constraint set
   * (a wall face, a clamp, a rigid body: it differs from what the nodal solve and the scheme
   * gave, MPM_COUPLING_HOLDS) keeps its value: the constraint takes the impulse, which is still
   * the gas's load on the solid (as mpm_coupling_follow_solid books it). */
  const double h = w->h;
  c->recording = 1;
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!c->owned[l] || !(s->m_i[l] > 0.0)) continue;
    double f[MPM_MAX_DIM], vc[MPM_MAX_DIM];
    int any = 0;
    for (int d = 0; d < dim; ++d) {
      const double v0 = s->v_i[d][l], a0 = s->a_i[d][l];
      const int held = c->held_v[d] && (v0 != c->held_v[d][l] || a0 != c->held_a[d][l]);
      const double dv = held ? 0.0 : w->J[d][l] / s->m_i[l];
      any |= w->J[d][l] != 0.0;
      f[d] = w->J[d][l] / h;
      vc[d] = 0.5 * (v0 - h * a0 + v0 + dv);
      s->v_i[d][l] = v0 + dv, s->a_i[d][l] = a0 + dv / h;
    }
    if (any) mpm_coupling_record_force(c, MPM_ROLE_SOLID, l, f, vc);
  }
  c->recording = 0;
  double *f[2 * MPM_MAX_DIM];
  for (int d = 0; d < dim; ++d) f[2 * d] = s->v_i[d], f[2 * d + 1] = s->a_i[d];
  return mpm_grid_halo_forward(g, f, 2 * dim);
}

/* ---- construction ------------------------------------------------------------------------- */

void mpm_solid_wall_free(mpm_solid_wall **wp) {
  if (!wp || !*wp) return;
  mpm_solid_wall *w = *wp;
  free(w->nod);
  for (int d = 0; d < MPM_MAX_DIM; ++d) free(w->J[d]);
  free(w->gx), free(w->order), free(w->start), free(w->counts), free(w->displs), free(w->mark);
  free(w);
  *wp = NULL;
}

int mpm_solid_wall_offer(mpm_coupling *c, const mpm_config *cfg, mpm_solid_wall **wp) {
  *wp = NULL;
  mpm_module *gas = c->module[MPM_ROLE_FLUID];
  const mpm_module *solid = c->module[MPM_ROLE_SOLID];
  if (!gas->ops->attach_wall) return 0;
  mpm_solid_wall *w;
  MPM_ALLOC(w, 1);
  *wp = w;
  const mpm_grid *g = c->grid;
  w->c = c;
  w->f_V0 = mpm_particles_find(solid->particles, "V0");
  MPM_ALLOC(w->nod, (size_t)(1 + g->dim) * g->nnodes);
  for (int k = 0; k <= g->dim; ++k) w->nod_ptr[k] = w->nod + (size_t)k * g->nnodes;
  for (int d = 0; d < g->dim; ++d) MPM_ALLOC(w->J[d], g->nnodes);
  MPM_ALLOC(w->counts, g->size);
  MPM_ALLOC(w->displs, g->size);
  w->src = (mpm_wall_source){.ctx = w,
                             .prepare = wall_prepare,
                             .at = wall_at,
                             .impulse = wall_impulse,
                             .finish = wall_finish};
  if (w->f_V0 < 0) MPM_FAIL(MPM_ERR_INTERNAL, "the solid module has no V0 field");
  int taken = 0;
  MPM_CALL(gas->ops->attach_wall(gas, cfg, &w->src, &taken));
  if (!taken) {
    mpm_solid_wall_free(wp);
    return 0;
  }
  /* Refused below after the gas took it: the gas then holds a table that traction_destroy
   * frees, harmless since the run stops at the input error. */
  const char *time, *method;
  MPM_CALL(mpm_config_get_string(cfg, "time.method", &method));
  if (strcmp(method, "musl") == 0)
    return mpm_config_fail(cfg, "time.method",
                           "the least-squares wall at a traction interface needs time.method = "
                           "usl: under musl the solid's remap fixes its particles' velocities "
                           "before the gas's G2P fits the wall, so the fit's impulses would not "
                           "reach the solid; use usl, or fluid.wall_treatment = ghost");
  MPM_CALL(mpm_config_get_string(cfg, "coupling.time", &time));
  if (strcmp(time, "monolithic") != 0)
    return mpm_config_fail(
        cfg, mpm_config_has(cfg, "coupling.time") ? "coupling.time" : "fluid.wall_treatment",
        "the least-squares wall at a traction interface acts in the gas's "
        "G2P and needs the solid solved in the same cycle: use "
        "coupling.time = monolithic, or fluid.wall_treatment = ghost");
  return 0;
}
