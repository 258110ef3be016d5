/* The usage and each command's help, kept out of main.c so that the dispatch reads on one
 * screen. Every text starts with its synopsis, so that `mpmfsi help run | head -3` answers
 * "how do I call it". The facts here (exit codes, files written) are those of main.c and
 * docs/running.md, docs/output.md: change them together. */
#include "cli.h"

#include <string.h>

static const char g_usage[] =
    "usage: mpmfsi COMMAND [ARGUMENTS]\n"
    "\n"
    "  run CASE [key=value ...]             run a case file\n"
    "  check CASE [key=value ...]           validate it, print the resolved case and the "
    "estimate\n"
    "  restart CHECKPOINT [key=value ...]   continue a run from a checkpoint\n"
    "  keys [SECTION] [--markdown]          list every case-file key (type, unit, default, "
    "range)\n"
    "  version                              the version, git revision and library versions\n"
    "  help [COMMAND]                       this text, or one command's help\n"
    "\n"
    "Every case-file key can be overridden on the command line as section.key=value.\n"
    "Options: -h, --help (also after a command: mpmfsi run --help); --version.\n"
    "Exit status: 0 success, 1 the run failed, 2 bad input (nothing ran), 3 stopped by a "
    "signal.\n"
    "In parallel: mpiexec -n 4 mpmfsi run CASE. Documentation: docs/index.md.\n";

/* What run, check and restart share. */
#define OVERRIDES                                                                                  \
  "  key=value    set a key as section.key=value (time.t_end=0.5), over the case file's\n"         \
  "               value; a key given twice on the command line is an error\n"
#define EXIT_CODES                                                                                 \
  "Exit status:\n"                                                                                 \
  "  0  success\n"                                                                                 \
  "  1  the run failed (an unphysical state, or the blow-up guard stopped it)\n"                   \
  "  2  bad input: nothing ran and nothing was written; an error line names file:line and key\n"   \
  "  3  stopped by SIGTERM, SIGINT or SIGHUP; a final checkpoint was written (restart from it)\n"

static const char g_run[] =
    "usage: mpmfsi run CASE [key=value ...]\n"
    "\n"
    "Run a case file.\n"
    "\n"
    "Arguments:\n"
    "  CASE         the case file (.ini: [section] headers and key = value lines)\n" OVERRIDES "\n"
    "Writes into output.dir (default: out): snap_NNNNNN.h5 snapshots with series.xmf (open it "
    "in\n"
    "ParaView), checkpoint_final.h5 (and checkpoint_NNNNNN.h5 every "
    "output.checkpoint_interval),\n"
    "diagnostics.csv, summary.json, timers.csv, run.log, view.py; coupling.csv, probes.csv,\n"
    "obstacles.csv where the case has them. A folder holding another run's results is refused\n"
    "unless output.overwrite=true. The log goes to stderr; stdout stays empty.\n"
    "\n" EXIT_CODES "\n"
    "Examples:\n"
    "  mpmfsi run cases/ballistic2d.ini\n"
    "  mpmfsi run cases/ballistic2d.ini time.t_end=0.5 output.dir=out/short\n"
    "  mpiexec -n 4 mpmfsi run cases/two_disks.ini\n";

static const char g_check[] =
    "usage: mpmfsi check CASE [key=value ...]\n"
    "\n"
    "Validate a case as run would (every input error is reported, not just the first), then\n"
    "print the resolved case on stdout: every key in use with its value and where it came from,\n"
    "the defaults commented out. The text is itself a valid case. Writes no file.\n"
    "\n"
    "Arguments:\n"
    "  CASE         the case file\n" OVERRIDES "\n"
    "Exit status: 0 the case is valid, 2 it is not (the errors are on stderr).\n"
    "\n"
    "Examples:\n"
    "  mpmfsi check cases/ballistic2d.ini\n"
    "  mpmfsi check cases/ballistic2d.ini grid.dx=0.05 > resolved.ini\n";

