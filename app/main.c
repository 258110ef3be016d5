/* mpmfsi: the command-line entry point.
 *
 *   mpmfsi run CASE [key=value ...]       run a case
 *   mpmfsi check CASE [key=value ...]     validate a case and print the resolved configuration
 *   mpmfsi restart CHECKPOINT [key=value ...]   continue a run from a checkpoint
 *   mpmfsi keys [SECTION] [--markdown]    list every case-file key
 *   mpmfsi version | --version            the version, git revision and library versions
 *   mpmfsi help [COMMAND] | -h | --help   the usage, or one command's help (also COMMAND -h)
 *
 * Help and version go to stdout with exit 0, on rank 0 only, and need neither a case file
 * nor MPI (without_mpi). No command at all is a usage error, as for git: the usage on stderr,
 * exit 2 (a script that passes an empty command must not look successful). The texts are in
 * cli_help.c, the key listing in cli_keys.c.
 *
 * Exit codes: 0 success, 1 a failure during the run, 2 bad input (nothing was run), 3 stopped
 * by SIGTERM, SIGINT or SIGHUP (a final checkpoint was written; restart from it to go on). Input
 * errors and unphysical states are found identically on every rank, and every rank agrees on
 * a failed write of an output file (MPM_ERR_OUTPUT), so they end the run cleanly; any other
 * failure aborts all ranks so that none is left waiting in a collective call. */
#include "cli.h"
#include "mpm_config.h"
#include "mpm_error.h"
#include "mpm_h5.h"
#include "mpm_output.h"
#include "mpm_path.h"
#include "mpm_rundir.h"
#include "mpm_sim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

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

/* The keys a restart honours: how and how long to integrate, what to write, how to log,
 * and the rank layout. Everything else describes the state the checkpoint already holds. */
static int restartable(const char *key) {
  static const char *const prefix[] = {"time.", "output.", "run."};
  for (size_t k = 0; k < sizeof prefix / sizeof prefix[0]; ++k)
    if (strncmp(key, prefix[k], strlen(prefix[k])) == 0) return 1;
  return strcmp(key, "grid.ranks") == 0;
}

/* The resolved text's assignments, defaults included, as "section.key = value" lines
 * (comments dropped), in order: what two configurations are compared by. */
static char *assignments(const mpm_config *cfg) {
  char *text = NULL;
  if (mpm_config_resolved_text(cfg, &text) != 0) return NULL;
  const size_t cap = 2 * strlen(text) + 4096;
  char *out = malloc(cap), section[256] = "";
  size_t len = 0;
  for (char *line = strtok(text, "\n"); out && line; line = strtok(NULL, "\n")) {
    if (line[0] == '[') {
      snprintf(section, sizeof section, "%.*s", (int)strcspn(line + 1, "]"), line + 1);
      continue;
    }
    /* A default is written commented out ("# key = value   # default"): compared as set. */
    if (strncmp(line, "# ", 2) == 0 &&
        line[2 + strspn(line + 2, "abcdefghijklmnopqrstuvwxyz_0123456789")] == ' ')
      line += 2;
    if (line[0] == '#' || !strchr(line, '=')) continue;
    char *comment = strstr(line, "   #");
    if (comment) *comment = 0;
    const int w = snprintf(out + len, cap - len, "%s.%s\n", section, line);
    len = w < 0 ? len : len + (size_t)w < cap ? len + (size_t)w : cap - 1; /* never past cap */
  }
  free(text);
  return out;
}

/* The key of one "section.key = value" line, NUL-terminated in buf. */
static const char *line_key(const char *line, char *buf, size_t n) {
  snprintf(buf, n, "%.*s", (int)strcspn(line, " ="), line);
  return buf;
}

/* Refuse what a restart would silently ignore: every key outside restartable() whose value
 * differs from the checkpoint's (a new section counts as a change). */
