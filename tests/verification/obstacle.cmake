# Static obstacles: rest, momentum balance against the reported forces, seeding, 2 ranks vs 1.
mpm_add_script_test(test_obstacles SCRIPT verification/test_obstacles.py
                    LABELS "verification;mpi" TIMEOUT 600)
# Total energy with obstacles, usl and musl, ghost and least_squares: conserved to roundoff
# (the obstacles' work is booked as heat; see the test's header).
mpm_add_script_test(test_obstacles_energy SCRIPT verification/test_obstacles.py ARGS energy
                    LABELS verification TIMEOUT 300)
