# Particle noise in the wedge's uniform post-shock region (issue 50, item 3): the relative
# density scatter 3x below the old settings' (bound and reasons in test_gas_noise.py).
# One wedge run: about 25 s idle, 90 s on the loaded 2-core machine.
mpm_add_script_test(test_gas_noise SCRIPT verification/test_gas_noise.py
                    LABELS verification TIMEOUT 300)
# The defect-corrected particle pressure (fluid.pressure = hybrid): a gas column at 800 cells per
# metre under usl, whose grid-scale transverse mode grows out of roundoff with the particles'
# pressure, stays at roundoff with exact energy; a uniform stream through open faces; its refusals
# (12 s of CPU time; 60-95 s wall on the loaded 2-core machine).
mpm_add_script_test(test_hybrid_pressure SCRIPT verification/test_hybrid_pressure.py
                    LABELS verification TIMEOUT 300)
# The grid pressure's relaxation of the particles' pressures (fluid.pressure_relax): two gases
# interleaved at rest against the exact relaxation, conservation and entropy; Sod under usl with
# and without it; a standing wave's damping; its default (off uniform, on on two levels); its
# refusals (about 15 s of CPU time).
mpm_add_script_test(test_pressure_relax SCRIPT verification/test_pressure_relax.py
                    LABELS verification TIMEOUT 300)
