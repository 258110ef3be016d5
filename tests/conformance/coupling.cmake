# The spatial coupling schemes: every registered scheme but none (found from the program), on a
# pulse in a periodic box (uniform motion, momentum, interface balance, energy closure), the
# shared nodal velocity (velocity), no interpenetration and separation (contact).
mpm_add_script_test(test_coupling SCRIPT conformance/test_coupling.py LABELS conformance
                    TIMEOUT 600)
# fluid.pic_fraction: the gas's own PIC share leaves the solid alone.
mpm_add_script_test(test_gas_pic SCRIPT conformance/test_gas_pic.py LABELS conformance TIMEOUT 300)
