# P2G/G2P kernels: the APIC affine transfer and the external-force deposit, every shape in
# 2-D and 3-D (one rank: the grid needs MPI).
mpm_add_test(test_kernels_apic SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_kernels_apic.c
             LABELS unit RANKS 1)
# G2P of nodal scalars with the velocity (the gas energy balance), every shape, 2-D and 3-D.
mpm_add_test(test_kernels_scalars SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_kernels_scalars.c
             LABELS unit RANKS 1)
# The lean deposit and the scalar gather (the grid pressure's corrections, the viscous deposit)
# against the full kernels, bitwise, every shape, 2-D and 3-D.
mpm_add_test(test_kernels_scalar_paths
             SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_kernels_scalar_paths.c LABELS unit RANKS 1)
# The kernels' index list and wrap (the hierarchy's per-level transfers) against the kernels on
# the same particles copied out or wrapped beforehand, bitwise, every shape, 2-D and 3-D.
mpm_add_test(test_kernels_subset SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_kernels_subset.c
             LABELS unit RANKS 1)
