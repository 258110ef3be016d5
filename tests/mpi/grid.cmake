# Grid decomposition, ownership and halo exchanges: one executable, run on 1-4 ranks.
mpm_add_test(test_halo_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_halo.c
             LABELS unit mpi RANKS 1)
foreach(np 2 3 4)
  mpm_add_test(test_halo_np${np} EXE test_halo_np1 LABELS unit mpi RANKS ${np})
endforeach()
# A phase's nodal passes over its active block (mpm_grid_phase_narrow).
mpm_add_test(test_phase_narrow_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_phase_narrow.c
             LABELS unit mpi RANKS 1)
mpm_add_test(test_phase_narrow_np2 EXE test_phase_narrow_np1 LABELS unit mpi RANKS 2)
