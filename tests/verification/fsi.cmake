# Gas-solid coupling: waves through the interface (tests/verification/test_fsi_waves.py):
# transmission of a 10 % shock into an elastic slab (Z_s / Z_g = 2) against the exact answer,
# and the acceleration of a free slab between two gas columns, for the coupling schemes
# velocity (usl, musl) and traction (musl) at dx = 0.01; `long` repeats them at dx = 0.005
# (measured: fails there on traction musl's reflected gas jump, -0.084 of the incident against
# the 0.06 tolerance; the shortfall grows with refinement: see test_fsi_waves.py).
mpm_add_script_test(test_fsi_waves SCRIPT verification/test_fsi_waves.py
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_fsi_waves_long SCRIPT verification/test_fsi_waves.py
                    ARGS long velocity:usl velocity:musl LABELS "verification;long" TIMEOUT 1800)
mpm_add_script_test(test_fsi_waves_long_traction SCRIPT verification/test_fsi_waves.py
                    ARGS long traction:musl LABELS "verification;long" TIMEOUT 1800)
set_tests_properties(test_fsi_waves_long_traction PROPERTIES WILL_FAIL TRUE)
# traction with usl creates energy at the interface (coupling.csv W_net > 0): the gas next to
# the slab heats before the shock arrives (p 1.07 in the last cell at t = 0.06), so the
# reflected jump comes out 0.59 of the incident against 0.34 and the transmitted stress +7 %
# (musl: -0.5 %). Kept honest as an expected failure; figures in test_fsi_waves.py.
mpm_add_script_test(test_fsi_waves_traction_usl SCRIPT verification/test_fsi_waves.py
                    ARGS traction:usl LABELS verification TIMEOUT 600)
set_tests_properties(test_fsi_waves_traction_usl PROPERTIES WILL_FAIL TRUE)
