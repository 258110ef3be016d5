# Periodic axes: P2G and halos against an unbounded lattice on 1-4 ranks; migration across
# periodic faces under a random walk on 2 and 4 ranks.
foreach(np 1 2 3 4)
  if(np EQUAL 1)
    mpm_add_test(test_periodic_p2g_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_periodic_p2g.c
                 LABELS "unit;mpi" RANKS 1 TIMEOUT 120)
  else()
    mpm_add_test(test_periodic_p2g_np${np} EXE test_periodic_p2g_np1 LABELS "unit;mpi"
                 RANKS ${np} TIMEOUT 120)
  endif()
endforeach()
mpm_add_test(test_periodic_migrate_np2 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_periodic_migrate.c
             LABELS "unit;mpi" RANKS 2 TIMEOUT 120)
mpm_add_test(test_periodic_migrate_np4 EXE test_periodic_migrate_np2 LABELS "unit;mpi" RANKS 4
             TIMEOUT 120)
