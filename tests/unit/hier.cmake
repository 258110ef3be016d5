# The refinement hierarchy (common/mpm_hier.h) on one rank: the composite basis (partition of
# unity, C1 across levels, adjoint restriction and prolongation, refusals of bad boxes) and the
# composite transfers (conservation, P2G = the basis, affine reproduction, the nodal solve; the
# cost against the plain kernel is printed).
mpm_add_test(test_hier_basis SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_hier_basis.c
             LABELS unit RANKS 1)
mpm_add_test(test_hier_transfer SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_hier_transfer.c
             LABELS unit RANKS 1)
# The hierarchy on a grid split over 2 ranks against one rank: the level of points, a deposit
# restricted, a field prolonged (a periodic level across the ranks' boundary, three levels).
mpm_add_test(test_hier_ranks SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_hier_ranks.c
             LABELS mpi RANKS 2)
# The exact span integrals the grid pressure uses (common/mpm_span.h): adjointness, constant and
# linear fields, halved spans at a wall, in 2-D and 3-D.
mpm_add_test(test_span SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_span.c LABELS unit RANKS 1)
# Levels across periodic faces (a band spanning the period, regions crossing the faces, 2-D and
# 3-D): partition of unity, periodicity of the basis, conservation, P2G = eval, reproduction.
mpm_add_test(test_hier_periodic SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_hier_periodic.c
             LABELS unit RANKS 1)
# Levels touching walls (slip and no-slip, a corner): the masks are symmetric about the walls,
# partition of unity, the finer levels' fold keeps the mass and empties the nodes beyond the
# walls, and the apply mirrors the velocity.
mpm_add_test(test_hier_walls SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_hier_walls.c
             LABELS unit RANKS 1)
