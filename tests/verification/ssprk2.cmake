# ssprk2 (time.method): second order in time on smooth gas flow; usl, the control, is not.
mpm_add_script_test(test_time_order_gas SCRIPT verification/test_time_order_gas.py
                    LABELS verification TIMEOUT 600)