static int check_restart_changes(const mpm_config *cfg, const char *before, const char *path) {
  char *after = assignments(cfg);
  int bad = 0;
  if (!after) return MPM_ERR_MEMORY;
  for (char *line = after; *line; line += strcspn(line, "\n") + 1) {
    const size_t n = strcspn(line, "\n");
    char key[512];
    line_key(line, key, sizeof key);
    if (restartable(key)) continue;
    int same = 0;
    for (const char *b = before; *b && !same; b += strcspn(b, "\n") + 1)
      same = strcspn(b, "\n") == n && strncmp(b, line, n) == 0;
    if (same) continue;
    mpm_log(MPM_LOG_ERROR,
            "%s: %s = %.*s cannot change on restart: the checkpoint %s already holds the state "
            "it describes. A restart may change only time.*, output.*, run.* and grid.ranks; "
            "start a new run (mpmfsi run) to change the rest",
            mpm_config_where(cfg, key), key, (int)(n - strlen(key) - 3), line + strlen(key) + 3,
            path);
    bad = 1;
  }
  free(after);
  return bad ? MPM_ERR_INPUT : 0;
}

/* Is key given on the command line (as the parser reads it: "key=value", spaces allowed
 * around the key)? */
static int has_override(int argc, char **argv, const char *key) {
  const size_t n = strlen(key);
  for (int k = 0; k < argc; ++k) {
    const char *a = argv[k] + strspn(argv[k], " \t");
    if (strncmp(a, key, n) == 0 && a[n + strspn(a + n, " \t")] == '=') return 1;
  }
  return 0;
}

/* Where a restart writes when output.dir is not given: the checkpoint's own folder, unless
 * that folder records results later than the checkpoint (an earlier checkpoint of a finished
 * or crashed run) and output.truncate is off; then a new folder beside it, named after the
 * checkpoint, so nothing is mixed or lost. */
static int restart_folder(const mpm_config *cfg, const char *path, double t, char *dir, size_t n) {
  int truncate;
  double latest;
  MPM_CALL(mpm_config_get_bool(cfg, "output.truncate", &truncate));
  char *parent = mpm_path_parent(path);
  if (!parent) return MPM_ERR_MEMORY;
  int rc = truncate ? 0 : mpm_rundir_latest(MPI_COMM_WORLD, parent, path, t, &latest);
  int len;
  if (!rc && !truncate && latest > t * (1 + 1e-12)) {
    const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    const int stem =
        (int)(strlen(name) > 3 && strcmp(name + strlen(name) - 3, ".h5") == 0 ? strlen(name) - 3
                                                                              : strlen(name));
    const int top = strcmp(parent, ".") == 0 || strcmp(parent, "/") == 0;
    len = snprintf(dir, n, "%s%s-from-%.*s", top ? "" : parent, top ? "restart" : "", stem, name);
    mpm_log(MPM_LOG_INFO,
            "restart: %s holds results up to t = %.6g, later than the checkpoint (t = %.6g); "
            "continuing in %s (output.truncate=true would cut %s back instead)",
            parent, latest, t, dir, parent);
  } else {
    len = snprintf(dir, n, "%s", parent);
  }
  free(parent);
  MPM_CALL(rc);
  if (len >= (int)n) MPM_FAIL(MPM_ERR_INPUT, "restart: the path '%s' is too long", path);
  return 0;
}

/* A restart: the checkpoint's stored case, then the overrides, which may change only what a
 * restart honours. output.overwrite and output.truncate act only when given with this
 * restart (never inherited from the stored case). The output folder: restart_folder. */
