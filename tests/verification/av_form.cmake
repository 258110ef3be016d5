# The Riemann-based artificial viscosity (fluid.av_form = riemann) against vnr at 400 cells on
# Toro 3 and Sod, usl: its measured gain (~15 s).
mpm_add_script_test(test_av_form SCRIPT verification/test_av_form.py LABELS verification
                    TIMEOUT 300)
