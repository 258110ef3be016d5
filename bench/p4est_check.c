/* Cross-check of bench/bench_partition.py's block maps against p4est (libp4est-dev 2.2), 2-D,
 * one rank: a brick of level-0 blocks (one tree each), refined wherever the map has a finer
 * block beneath (p4est refines whole families), then p4est_balance over faces and corners.
 * Prints the leaf counts before and after the balance and every leaf in p4est's order as
 * "level ix iy" (block indices on that level), which the driver compares with its own Morton
 * order and cuts with p4est_partition's weighted rule.
 *
 * With any argument it skips the balance (to list the leaves the balance adds).
 * Input (stdin): "nbx nby L", then per level l = 1 .. L-1 a count and that many "ix iy".
 * Built by the driver with mpicc only when asked (--p4est); not part of the CMake build, so
 * mpmfsi does not depend on p4est. */
#include <p4est_bits.h>
#include <p4est_extended.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct block_map {
  int nbx, nby, levels;
  unsigned char *present[P4EST_QMAXLEVEL]; /* per level, nbx 2^l x nby 2^l */
} block_map;

static block_map g_map;

static int has(int l, long ix, long iy) {
  const long nx = (long)g_map.nbx << l, ny = (long)g_map.nby << l;
  return l < g_map.levels && ix < nx && iy < ny && g_map.present[l][iy * nx + ix];
}

/* Block index of a quadrant on its level. */
static void index_of(p4est_t *p4est, p4est_topidx_t t, const p4est_quadrant_t *q, long *ix,
                     long *iy) {
  const p4est_connectivity_t *c = p4est->connectivity;
  const double *v = c->vertices + 3 * c->tree_to_vertex[P4EST_CHILDREN * t];
  const p4est_qcoord_t len = P4EST_QUADRANT_LEN(q->level);
  *ix = ((long)v[0] << q->level) + q->x / len;
  *iy = ((long)v[1] << q->level) + q->y / len;
}

static int refine_fn(p4est_t *p4est, p4est_topidx_t t, p4est_quadrant_t *q) {
  long ix, iy;
  index_of(p4est, t, q, &ix, &iy);
  for (int k = 0; k < 4; ++k)
    if (has(q->level + 1, 2 * ix + (k & 1), 2 * iy + (k >> 1))) return 1;
  return 0;
}

static int read_map(void) {
  if (scanf("%d %d %d", &g_map.nbx, &g_map.nby, &g_map.levels) != 3) return 1;
  for (int l = 0; l < g_map.levels; ++l) {
    const long n = ((long)g_map.nbx << l) * ((long)g_map.nby << l);
    g_map.present[l] = calloc((size_t)n, 1);
    if (!g_map.present[l]) return 1;
    if (l == 0) {
      for (long i = 0; i < n; ++i) g_map.present[0][i] = 1;
      continue;
    }
    long count, ix, iy;
    if (scanf("%ld", &count) != 1) return 1;
    for (long i = 0; i < count; ++i) {
      if (scanf("%ld %ld", &ix, &iy) != 2) return 1;
      g_map.present[l][iy * ((long)g_map.nbx << l) + ix] = 1;
    }
  }
  return 0;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  sc_init(MPI_COMM_WORLD, 0, 0, NULL, SC_LP_ERROR);
  p4est_init(NULL, SC_LP_ERROR);
  if (read_map()) {
    fprintf(stderr, "p4est_check: bad block map on stdin\n");
    return 2;
  }
  p4est_connectivity_t *conn = p4est_connectivity_new_brick(g_map.nbx, g_map.nby, 0, 0);
  p4est_t *p4est = p4est_new_ext(MPI_COMM_WORLD, conn, 0, 0, 1, 0, NULL, NULL);
  p4est_refine(p4est, 1, refine_fn, NULL);
  const long before = (long)p4est->global_num_quadrants;
  if (argc < 2) p4est_balance(p4est, P4EST_CONNECT_FULL, NULL); /* any argument: no balance */
  printf("leaves %ld balanced %ld\n", before, (long)p4est->global_num_quadrants);
  for (p4est_topidx_t t = p4est->first_local_tree; t <= p4est->last_local_tree; ++t) {
    sc_array_t *qs = &p4est_tree_array_index(p4est->trees, t)->quadrants;
    for (size_t i = 0; i < qs->elem_count; ++i) {
      const p4est_quadrant_t *q = p4est_quadrant_array_index(qs, i);
      long ix, iy;
      index_of(p4est, t, q, &ix, &iy);
      printf("%d %ld %ld\n", q->level, ix, iy);
    }
  }
  p4est_destroy(p4est);
  p4est_connectivity_destroy(conn);
  for (int l = 0; l < g_map.levels; ++l) free(g_map.present[l]);
  sc_finalize();
  MPI_Finalize();
  return 0;
}