static int load_restart(mpm_config *cfg, const char *path, int argc, char **argv) {
  mpm_checkpoint *ck = NULL;
  double t = 0;
  MPM_CALL(mpm_checkpoint_open(&ck, MPI_COMM_WORLD, path));
  int rc = mpm_config_read_string(cfg, mpm_checkpoint_config(ck), path, ".");
  if (!rc) rc = mpm_checkpoint_attr(ck, "t", &t);
  mpm_checkpoint_close(&ck);
  MPM_CALL(rc);
  char *before = assignments(cfg);
  MPM_CALL(mpm_h5_agree(MPI_COMM_WORLD, before ? 0 : MPM_ERR_MEMORY));
  char dir[4096];
  rc = apply_overrides(cfg, argc, argv);
  static const char *const intent[] = {"output.overwrite", "output.truncate"};
  for (int k = 0; k < 2 && !rc; ++k)
    if (!has_override(argc, argv, intent[k]))
      rc = mpm_config_set(cfg, intent[k], "false", "restart (not inherited)");
  if (!rc) rc = mpm_config_validate(cfg);
  if (!rc && !has_override(argc, argv, "output.dir")) {
    rc = restart_folder(cfg, path, t, dir, sizeof dir);
    if (!rc) rc = mpm_config_set(cfg, "output.dir", dir, "restart (the checkpoint's folder)");
    if (!rc) rc = mpm_config_validate(cfg);
  }
  if (!rc) rc = check_restart_changes(cfg, before, path);
  free(before);
  return rc;
}

/* Read the case (or the checkpoint's stored case), apply overrides, validate. */
static int load_config(mpm_config *cfg, const char *cmd, const char *path, int argc, char **argv) {
  MPM_CALL(mpm_sim_add_schema(cfg));
  if (strcmp(cmd, "restart") == 0) {
    MPM_CALL(load_restart(cfg, path, argc, argv));
  } else {
    MPM_CALL(mpm_config_read_file(cfg, path));
    MPM_CALL(apply_overrides(cfg, argc, argv));
    MPM_CALL(mpm_config_validate(cfg));
  }
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
  if (!rc && strcmp(cmd, "check") != 0) {
    /* First in run.log: which code made the results that follow. */
    int size;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    mpm_log(MPM_LOG_INFO, "%s: %s %s on %d rank%s", cli_version(), cmd, path, size,
            size > 1 ? "s" : "");
  }
  if (!rc)
    rc = strcmp(cmd, "restart") == 0 ? mpm_sim_restart(&sim, cfg, path) : mpm_sim_create(&sim, cfg);
  /* check builds everything a run needs (so every input error shows), then stops. */
  if (!rc && strcmp(cmd, "check") == 0)
    rc = print_resolved(cfg);
  else if (!rc) {
    mpm_sim_set_version(sim, cli_version());
    rc = mpm_sim_run(sim);
  }
  mpm_sim_destroy(&sim);
  mpm_config_destroy(&cfg);
  return rc;
}

/* This process's rank as its launcher numbers it, read before MPI starts (0 when not
 * started by mpiexec, srun or another PMI launcher), so that help and version print once. */
static int launcher_rank(void) {
  static const char *const var[] = {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK",
                                    "SLURM_PROCID"};
  for (size_t k = 0; k < sizeof var / sizeof var[0]; ++k) {
    const char *v = getenv(var[k]);
    if (v && *v) return atoi(v);
  }
  return 0;
}

/* help [COMMAND] on stdout; an unknown COMMAND is a usage error. */
static int help(const char *command, int print) {
  if (command && !cli_is_command(command)) {
    if (print)
      fprintf(stderr, "mpmfsi help: '%s' is not a command; the commands are " CLI_COMMANDS "\n",
              command);
    return MPM_ERR_INPUT;
  }
  if (print && command) cli_help(stdout, command);
  if (print && !command) cli_usage(stdout);
  return 0;
}

/* run, check or restart without its file: say which file is missing. */
static int missing_file(const char *cmd, int print) {
  const int ck = strcmp(cmd, "restart") == 0;
  if (print)
    fprintf(stderr,
            "mpmfsi %s: no %s given; usage: mpmfsi %s %s [key=value ...] (mpmfsi help %s)\n", cmd,
            ck ? "checkpoint" : "case file", cmd, ck ? "CHECKPOINT" : "CASE", cmd);
  return MPM_ERR_INPUT;
}

