# Output folders that cannot redirect a run (issue 54): no file is written through a link in
# the output folder, system folders are refused, and output.dir has a length limit that
# check enforces.
mpm_add_script_test(test_output_links SCRIPT verification/test_output_links.py
                    LABELS "verification;mpi" TIMEOUT 600)
# The writers themselves, below the folder's claim: links at a checkpoint's final, temporary
# and Open MPI lock-test names and at a CSV's names leave their targets as they were.
mpm_add_test(test_safefile SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_safefile.c
             LABELS unit ARGS ${CMAKE_CURRENT_BINARY_DIR}/test_safefile_files TIMEOUT 60)
mpm_add_test(test_safefile_np2 EXE test_safefile LABELS "unit;mpi" RANKS 2
             ARGS ${CMAKE_CURRENT_BINARY_DIR}/test_safefile_files_np2 TIMEOUT 60)
