# Every particle layout the gas, the solid and the coupler can build fits the particle store,
# 2-D and 3-D, through the modules' own layout builders (a new field cannot silently break a
# combination of options).
mpm_add_test(test_layouts SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_layouts.c LABELS unit
             RANKS 1 LIBS mpmfsi_fluid mpmfsi_solid mpmfsi_coupler)
