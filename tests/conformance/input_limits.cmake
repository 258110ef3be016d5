# Input limits (issue 54): expressions too large for libmatheval, non-normal reals, runaway
# substeps, sub-iterations and time.dt_max, and checkpoints edited to a time that cannot run.
mpm_add_script_test(test_input_limits SCRIPT conformance/test_input_limits.py
                    LABELS conformance TIMEOUT 600 NO_LEAK_CHECK)
