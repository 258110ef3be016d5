# Run safety (issue 13): output folders that belong to one run, restarts that never mix or
# silently change results, runaway runs refused, signals that end with a checkpoint.
mpm_add_script_test(test_run_safety SCRIPT verification/test_run_safety.py
                    LABELS "verification;mpi" TIMEOUT 600)
# Every case in cases/ restarts bitwise from a checkpoint halfway through a few steps.
mpm_add_script_test(test_restart_cases SCRIPT verification/test_restart_cases.py
                    LABELS verification TIMEOUT 900)
