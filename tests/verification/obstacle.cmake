# Static obstacles: rest, momentum balance against the reported forces, seeding, 2 ranks vs 1.
mpm_add_script_test(test_obstacles SCRIPT verification/test_obstacles.py
                    LABELS "verification;mpi" TIMEOUT 600)
# Total energy with usl is not conserved with obstacles: the ghost pressure does work on the
# moving gas (measured 5.3e-5 relative over 67 steps against a 1e-12 target). Expected failure
# until that work is booked as heat; see the test's header.
mpm_add_script_test(test_obstacles_energy SCRIPT verification/test_obstacles.py ARGS energy
                    LABELS verification TIMEOUT 300)
set_tests_properties(test_obstacles_energy PROPERTIES WILL_FAIL TRUE)
