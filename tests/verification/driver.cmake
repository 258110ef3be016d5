mpm_add_script_test(test_ballistic SCRIPT verification/test_ballistic.py
                    LABELS "verification;mpi" TIMEOUT 600)
mpm_add_script_test(test_restart SCRIPT verification/test_restart.py
                    LABELS "verification;mpi" TIMEOUT 900)
mpm_add_script_test(test_bad_input SCRIPT conformance/test_bad_input.py
                    LABELS "conformance" TIMEOUT 600)
mpm_add_script_test(test_recoverable SCRIPT verification/test_recoverable.py
                    LABELS "verification" TIMEOUT 600)
mpm_add_script_test(test_decomposition SCRIPT verification/test_decomposition.py
                    LABELS "verification;mpi" TIMEOUT 600)
mpm_add_script_test(test_axial_bar SCRIPT verification/test_axial_bar.py
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_axial_bar_long SCRIPT verification/test_axial_bar.py ARGS long
                    LABELS "verification;long" TIMEOUT 1800)
mpm_add_script_test(test_cases SCRIPT conformance/test_cases.py LABELS conformance TIMEOUT 300)
