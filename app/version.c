/* mpmfsi's version, the git revision it was built from (mpm_version.h, written at every
 * build by revision.cmake) and the versions of the libraries it runs on: what a bug report
 * and a run's log need to say which code made a result. */
#include "cli.h"
#include "mpm_version.h"

#include <hdf5.h>
#include <mpi.h>
#include <string.h>
#include <sundials/sundials_config.h>

const char *cli_version(void) {
  return "mpmfsi " MPMFSI_VERSION " (git " MPMFSI_REVISION ")";
}

void cli_print_version(FILE *f) {
  unsigned major = 0, minor = 0, release = 0;
  char mpi[MPI_MAX_LIBRARY_VERSION_STRING] = "unknown";
  int len = 0, standard = 0, subversion = 0;
  const int h5 = H5get_libversion(&major, &minor, &release) >= 0;
  if (MPI_Get_library_version(mpi, &len) != MPI_SUCCESS) snprintf(mpi, sizeof mpi, "unknown");
  MPI_Get_version(&standard, &subversion);
  fprintf(f, "%s\n", cli_version());
  fprintf(f, "SUNDIALS %s\n", SUNDIALS_VERSION);
  if (h5)
    fprintf(f, "HDF5 %u.%u.%u\n", major, minor, release);
  else
    fprintf(f, "HDF5 unknown\n");
  /* The library's text runs over several lines (Open MPI adds its repository and date): the
   * first says which library and release. */
  fprintf(f, "MPI %.*s (MPI standard %d.%d)\n", (int)strcspn(mpi, "\r\n"), mpi, standard,
          subversion);
}
