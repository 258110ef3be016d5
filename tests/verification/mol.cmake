# The method of lines' transverse grid-scale mode and fluid.mol_damping (plain build only in CI:
# 131 s under the sanitizers); _shift: shifting with the damping on, two runs to t = 1, the
# sanitizer pass's cover of the damping's code.
mpm_add_script_test(test_mol_damping SCRIPT verification/test_mol_damping.py
                    LABELS verification TIMEOUT 300)
mpm_add_script_test(test_mol_damping_shift SCRIPT verification/test_mol_damping.py ARGS shift
                    LABELS verification TIMEOUT 300)
