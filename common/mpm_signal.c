/* Stopping a run on a signal (see mpm_signal.h). */
#define _POSIX_C_SOURCE 200809L /* sigaction */
#include "mpm_signal.h"

#include "mpm_error.h"

#include <signal.h>
#include <string.h>

static volatile sig_atomic_t g_signal;

static void on_signal(int sig) {
  g_signal = sig;
  signal(sig, SIG_DFL); /* async-signal-safe; the next one acts at once */
}

void mpm_signal_catch(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sa.sa_flags = SA_RESTART; /* a log write the signal interrupts goes on */
  sigemptyset(&sa.sa_mask);
  g_signal = 0;
  sigaction(SIGTERM, &sa, NULL);
  sigaction(SIGINT, &sa, NULL);
  /* SIGHUP (the terminal or the ssh session went away) as SIGTERM, unless the run was started
   * under nohup, which asks for it to be ignored: that wish is kept, as careful tools do. */
  struct sigaction old;
  if (sigaction(SIGHUP, NULL, &old) == 0 && old.sa_handler != SIG_IGN) sigaction(SIGHUP, &sa, NULL);
}

int mpm_signal_agreed(MPI_Comm comm, int *sig) {
  int mine = (int)g_signal;
  MPM_CALL_MPI(MPI_Allreduce(&mine, sig, 1, MPI_INT, MPI_MAX, comm));
  return 0;
}

const char *mpm_signal_name(int sig) {
  return sig == SIGTERM  ? "SIGTERM"
         : sig == SIGINT ? "SIGINT"
         : sig == SIGHUP ? "SIGHUP"
                         : "a signal";
}
