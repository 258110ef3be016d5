/* mpmfsi: the command-line entry point.
 *
 *   mpmfsi run CASE [key=value ...]       run a case
 *   mpmfsi check CASE [key=value ...]     validate a case and print the resolved configuration
 *   mpmfsi restart CHECKPOINT [key=value ...]   continue a run from a checkpoint
 *
 * Exit codes: 0 success, 1 a failure during the run, 2 bad input (nothing was run). Input
 * errors and unphysical states are found identically on every rank, so they end the run
 * cleanly; any other failure aborts all ranks so that none is left waiting in a collective
 * call. */
#include "mpm_config.h"
#include "mpm_error.h"
#include "mpm_output.h"
#include "mpm_sim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(void) {
  mpm_log(MPM_LOG_INFO,
          "usage:\n"
          "  mpmfsi run CASE [key=value ...]          run a case file\n"
          "  mpmfsi check CASE [key=value ...]        validate it and print the resolved "
          "configuration\n"
          "  mpmfsi restart CHECKPOINT [key=value ...] continue a run (e.g. time.t_end=2)\n"
          "Every case-file key can be overridden on the command line as section.key=value.");
}

static int apply_overrides(mpm_config *cfg, int argc, char **argv) {
  int rc = 0;
  for (int k = 0; k < argc; ++k)
    if (mpm_config_override(cfg, argv[k]) != 0) rc = MPM_ERR_INPUT;
  return rc;
}

static int set_logging(const mpm_config *cfg) {
  const char *level;
  int all;
  MPM_CALL(mpm_config_get_string(cfg, "run.log_level", &level));
  MPM_CALL(mpm_config_get_bool(cfg, "run.log_all_ranks", &all));
  mpm_log_init(MPI_COMM_WORLD, (mpm_log_level)mpm_log_level_parse(level), all);
  return 0;
}

/* Read the case (or the checkpoint's stored case), apply overrides, validate. */
static int load_config(mpm_config *cfg, const char *cmd, const char *path, int argc, char **argv) {
  MPM_CALL(mpm_sim_add_schema(cfg));
  if (strcmp(cmd, "restart") == 0) {
    mpm_checkpoint *ck = NULL;
    MPM_CALL(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path));
    int rc = mpm_config_read_string(cfg, mpm_checkpoint_config(ck), path, ".");
    mpm_checkpoint_close(&ck);
    MPM_CALL(rc);
  } else {
    MPM_CALL(mpm_config_read_file(cfg, path));
  }
  MPM_CALL(apply_overrides(cfg, argc, argv));
  MPM_CALL(mpm_config_validate(cfg));
  return set_logging(cfg);
}

static int print_resolved(const mpm_config *cfg) {
  char *text = NULL;
  int rank;
  MPM_CALL(mpm_config_resolved_text(cfg, &text));
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) fputs(text, stdout);
  free(text);
  return 0;
}

static int run(const char *cmd, const char *path, int argc, char **argv) {
  mpm_config *cfg = NULL;
  mpm_sim *sim = NULL;
  int rc = mpm_config_new(&cfg, MPI_COMM_WORLD);
  /* Whatever stops the case from loading (a missing file too) is bad input: exit 2. */
  if (!rc && load_config(cfg, cmd, path, argc, argv) != 0) rc = MPM_ERR_INPUT;
  if (!rc)
    rc = strcmp(cmd, "restart") == 0 ? mpm_sim_restart(&sim, cfg, path) : mpm_sim_create(&sim, cfg);
  /* check builds everything a run needs (so every input error shows), then stops. */
  if (!rc && strcmp(cmd, "check") == 0)
    rc = print_resolved(cfg);
  else if (!rc)
    rc = mpm_sim_run(sim);
  mpm_sim_destroy(&sim);
  mpm_config_destroy(&cfg);
  return rc;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  int rc;
  const int known = argc >= 3 && (strcmp(argv[1], "run") == 0 || strcmp(argv[1], "check") == 0 ||
                                  strcmp(argv[1], "restart") == 0);
  if (!known) {
    usage();
    rc = argc >= 2 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0 ||
                       strcmp(argv[1], "help") == 0)
             ? 0
             : MPM_ERR_INPUT;
  } else {
    rc = run(argv[1], argv[2], argc - 3, argv + 3);
  }
  /* Input errors and unphysical states are detected on every rank alike: end cleanly. */
  if (rc != 0 && rc != MPM_ERR_INPUT && rc != MPM_ERR_UNPHYSICAL) {
    mpm_log_all(MPM_LOG_DEBUG, "mpmfsi failed: %s", mpm_error_string(rc));
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return rc == 0 ? 0 : rc == MPM_ERR_INPUT ? 2 : 1;
}
