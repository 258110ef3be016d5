# fluid.pressure_smoothing: mass, momentum and total energy exact with the smoothed pressure
# (usl, musl, bs32), 2 ranks as 1, gas at rest kept at rest (bounds in the script).
mpm_add_script_test(test_pressure_smoothing SCRIPT verification/test_pressure_smoothing.py
                    LABELS "verification;mpi" TIMEOUT 300)
