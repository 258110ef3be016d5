# Split and merge of gas particles for refinement (fluid/fluid_split.h): conservation, round
# trip and ids on random sets in the gas's layouts, 2-D and 3-D, and their cost (printed).
mpm_add_test(test_split SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_split.c LABELS unit RANKS 1
             LIBS mpmfsi_fluid)
# The same split on 1, 2 and 3 ranks: ids and data bit for bit, and split + migrate + merge by
# parent slot returns the gas.
mpm_add_test(test_split_ranks_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_split_ranks.c
             LABELS "unit;mpi" RANKS 1 LIBS mpmfsi_fluid)
mpm_add_test(test_split_ranks_np2 EXE test_split_ranks_np1 LABELS "unit;mpi" RANKS 2)
mpm_add_test(test_split_ranks_np3 EXE test_split_ranks_np1 LABELS "unit;mpi" RANKS 3)