/* What needs neither a case nor MPI: the usage, help, version and usage errors. They answer
 * at once, without the second MPI takes to start, and print on rank 0 only when launched on
 * several ranks (each rank decides alike, from the same arguments). Returns 1 with *rc set
 * when the command line is one of them; 0 for keys and for run, check and restart with their
 * file. */
static int without_mpi(int argc, char **argv, int *rc) {
  const int print = launcher_rank() == 0;
  if (argc < 2) { /* a usage error, as for git: the usage on stderr */
    if (print) cli_usage(stderr);
    return *rc = MPM_ERR_INPUT, 1;
  }
  const char *cmd = argv[1];
  if (cli_is_help_flag(cmd)) return *rc = help(argc > 2 ? argv[2] : NULL, print), 1;
  if (strcmp(cmd, "--version") == 0) cmd = "version";
  if (!cli_is_command(cmd)) {
    if (print)
      fprintf(stderr,
              "mpmfsi: '%s' is not a command; the commands are " CLI_COMMANDS " (mpmfsi help)\n",
              cmd);
    return *rc = MPM_ERR_INPUT, 1;
  }
  /* "mpmfsi run --help" asks for help: no case file of that name is looked for. */
  if (argc > 2 && cli_is_help_flag(argv[2])) return *rc = help(cmd, print), 1;
  if (strcmp(cmd, "help") == 0) return *rc = help(argc > 2 ? argv[2] : NULL, print), 1;
  if (strcmp(cmd, "version") == 0) {
    if (print) cli_print_version(stdout); /* MPI allows its version queries before MPI_Init */
    return *rc = 0, 1;
  }
  if (strcmp(cmd, "keys") != 0 && argc < 3) return *rc = missing_file(cmd, print), 1;
  return 0;
}

static int exit_status(int rc) {
  return rc == 0 ? 0 : rc == MPM_ERR_INPUT ? 2 : rc == MPM_ERR_INTERRUPTED ? 3 : 1;
}

int main(int argc, char **argv) {
  int rc;
  if (without_mpi(argc, argv, &rc)) return exit_status(rc);
#if defined(__SANITIZE_ADDRESS__)
  __lsan_disable(); /* Open MPI's start-up keeps, and loses, blocks of its own: not ours */
#endif
  MPI_Init(&argc, &argv);
#if defined(__SANITIZE_ADDRESS__)
  __lsan_enable();
#endif
  mpm_log_init(MPI_COMM_WORLD, MPM_LOG_INFO, 0);
  if (strcmp(argv[1], "keys") == 0)
    rc = cli_keys(argc - 2, argv + 2);
  else
    rc = run(argv[1], argv[2], argc - 3, argv + 3);
  /* Input errors and unphysical states are detected on every rank alike, and a failed write
   * of an output file is agreed on by every rank: end cleanly. */
  if (rc != 0 && rc != MPM_ERR_INPUT && rc != MPM_ERR_UNPHYSICAL && rc != MPM_ERR_INTERRUPTED &&
      rc != MPM_ERR_OUTPUT) {
    mpm_log_all(MPM_LOG_DEBUG, "mpmfsi failed: %s", mpm_error_string(rc));
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  /* A file HDF5 could not close would crash HDF5's termination in MPI_Finalize (mpm_h5.h):
   * every rank knows, and ends without it. */
  if (rc == MPM_ERR_OUTPUT && mpm_h5_unclosed()) {
    fflush(NULL);
    _exit(exit_status(rc));
  }
#if defined(__SANITIZE_ADDRESS__)
  /* Every allocation of ours is freed by now, and Open MPI's are still reachable from its
   * globals: a leak check here sees only our leaks. At exit, after MPI_Finalize has unloaded
   * Open MPI's plugins, their allocations would need the slow unwinder (on every malloc, 35 %
   * of a sanitized run's time) to be matched to a suppression. The check at exit is then off. */
  __lsan_do_leak_check();
#endif
  MPI_Finalize();
  return exit_status(rc);
}
