# The finite-volume anchor of the gas benchmarks (bench/fv_strip.py, bench/bench_sod.py
# --problem): the reference solver's Sod L1 at 400 cells against the quoted 1.3e-3, and a tiny
# run of each problem that must write its page, CSV and plot with the ratio and Galilean
# tables (~15 s; asserts no wall time).
mpm_add_script_test(test_fv_anchor SCRIPT verification/test_fv_anchor.py LABELS benchmark
                    TIMEOUT 200)
