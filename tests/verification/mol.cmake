# The method of lines' transverse grid-scale mode and fluid.mol_damping.
mpm_add_script_test(test_mol_damping SCRIPT verification/test_mol_damping.py
                    LABELS verification TIMEOUT 300)
