# A full disk never hangs a run (issue 54, tests/verification/test_full_disk.py): 1, 2 and 3
# ranks end within a bounded time with one line and exit 1, the last checkpoint intact and
# restartable. The full disk is a small tmpfs where the test may mount one, and otherwise the
# LD_PRELOAD shim below (test-only; never linked into mpmfsi), so that the test never skips.
add_library(mpmfsi_fulldisk_shim SHARED tools/fulldisk_shim.c)
target_link_libraries(mpmfsi_fulldisk_shim PRIVATE ${CMAKE_DL_LIBS})
# A preloaded library must not carry the sanitizers' runtime: the executable brings its own.
target_compile_options(mpmfsi_fulldisk_shim PRIVATE -fno-sanitize=all)
target_link_options(mpmfsi_fulldisk_shim PRIVATE -fno-sanitize=all)
mpm_add_script_test(test_full_disk SCRIPT verification/test_full_disk.py
                    ARGS $<TARGET_FILE:mpmfsi_fulldisk_shim> LABELS "verification;mpi"
                    TIMEOUT 600 NO_LEAK_CHECK)
