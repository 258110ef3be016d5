# The compiled serial N_Vector operations against SUNDIALS' own, bit for bit.
mpm_add_test(test_nvector SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_nvector.c
             LABELS unit RANKS 1 LIBS mpmfsi_coupler)
