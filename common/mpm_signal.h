/* Stopping a run on SIGTERM, SIGINT or SIGHUP (a batch scheduler's time limit, Ctrl-C, a closed
 * terminal or ssh session; SIGHUP is left ignored under nohup). The first
 * signal is only recorded; the step loop asks, once per step, whether any rank has one and
 * then ends the run with a checkpoint. A second signal acts at once (the default action is
 * back in place). */
#ifndef MPM_SIGNAL_H
#define MPM_SIGNAL_H

#include <mpi.h>

/* Install the handlers and forget any earlier signal. */
void mpm_signal_catch(void);

/* The signal any rank has received (0: none), the same on every rank. Collective. */
int mpm_signal_agreed(MPI_Comm comm, int *sig);

/* "SIGTERM", "SIGINT", "SIGHUP" or "a signal". */
const char *mpm_signal_name(int sig);

#endif
