# J2 plasticity (solid_j2.c): eigen solver, Hencky elastic range, uniaxial bilinear curve,
# unloading, yield surface, plastic incompressibility, objectivity, history untouched.
mpm_add_test(test_j2 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_j2.c LABELS unit
             LIBS mpmfsi_solid)
