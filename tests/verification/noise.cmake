# Particle noise in the wedge's uniform post-shock region (issue 50, item 3): the relative
# density scatter 3x below the old settings' (bound and reasons in test_gas_noise.py). ~25 s.
mpm_add_script_test(test_gas_noise SCRIPT verification/test_gas_noise.py
                    LABELS verification TIMEOUT 300)
