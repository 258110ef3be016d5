/* test_periodic_p2g: grids with periodic axes on 1..N ranks.
 *
 * For 2-D and 3-D, every shape kind and several sets of periodic axes and splits (MPI's
 * choice; one rank along a periodic axis, which then exchanges with itself, with the ranks
 * split along another axis; a periodic strip only `ghost` cells wide) it checks:
 * - layout: along a periodic axis rank c owns exactly the nodes of its cells (no pad, no node
 *   ncells), its neighbours wrap around, and each of the ncells distinct nodes has exactly
 *   one owner over all ranks;
 * - P2G then the reverse halo, on the owned nodes, against the unbounded lattice: a serial
 *   P2G of the same particles on a non-periodic grid reaching K cells past each periodic
 *   face, folded modulo ncells. Tolerance 1e-13 relative to the largest value of each field
 *   (m, mv, f): the sums differ only in the order of the additions;
 * - the forward halo: every stored node, the images beyond a periodic face included, then
 *   holds the folded reference value (same tolerance);
 * - conservation: owned nodal mass and momentum against the particle totals, 1e-13 relative;
 * - translation: moving every particle by a whole period plus s cells and wrapping it back
 *   into the domain gives the same fields shifted cyclically by s nodes. Tolerance 1e-12
 *   relative: a translated position is off by roundoff (about 1e-16 m), which moves the
 *   weights by about 1e-15.
 * Particles are uniform in the domain, with extra ones within a cell of a periodic face and
 * some up to 0.9 cells beyond it, as they are during a step before migration wraps them;
 * such a particle is held by the rank that owns the nearest cell inside.
 * Also: wall rules skip periodic faces, and a periodic axis shorter than the ghost layers is
 * an input error. */
#include "mpm_bc.h"
#include "mpm_error.h"
#include "mpm_grid.h"
#include "mpm_kernels.h"

#include "mpm_testing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { NP = 3000, K = 4 };

typedef struct config {
  int dim, periodic[3], nproc[3];
  int strip; /* axis 1 only `ghost` cells long */
} config;

static const config g_configs[] = {
    {2, {1, 0, 0}, {0, 0, 0}, 0}, {2, {1, 0, 0}, {1, 0, 0}, 0}, {2, {1, 1, 0}, {0, 0, 0}, 0},
    {2, {0, 1, 0}, {0, 1, 0}, 1}, {3, {1, 1, 1}, {0, 0, 0}, 0}, {3, {0, 1, 0}, {0, 1, 0}, 0},
    {3, {1, 0, 1}, {0, 0, 0}, 0},
};

typedef struct pset {
  int dim;
  double x[3][NP], v[3][NP], m[NP], vsig[9 * NP];
} pset;

static double rnd(unsigned long long *s) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(*s >> 11) / 9007199254740992.0;
}

/* ---- particles ------------------------------------------------------------------------- */

/* A coordinate along a periodic axis: uniform, near a face, or up to 0.9 cells beyond. */
static double periodic_coord(unsigned long long *s, double lo, double hi, double dx) {
  const double u = rnd(s), r = rnd(s);
  if (u < 0.1) return lo - 0.9 * dx * r;
  if (u < 0.2) return hi + 0.9 * dx * r;
  if (u < 0.3) return r < 0.5 ? lo + 2 * r * dx : hi - 2 * (r - 0.5) * dx;
  return lo + (hi - lo) * r;
}

static void make_particles(pset *p, const mpm_grid *g, unsigned long long seed) {
  unsigned long long s = seed;
  p->dim = g->dim;
  for (int i = 0; i < NP; ++i) {
    for (int d = 0; d < g->dim; ++d) {
      p->x[d][i] = g->periodic[d] ? periodic_coord(&s, g->lo[d], g->hi[d], g->dx)
                                  : g->lo[d] + (g->hi[d] - g->lo[d]) * rnd(&s);
      p->v[d][i] = 2 * rnd(&s) - 1;
    }
    p->m[i] = 0.5 + rnd(&s);
    for (int c = 0; c < g->dim * g->dim; ++c) p->vsig[c * NP + i] = rnd(&s) - 0.5;
  }
}

