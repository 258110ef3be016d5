/* The command line's texts and its two commands that need no case: what main.c dispatches
 * to besides run, check and restart. Everything here prints on rank 0 only (the caller may
 * run under mpiexec) and needs no more than one rank. */
#ifndef MPMFSI_CLI_H
#define MPMFSI_CLI_H

#include <stdio.h>

/* The commands, as a user reads them in an error line. */
#define CLI_COMMANDS "run, check, restart, keys, version, help"

/* Is name one of CLI_COMMANDS? */
int cli_is_command(const char *name);
/* Is arg a request for help: -h or --help? */
int cli_is_help_flag(const char *arg);

/* The general usage, which starts with a "usage:" line (so `mpmfsi --help | head` shows it). */
void cli_usage(FILE *f);
/* One command's help: synopsis, arguments, what it writes, exit codes, examples. Returns 0,
 * or -1 (printing nothing) when command is not one of CLI_COMMANDS. */
int cli_help(FILE *f, const char *command);

/* "mpmfsi 0.1.0 (git 17dee4f, dirty)": the version and the revision it was built from. */
const char *cli_version(void);
/* cli_version() and the SUNDIALS, HDF5 and MPI versions, one line each. */
void cli_print_version(FILE *f);

/* mpmfsi keys [SECTION] [--markdown]: every key of the schema `check` validates against,
 * on stdout. Returns 0, or MPM_ERR_INPUT on a bad argument (reported on stderr). */
int cli_keys(int argc, char **argv);

#endif
