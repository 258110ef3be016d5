# fluid.volume_rate = domain on the strong shock moving across the grid against at rest, bs32,
# 200 and 400 cells (~30 s).
mpm_add_script_test(test_volume_rate SCRIPT verification/test_volume_rate.py LABELS verification
                    TIMEOUT 300)
