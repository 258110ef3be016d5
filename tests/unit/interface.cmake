# The partitioned schemes' owed momentum after a solid advance (mpm_interface_rehome).
mpm_add_test(test_interface_rehome_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_interface_rehome.c
             LABELS "unit;mpi" RANKS 1 LIBS mpmfsi_coupler)
mpm_add_test(test_interface_rehome_np2 EXE test_interface_rehome_np1 LABELS "unit;mpi" RANKS 2)
mpm_add_test(test_interface_rehome_np3 EXE test_interface_rehome_np1 LABELS "unit;mpi" RANKS 3)
