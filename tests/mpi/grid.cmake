# Grid decomposition, ownership and halo exchanges: one executable, run on 1-4 ranks.
add_executable(test_halo ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_halo.c)
target_link_libraries(test_halo PRIVATE mpmfsi_common)
foreach(np 1 2 3 4)
  mpm_add_test(test_halo_np${np} EXE test_halo LABELS unit mpi RANKS ${np})
endforeach()
