# The shared conformance suite of the material models: every registered model, 2-D and 3-D.
mpm_add_test(test_materials SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/conformance/test_materials.c
             LABELS conformance LIBS mpmfsi_solid)
