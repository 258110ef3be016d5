# Particle storage: edit, inject, sort and migration under a random walk, on 2 and 4 ranks.
mpm_add_test(test_migrate_np2 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_migrate.c
             LABELS unit mpi RANKS 2)
mpm_add_test(test_migrate_np4 EXE test_migrate_np2 LABELS unit mpi RANKS 4)
