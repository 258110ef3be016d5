/* Wall-clock timers per phase of a step. One process-wide table: phases may nest (the
 * stress update runs inside P2G's caller, say), but a phase is never started twice.
 *
 * restrict and prolong (the refinement hierarchy's transfers between levels, mpm_hier.h) are
 * details: they are timed wherever they run, also inside another phase (the grid pressure's run
 * inside grid), so the report leaves them out of the sum it subtracts from total for (other);
 * likewise relevel (a refined gas's splits and merges, inside post_step). regrid (a dynamic
 * refinement's rebuild of the hierarchy) runs between steps on its own. */
#ifndef MPM_TIMER_H
#define MPM_TIMER_H

#include <mpi.h>

#define MPM_TIMER_LIST(X)                                                                          \
  X(MPM_T_P2G, "p2g")                                                                              \
  X(MPM_T_GRID, "grid")                                                                            \
  X(MPM_T_G2P, "g2p")                                                                              \
  X(MPM_T_HALO, "halo")                                                                            \
  X(MPM_T_STRESS, "stress")                                                                        \
  X(MPM_T_COUPLING, "coupling")                                                                    \
  X(MPM_T_CHECK, "check")                                                                          \
  X(MPM_T_STABLE, "stable")                                                                        \
  X(MPM_T_DIAG, "diagnostics")                                                                     \
  X(MPM_T_BOUNDARY, "boundary")                                                                    \
  X(MPM_T_MIGRATE, "migrate")                                                                      \
  X(MPM_T_POST, "post_step")                                                                       \
  X(MPM_T_RESTRICT, "restrict")                                                                    \
  X(MPM_T_PROLONG, "prolong")                                                                      \
  X(MPM_T_RELEVEL, "relevel")                                                                      \
  X(MPM_T_REGRID, "regrid")                                                                        \
  X(MPM_T_IO, "io")                                                                                \
  X(MPM_T_TOTAL, "total")

typedef enum {
#define MPM_X_ENUM(id, name) id,
  MPM_TIMER_LIST(MPM_X_ENUM)
#undef MPM_X_ENUM
      MPM_T_COUNT
} mpm_timer_phase;

void mpm_timer_reset(void);
void mpm_timer_start(mpm_timer_phase phase);
void mpm_timer_stop(mpm_timer_phase phase);
double mpm_timer_seconds(mpm_timer_phase phase);
const char *mpm_timer_name(mpm_timer_phase phase);

/* Max and mean over the ranks of comm, for every phase (collective). */
int mpm_timer_reduce(MPI_Comm comm, double *max, double *mean);

/* Print the table on rank 0 and, if path is not NULL, write it there as CSV
 * (phase,max_s,mean_s,fraction). Collective. */
int mpm_timer_report(MPI_Comm comm, const char *path);

#endif
