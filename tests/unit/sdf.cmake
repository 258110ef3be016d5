# Signed distances of the obstacle shapes, and the RAE 2822 aerofoil outline
# (cases/rae2822_coordinates.csv, a copy of shared/validation's file).
mpm_add_test(test_sdf SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_sdf.c LABELS unit
             ARGS ${PROJECT_SOURCE_DIR}/cases/rae2822_coordinates.csv)
