# ssprk2 (time.method): second order in time on smooth gas flow; usl, the control, is not.
mpm_add_script_test(test_time_order_gas SCRIPT verification/test_time_order_gas.py
                    LABELS verification TIMEOUT 600)
# ... and where it is refused (coupling.time = multirate, staggered; a lagged strain rate).
mpm_add_script_test(test_ssprk2_input SCRIPT verification/test_ssprk2_input.py
                    LABELS verification TIMEOUT 300 NO_LEAK_CHECK)
