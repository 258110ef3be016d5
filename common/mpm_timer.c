/* Phase timers: accumulated MPI_Wtime() intervals in a process-wide table. */
#include "mpm_timer.h"

#include "mpm_error.h"
#include "mpm_safefile.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static struct { double total[MPM_T_COUNT], started[MPM_T_COUNT]; } g_timer;

static const char *const g_names[MPM_T_COUNT] = {
#define MPM_X_NAME(id, name) name,
    MPM_TIMER_LIST(MPM_X_NAME)
#undef MPM_X_NAME
};

void mpm_timer_reset(void) {
  memset(&g_timer, 0, sizeof g_timer);
}
void mpm_timer_start(mpm_timer_phase phase) {
  g_timer.started[phase] = MPI_Wtime();
}
void mpm_timer_stop(mpm_timer_phase phase) {
  g_timer.total[phase] += MPI_Wtime() - g_timer.started[phase];
}
double mpm_timer_seconds(mpm_timer_phase phase) {
  return g_timer.total[phase];
}
const char *mpm_timer_name(mpm_timer_phase phase) {
  return g_names[phase];
}

int mpm_timer_reduce(MPI_Comm comm, double *max, double *mean) {
  int size;
  MPM_CALL_MPI(MPI_Comm_size(comm, &size));
  MPM_CALL_MPI(MPI_Allreduce(g_timer.total, max, MPM_T_COUNT, MPI_DOUBLE, MPI_MAX, comm));
  MPM_CALL_MPI(MPI_Allreduce(g_timer.total, mean, MPM_T_COUNT, MPI_DOUBLE, MPI_SUM, comm));
  for (int k = 0; k < MPM_T_COUNT; ++k) mean[k] /= size;
  return 0;
}

static int report(const double *max, const double *mean, const char *path);

int mpm_timer_report(MPI_Comm comm, const char *path) {
  double max[MPM_T_COUNT], mean[MPM_T_COUNT];
  int rank;
  MPM_CALL(mpm_timer_reduce(comm, max, mean));
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  int status = rank == 0 ? report(max, mean, path) : 0;
  /* Rank 0 wrote the file: every rank learns whether it could (MPM_ERR_OUTPUT, explained). */
  MPM_CALL_MPI(MPI_Bcast(&status, 1, MPI_INT, 0, comm));
  MPM_CALL(status ? MPM_ERR_OUTPUT : 0);
  return 0;
}

/* Rank 0: the table in the log and, if path is not NULL, in path. */
static int report(const double *max, const double *mean, const char *path) {
  const double total = max[MPM_T_TOTAL] > 0 ? max[MPM_T_TOTAL] : 1.0;
  mpm_log(MPM_LOG_INFO, "%-11s %12s %12s %8s", "phase", "max [s]", "mean [s]", "share");
  double parts = 0.0;
  for (int k = 0; k < MPM_T_COUNT; ++k) {
    mpm_log(MPM_LOG_INFO, "%-11s %12.4f %12.4f %7.1f%%", g_names[k], max[k], mean[k],
            100.0 * max[k] / total);
    if (k != MPM_T_TOTAL && k != MPM_T_RESTRICT && k != MPM_T_PROLONG && k != MPM_T_RELEVEL)
      parts += mean[k];
  }
  /* Integrator vector operations, set-up and whatever else no phase covers. */
  mpm_log(MPM_LOG_INFO, "%-11s %12s %12.4f %7.1f%%", "(other)", "", mean[MPM_T_TOTAL] - parts,
          100.0 * (mean[MPM_T_TOTAL] - parts) / total);
  if (!path) return 0;
  FILE *f = mpm_file_begin(path, "w");
  if (!f) return mpm_file_fail(path, errno, "timers");
  fprintf(f, "phase,max_s,mean_s,fraction\n");
  for (int k = 0; k < MPM_T_COUNT; ++k)
    fprintf(f, "%s,%.6e,%.6e,%.4f\n", g_names[k], max[k], mean[k], max[k] / total);
  const int e = mpm_file_commit(f, path);
  if (e) return mpm_file_fail(path, e, "timers");
  return 0;
}
