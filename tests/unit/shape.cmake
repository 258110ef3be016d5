# Shape function properties (partition of unity, linear completeness, gradients, continuity).
mpm_add_test(test_shape SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_shape.c LABELS unit)
