# Particle storage: edit, inject, sort and migration under a random walk, on 2 and 4 ranks.
add_executable(test_migrate ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_migrate.c)
target_link_libraries(test_migrate PRIVATE mpmfsi_common)
foreach(np 2 4)
  mpm_add_test(test_migrate_np${np} EXE test_migrate LABELS unit mpi RANKS ${np})
endforeach()