/* The rank holding particle i: the owner of the nearest cell inside the domain. */
static int home_rank(const mpm_grid *g, const pset *p, int i) {
  double x[3] = {0, 0, 0};
  for (int d = 0; d < g->dim; ++d)
    x[d] = fmin(fmax(p->x[d][i], g->lo[d]), nextafter(g->hi[d], g->lo[d]));
  return mpm_grid_owner_of(g, x);
}

/* Translate by a whole period plus shift[d] cells along every periodic axis, then wrap
 * into [lo, hi) (independently of mpm_grid_wrap). */
static void translate(pset *p, const mpm_grid *g, const int *shift) {
  for (int d = 0; d < g->dim; ++d) {
    if (!g->periodic[d]) continue;
    const double len = g->hi[d] - g->lo[d];
    for (int i = 0; i < NP; ++i) {
      const double y = fmod(p->x[d][i] - g->lo[d] + shift[d] * g->dx + len, len) + g->lo[d];
      p->x[d][i] = y < g->hi[d] ? y : g->lo[d];
    }
  }
}

/* P2G of the particles of `all` held by `rank` (all of them if rank < 0) into phase ph, then
 * the reverse halo. */
static void p2g(mpm_grid *g, int ph, const pset *all, int rank) {
  static double x[3][NP], v[3][NP], m[NP], vsig[9 * NP];
  const int dim = all->dim;
  int n = 0, keep[NP];
  for (int i = 0; i < NP; ++i)
    if (rank < 0 || home_rank(g, all, i) == rank) keep[n++] = i;
  for (int k = 0; k < n; ++k) {
    const int i = keep[k];
    for (int d = 0; d < dim; ++d) x[d][k] = all->x[d][i], v[d][k] = all->v[d][i];
    m[k] = all->m[i];
    for (int c = 0; c < dim * dim; ++c) vsig[c * n + k] = all->vsig[c * NP + i];
  }
  mpm_p2g_args a = {.n = n, .m = m, .vsig = vsig, .lp = 0.25};
  for (int d = 0; d < dim; ++d) a.x[d] = x[d], a.v[d] = v[d], a.gravity[d] = 0.5 * (d + 1);
  mpm_grid_phase_zero(g, ph);
  mpm_kernels_get(dim)->p2g(g, ph, &a);
  mpm_grid_phase *f = &g->phase[ph];
  double *fields[1 + 2 * 3];
  int nf = 0;
  fields[nf++] = f->m_i;
  for (int d = 0; d < dim; ++d) fields[nf++] = f->mv_i[d], fields[nf++] = f->f_i[d];
  CHECK(mpm_grid_halo_reverse(g, fields, nf) == 0, "halo_reverse");
}

/* ---- the folded reference -------------------------------------------------------------- */

/* Distinct lattice nodes: ncells along a periodic axis, ncells + 1 + 2 pad otherwise. */
static int lattice_n(const mpm_grid *g, int d) {
  return g->periodic[d] ? g->ncells[d] : g->ncells[d] + 1 + 2 * g->pad;
}

/* Index of global node gi (any image) among the distinct nodes; -1 beyond the pad. */
static long lattice_index(const mpm_grid *g, const int *gi) {
  long idx = 0;
  for (int d = g->dim - 1; d >= 0; --d) {
    const int n = lattice_n(g, d);
    int j = g->periodic[d] ? ((gi[d] % n) + n) % n : gi[d] + g->pad;
    if (j < 0 || j >= n) return -1;
    idx = idx * n + j;
  }
  return idx;
}

static long lattice_size(const mpm_grid *g) {
  long n = 1;
  for (int d = 0; d < g->dim; ++d) n *= lattice_n(g, d);
  return n;
}

static void global_of(const mpm_grid *g, mpm_lidx l, int *gi) {
  gi[0] = gi[1] = gi[2] = 0;
  for (int d = 0; d < g->dim; ++d) gi[d] = g->box_lo[d] + (int)(l % g->box_n[d]), l /= g->box_n[d];
}

