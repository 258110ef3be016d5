# Multirate's coupling step: the damped stable step of the gas (fluid.viscous_step) on the shock
# panel, and the predictor of the solid's interface velocity (coupling.predictor) on the stiff
# piston: its coupling error's order and momentum balance, and where the panel leaves a node
# (~50 s).
mpm_add_script_test(test_multirate_step SCRIPT verification/test_multirate_step.py
                    LABELS verification TIMEOUT 300)

# Multirate's exchange at the face of a soft, fast slab under a Mach 2 shock
# (cases/fsi_multirate_face.ini): coupling.exchange = shared against monolithic, and the slab
# clamped under shared and held (the gas stays out, W within 2x of monolithic's) (~60 s).
mpm_add_script_test(test_multirate_face SCRIPT verification/test_multirate_face.py
                    LABELS verification TIMEOUT 300)
# The same face and energy at time.cfl 0.4 to 0.025 (shared): the total energy's excess over
# monolithic's falls at every halving; the booked W's own part to 0.05 only (~8 min).
mpm_add_script_test(test_multirate_face_long SCRIPT verification/test_multirate_face.py ARGS long
                    LABELS "verification;long" TIMEOUT 1800)
# MRIStep (bs32, fixed steps) on the same face against monolithic bs32 at time.cfl 0.4, 0.2, 0.1:
# the face's motion within 3 % of the exact interface speed, the balance, the total energy's
# change within twice monolithic's and its excess over monolithic's falling with the step.
mpm_add_script_test(test_multirate_face_mri SCRIPT verification/test_multirate_face.py ARGS mri
                    LABELS "verification;long" TIMEOUT 1800)
