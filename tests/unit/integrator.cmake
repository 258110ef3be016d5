# The ARKODE driver with an exactly solvable test module (two modules, injection, retries).
mpm_add_test(test_integrator_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_integrator.c
             LABELS "unit;mpi" RANKS 1 LIBS mpmfsi_coupler)
mpm_add_test(test_integrator_np2 EXE test_integrator_np1 LABELS "unit;mpi" RANKS 2)
mpm_add_test(test_integrator_np3 EXE test_integrator_np1 LABELS "unit;mpi" RANKS 3)
# The blow-up guard's criteria and defaults on step and energy sequences.
mpm_add_test(test_guard SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_guard.c
             LABELS unit LIBS mpmfsi_coupler)
