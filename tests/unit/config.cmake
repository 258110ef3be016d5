# Case-file configuration: unit tests and a seeded fuzz test (both fast, label unit).
mpm_add_test(test_config SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_config.c LABELS unit)
mpm_add_test(fuzz_config SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/fuzz_config.c LABELS unit
             TIMEOUT 60)
