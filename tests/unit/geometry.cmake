# Regions and lattice seeding: exact counts, area/volume bounds, rank independence, bad input.
mpm_add_test(test_geometry SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_geometry.c LABELS unit)