/* Field k of phase 0: 0 = m, 1..dim = mv, dim+1..2 dim = f. */
static double *field(const mpm_grid *g, int ph, int k) {
  const int dim = g->dim;
  return k == 0     ? g->phase[ph].m_i
         : k <= dim ? g->phase[ph].mv_i[k - 1]
                    : g->phase[ph].f_i[k - 1 - dim];
}

/* Serial P2G of every particle on an unbounded (K cells wider) non-periodic grid, folded
 * onto the distinct nodes of g: nf arrays of lattice_size(g) values. */
static double *folded_reference(const mpm_grid *g, const pset *all) {
  double lo[3], hi[3];
  const int nf = 1 + 2 * g->dim;
  for (int d = 0; d < g->dim; ++d) {
    const double ext = g->periodic[d] ? K * g->dx : 0.0;
    lo[d] = g->lo[d] - ext, hi[d] = g->hi[d] + ext;
  }
  mpm_grid *ref = NULL;
  int ip;
  const long n = lattice_size(g);
  double *out = calloc((size_t)(n * nf), sizeof *out);
  if (mpm_grid_new(&ref, MPI_COMM_SELF, g->dim, lo, hi, g->dx, g->shape, NULL) != 0 ||
      mpm_grid_add_phase(ref, "p", &ip) != 0) {
    CHECK(0, "reference grid");
    return out;
  }
  p2g(ref, 0, all, -1);
  for (mpm_lidx l = 0; l < ref->nnodes; ++l) {
    int gi[3];
    global_of(ref, l, gi);
    for (int d = 0; d < g->dim; ++d) gi[d] -= g->periodic[d] ? K : 0;
    const long q = lattice_index(g, gi);
    if (q < 0) continue; /* the reference's own outer ghosts: never deposited on */
    for (int k = 0; k < nf; ++k) out[k * n + q] += field(ref, 0, k)[l];
  }
  mpm_grid_destroy(&ref);
  return out;
}

/* Largest difference of field values on the nodes g stores (owned only, or every stored
 * node with a lattice image), relative to each field's largest reference value; the
 * reference is read at the node shifted back by shift[d] cells. */
static double compare(const mpm_grid *g, int ph, const double *ref, int owned_only,
                      const int *shift) {
  const int nf = 1 + 2 * g->dim;
  const long n = lattice_size(g);
  double worst = 0;
  for (int k = 0; k < nf; ++k) {
    double scale = 0, err = 0;
    for (long q = 0; q < n; ++q) scale = fmax(scale, fabs(ref[k * n + q]));
    for (mpm_lidx l = 0; l < g->nnodes; ++l) {
      if (owned_only && !mpm_grid_node_is_owned(g, l)) continue;
      int gi[3];
      global_of(g, l, gi);
      for (int d = 0; d < g->dim; ++d) gi[d] -= shift[d];
      const long q = lattice_index(g, gi);
      if (q >= 0) err = fmax(err, fabs(field(g, ph, k)[l] - ref[k * n + q]));
    }
    worst = fmax(worst, err / scale);
  }
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return worst;
}

/* ---- checks ---------------------------------------------------------------------------- */

static void check_layout(const mpm_grid *g) {
  const long n = lattice_size(g);
  int *owners = calloc((size_t)n, sizeof *owners);
  for (int d = 0; d < g->dim; ++d) {
    if (!g->periodic[d]) continue;
    const int c = g->coord[d], np = g->nproc[d];
    CHECK(g->own_lo[d] == g->cell_split[d][c] && g->own_hi[d] == g->cell_split[d][c + 1],
          "periodic axis %d: owned [%d, %d)", d, g->own_lo[d], g->own_hi[d]);
    int coords[3], want[2];
    for (int s = 0; s < 2; ++s) {
      memcpy(coords, g->coord, sizeof coords);
      coords[d] = (c + (s ? 1 : np - 1)) % np;
      MPI_Cart_rank(g->comm, coords, &want[s]);
      CHECK(g->nbr[d][s] == want[s], "periodic axis %d: neighbour %d is %d, want %d", d, s,
            g->nbr[d][s], want[s]);
    }
  }
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!mpm_grid_node_is_owned(g, l)) continue;
    int gi[3];
    global_of(g, l, gi);
    const long q = lattice_index(g, gi);
    CHECK(q >= 0, "owned node (%d, %d, %d) outside the lattice", gi[0], gi[1], gi[2]);
    if (q >= 0) owners[q]++;
  }
  MPI_Allreduce(MPI_IN_PLACE, owners, (int)n, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  long bad = 0;
  for (long q = 0; q < n; ++q) bad += owners[q] != 1;
  CHECK(bad == 0, "%ld of %ld distinct nodes do not have exactly one owner", bad, n);
  free(owners);
}