static const char g_restart[] =
    "usage: mpmfsi restart CHECKPOINT [key=value ...]\n"
    "\n"
    "Continue a run, bit for bit, from a checkpoint (checkpoint_final.h5 or "
    "checkpoint_NNNNNN.h5),\n"
    "on any number of ranks. The case is the one the checkpoint stores.\n"
    "\n"
    "Arguments:\n"
    "  CHECKPOINT   a checkpoint file written by mpmfsi run or restart\n"
    "  key=value    override a key; a restart may change only time.*, output.*, run.* and\n"
    "               grid.ranks (the rest describes the state the checkpoint holds)\n"
    "\n"
    "Writes into the checkpoint's folder, appending to its CSV files and run.log; if that "
    "folder\n"
    "holds results later than the checkpoint, into <folder>-from-<checkpoint> beside it\n"
    "(output.dir=... chooses the folder; output.truncate=true cuts the old run back instead).\n"
    "\n" EXIT_CODES "\n"
    "Examples:\n"
    "  mpmfsi restart out/ballistic2d/checkpoint_final.h5 time.t_end=0.5\n"
    "  mpiexec -n 2 mpmfsi restart out/ballistic2d/checkpoint_000003.h5 output.dir=out/b2\n";

static const char g_keys[] =
    "usage: mpmfsi keys [SECTION] [--markdown]\n"
    "\n"
    "List every key a case file may set (the schema check validates against): its type, unit,\n"
    "default, allowed range or choices and meaning, sections in alphabetical order and the keys\n"
    "of a section in the order the program declares them. A '*' stands for an instance name:\n"
    "geometry.*.type is type under [geometry.NAME]. Needs no case file.\n"
    "\n"
    "Arguments:\n"
    "  SECTION      only the keys of this section (grid, fluid, geometry, ...)\n"
    "  --markdown   a Markdown document, one table per section: the key reference docs/keys.md\n"
    "\n"
    "Writes only to stdout. Exit status: 0, or 2 for an unknown section or option.\n"
    "\n"
    "Examples:\n"
    "  mpmfsi keys grid\n"
    "  mpmfsi keys | grep -i viscosity\n"
    "  mpmfsi keys --markdown > docs/keys.md\n";

static const char g_version[] =
    "usage: mpmfsi version    (or mpmfsi --version)\n"
    "\n"
    "Print the version and the git revision the program was built from (\", dirty\": with\n"
    "uncommitted changes; \"unknown\": built outside a git clone), then the SUNDIALS, HDF5 and "
    "MPI\n"
    "versions it runs on, one line each. The revision is also in the first log line of every "
    "run.\n"
    "\n"
    "Writes only to stdout. Exit status: 0.\n"
    "\n"
    "Examples:\n"
    "  mpmfsi --version\n"
    "  mpmfsi version | head -1\n";

static const char g_help[] = "usage: mpmfsi help [COMMAND]    (or mpmfsi COMMAND --help)\n"
                             "\n"
                             "Print the usage, or the help of one command: " CLI_COMMANDS ".\n"
                             "\n"
                             "Writes only to stdout. Exit status: 0, or 2 for an unknown command.\n"
                             "\n"
                             "Examples:\n"
                             "  mpmfsi help\n"
                             "  mpmfsi help run\n"
                             "  mpmfsi restart -h\n";

static const struct {
  const char *name, *text;
} g_commands[] = {{"run", g_run},   {"check", g_check},     {"restart", g_restart},
                  {"keys", g_keys}, {"version", g_version}, {"help", g_help}};

enum { NCOMMANDS = sizeof g_commands / sizeof g_commands[0] };

int cli_is_command(const char *name) {
  for (int k = 0; k < NCOMMANDS; ++k)
    if (strcmp(name, g_commands[k].name) == 0) return 1;
  return 0;
}

int cli_is_help_flag(const char *arg) {
  return strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0;
}

void cli_usage(FILE *f) {
  fputs(g_usage, f);
}

int cli_help(FILE *f, const char *command) {
  for (int k = 0; k < NCOMMANDS; ++k)
    if (strcmp(command, g_commands[k].name) == 0) {
      fputs(g_commands[k].text, f);
      return 0;
    }
  return -1;
}
