# Split and merge of gas particles for refinement (fluid/fluid_split.h): conservation, round
# trip and ids on random sets in the gas's layouts, 2-D and 3-D, and their cost (printed).
mpm_add_test(test_split SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_split.c LABELS unit RANKS 1
             LIBS mpmfsi_fluid)
