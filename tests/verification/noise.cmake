# Particle noise in the wedge's uniform post-shock region (issue 50, item 3): the relative
# density scatter 3x below the old settings' (bound and reasons in test_gas_noise.py).
# One wedge run: about 25 s idle, 90 s on the loaded 2-core machine.
mpm_add_script_test(test_gas_noise SCRIPT verification/test_gas_noise.py
                    LABELS verification TIMEOUT 300)