/* Owned nodal mass and momentum against the particle totals, relative to the mass. */
static double conservation(const mpm_grid *g, int ph, const pset *all) {
  double t[4] = {0}, pt[4] = {0};
  for (mpm_lidx l = 0; l < g->nnodes; ++l) {
    if (!mpm_grid_node_is_owned(g, l)) continue;
    t[0] += g->phase[ph].m_i[l];
    for (int d = 0; d < g->dim; ++d) t[1 + d] += g->phase[ph].mv_i[d][l];
  }
  MPI_Allreduce(MPI_IN_PLACE, t, 4, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  for (int i = 0; i < NP; ++i) {
    pt[0] += all->m[i];
    for (int d = 0; d < g->dim; ++d) pt[1 + d] += all->m[i] * all->v[d][i];
  }
  double err = 0;
  for (int k = 0; k <= g->dim; ++k) err = fmax(err, fabs(t[k] - pt[k]) / pt[0]);
  return err;
}

static void forward(mpm_grid *g, int ph) {
  double *f[1 + 2 * 3];
  const int nf = 1 + 2 * g->dim;
  for (int k = 0; k < nf; ++k) f[k] = field(g, ph, k);
  CHECK(mpm_grid_halo_forward(g, f, nf) == 0, "halo_forward");
}

static mpm_grid *make_grid(const config *c, mpm_shape_kind shape) {
  const double lo[3] = {-1.0, 0.5, 0.25}, dx = 0.125;
  const int n2[3] = {16, 12, 1}, n3[3] = {12, 10, 8};
  double hi[3];
  for (int d = 0; d < 3; ++d) {
    int n = c->dim == 2 ? n2[d] : n3[d];
    if (c->strip && d == 1) n = mpm_shape_ghost_width(shape);
    hi[d] = lo[d] + n * dx;
  }
  mpm_grid *g = NULL;
  int ip;
  CHECK(mpm_grid_new_periodic(&g, MPI_COMM_WORLD, c->dim, lo, hi, dx, shape, c->nproc,
                              c->periodic) == 0,
        "grid_new_periodic");
  if (g) {
    CHECK(mpm_grid_add_phase(g, "a", &ip) == 0 && mpm_grid_add_phase(g, "b", &ip) == 0, "phases");
    for (int d = 0; d < 3; ++d)
      CHECK(g->periodic[d] == (d < c->dim && c->periodic[d]), "periodic[%d]", d);
  }
  return g;
}

static void run_case(int ic, mpm_shape_kind shape) {
  const config *c = &g_configs[ic];
  static pset all;
  mpm_grid *g = make_grid(c, shape);
  if (!g) return;
  check_layout(g);
  make_particles(&all, g, 1000 * (unsigned long long)ic + (unsigned long long)shape);
  double *ref = folded_reference(g, &all);
  const int none[3] = {0, 0, 0}, cells[3] = {5, 2, 3};
  int shift[3] = {0, 0, 0}; /* cells moved along each periodic axis */
  for (int d = 0; d < g->dim; ++d) shift[d] = g->periodic[d] ? cells[d] % g->ncells[d] : 0;

  p2g(g, 0, &all, g->rank);
  const double owned = compare(g, 0, ref, 1, none), cons = conservation(g, 0, &all);
  forward(g, 0);
  const double images = compare(g, 0, ref, 0, none);
  translate(&all, g, shift);
  p2g(g, 1, &all, g->rank);
  const double moved = compare(g, 1, ref, 1, shift), cons2 = conservation(g, 1, &all);

  char what[96];
  snprintf(what, sizeof what, "%d-D %s periodic %d%d%d split %dx%dx%d%s", c->dim,
           mpm_shape_name(shape), c->periodic[0], c->periodic[1], c->dim == 3 && c->periodic[2],
           g->nproc[0], g->nproc[1], g->nproc[2], c->strip ? " strip" : "");
  CHECK(owned <= 1e-13, "%s: owned nodes differ from the unbounded lattice by %.3e", what, owned);
  CHECK(images <= 1e-13, "%s: after the forward halo, stored nodes differ by %.3e", what, images);
  CHECK(fmax(cons, cons2) <= 1e-13, "%s: mass/momentum not conserved: %.3e, %.3e", what, cons,
        cons2);
  CHECK(moved <= 1e-12, "%s: translated set differs from the shifted fields by %.3e", what, moved);
  if (g_rank == 0)
    printf("%-44s owned %.1e  images %.1e  translated %.1e  conservation %.1e\n", what, owned,
           images, moved, fmax(cons, cons2));
  free(ref);
  mpm_grid_destroy(&g);
}

/* Periodic x, slip y: the rules are exactly those of the y walls alone. */
static void check_walls(void) {
  const config c = {2, {1, 0, 0}, {0, 0, 0}, 0};
  mpm_grid *g = make_grid(&c, MPM_SHAPE_QUADRATIC);
  if (!g) return;
  mpm_walls w = {0}, y_only = {0};
  w.face[0][0] = w.face[0][1] = MPM_WALL_PERIODIC;
  w.face[1][0] = w.face[1][1] = y_only.face[1][0] = y_only.face[1][1] = MPM_WALL_SLIP;
  int periodic[3];
  mpm_walls_periodic(&w, periodic);
  CHECK(periodic[0] == 1 && periodic[1] == 0 && periodic[2] == 0, "mpm_walls_periodic");
  mpm_node_constraints a = {0}, b = {0};
  CHECK(mpm_constraints_add_walls(&a, &w, g) == 0 && mpm_constraints_add_walls(&b, &y_only, g) == 0,
        "add_walls");
  /* A rank away from the y walls (the layout may split y) holds no rules: count them all. */
  long total = (long)a.count;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  CHECK(a.count == b.count && total > 0, "periodic faces add rules: %d vs %d (%ld in all)",
        (int)a.count, (int)b.count, total);
  for (mpm_lidx k = 0; k < a.count && k < b.count; ++k)
    CHECK(a.node[k] == b.node[k] && a.source[k] == b.source[k], "rule %d", (int)k);
  mpm_constraints_free(&a), mpm_constraints_free(&b);
  mpm_grid_destroy(&g);
}

/* A periodic axis needs `ghost` cells even on one rank. */
static void check_input_errors(void) {
  const double lo[3] = {0, 0, 0}, hi[3] = {2.0, 0.2, 0};
  const int periodic[3] = {0, 1, 0}, nproc[3] = {0, 1, 0};
  mpm_grid *g = NULL;
  if (g_rank == 0) fprintf(stderr, "expected input errors follow:\n");
  CHECK(mpm_grid_new_periodic(&g, MPI_COMM_WORLD, 2, lo, hi, 0.1, MPM_SHAPE_QUADRATIC, nproc,
                              periodic) == MPM_ERR_INPUT &&
            !g,
        "2 periodic cells with 3 ghost layers");
  CHECK(mpm_grid_new_periodic(&g, MPI_COMM_WORLD, 2, lo, hi, 0.1, MPM_SHAPE_LINEAR, nproc,
                              periodic) == 0,
        "2 periodic cells with 2 ghost layers");
  mpm_grid_destroy(&g);
}

int main(int argc, char **argv) {
  mpm_test_init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  for (int ic = 0; ic < (int)(sizeof g_configs / sizeof g_configs[0]); ++ic)
    for (int s = 0; s < MPM_SHAPE_COUNT; ++s) run_case(ic, (mpm_shape_kind)s);
  check_walls();
  check_input_errors();
  mpm_test_finish("test_periodic_p2g");
  MPI_Finalize();
  return g_fail != 0;
}
