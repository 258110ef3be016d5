/* Checks for the MPI test drivers (which cannot use cmocka's single-process runner): every
 * rank counts its own failed checks, printing the first 20; mpm_test_finish() adds them up
 * over the ranks and prints one closing line on rank 0. */
#ifndef MPM_TESTING_H
#define MPM_TESTING_H

#include <mpi.h>
#include <stdio.h>

static int g_rank, g_size, g_fail;

#define CHECK(cond, ...)                                                                           \
  do {                                                                                             \
    if (!(cond) && g_fail++ < 20) {                                                                \
      fprintf(stderr, "[%d] %s:%d: check failed: %s: ", g_rank, __FILE__, __LINE__, #cond);        \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fputc('\n', stderr);                                                                         \
    }                                                                                              \
  } while (0)

static inline void mpm_test_init(int *argc, char ***argv) {
  MPI_Init(argc, argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
}

/* Total failures over the ranks (0 = passed); prints "<name> on N ranks: ...". */
static inline int mpm_test_finish(const char *name) {
  MPI_Allreduce(MPI_IN_PLACE, &g_fail, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (g_rank == 0)
    printf("%s on %d ranks: %s (%d failed checks)\n", name, g_size, g_fail ? "FAILED" : "passed",
           g_fail);
  return g_fail;
}

#endif
