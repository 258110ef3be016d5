# Gas-solid coupling: waves through the interface (tests/verification/test_fsi_waves.py):
# transmission of a 10 % shock into an elastic slab (Z_s / Z_g = 2) against the exact answer,
# and the acceleration of a free slab between two gas columns, for the coupling schemes
# velocity and traction, usl and musl, at dx = 0.01; `long` repeats them at dx = 0.005.
mpm_add_script_test(test_fsi_waves SCRIPT verification/test_fsi_waves.py
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_fsi_waves_long SCRIPT verification/test_fsi_waves.py ARGS long
                    LABELS "verification;long" TIMEOUT 1800)
# Temporal coupling: the Piperno-Farhat energy check (cases/fsi_piston.ini): monolithic against
# the uncoupled modules, staggered solid_first's interface energy at three coupling steps (order
# 2), its momentum balance, gas_first = monolithic, and 2 ranks against 1.
mpm_add_script_test(test_piperno_farhat SCRIPT verification/test_piperno_farhat.py
                    LABELS "verification;mpi" TIMEOUT 900)
# Temporal coupling: multirate = monolithic at one substep, its coupling error against a fine
# reference, the momentum balance, the light-node rule on the shock panel (2 ranks, ~15 s), bitwise
# restart of every temporal scheme, 2 ranks against 1.
mpm_add_script_test(test_timeschemes SCRIPT verification/test_timeschemes.py
                    LABELS "verification;mpi" TIMEOUT 900)
# Multirate with an ERK pair (ARKODE MRIStep): its coupling error's order against a fine monolithic
# bs32 reference, its momentum balance, 2 ranks against 1. `long` (134 s in CI's plain pass since
# the current strain rate, over a sixth of it): test_timeschemes_quick runs MRIStep's cycles,
# checkpoints and restarts on 1 and 2 ranks in every CI run.
mpm_add_script_test(test_timeschemes_mri SCRIPT verification/test_timeschemes.py ARGS mri
                    LABELS "verification;mpi;long" TIMEOUT 900)
# Its restart checks, short (the sanitizer pass runs this one, not the whole study), and the
# shared exchange on 2 ranks against 1.
mpm_add_script_test(test_timeschemes_quick SCRIPT verification/test_timeschemes.py ARGS quick
                    LABELS "verification;mpi" TIMEOUT 600)
# The least-squares wall at a moving traction interface (cases/fsi_gas_piston.ini): a slab
# driven into gas at rest against the exact piston shock, ghost and least_squares side by side,
# usl; the interface balance, 2 ranks against 1; fsi_box (a block with corners) under traction
# with least_squares: momentum, energy, 3 ranks against 1; input errors (~10 s).
mpm_add_script_test(test_traction_ls SCRIPT verification/test_traction_ls.py
                    LABELS "verification;mpi" TIMEOUT 600)
# Shocks reflecting from a near-rigid slab (Mach 1.21, Z_s / Z_g = 1.7e4) and a soft one
# (Mach 2, 3.4) (tests/verification/test_fsi_reflection.py): the first gas layer, the reflected
# plateau, the interface force and the transmitted stress plateau against the exact reflection;
# the first layer and some ringing are marked expected to fail (see the driver). Default: velocity,
# contact, traction (with and without least_squares), usl and bs32, and sharp under usl (~110 s);
# `long` the rest.
mpm_add_script_test(test_fsi_reflection SCRIPT verification/test_fsi_reflection.py
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_fsi_reflection_long SCRIPT verification/test_fsi_reflection.py ARGS long
                    LABELS "verification;long" TIMEOUT 2400)
# Initial stress (solid.NAME.initial_pressure): a pre-stressed slab between gas columns at the
# same pressure stays at rest to roundoff for 1,000 steps under velocity, contact and traction,
# usl and bs32 (contact: usl, musl), the least-squares wall, multirate, staggered gas_first,
# 2 ranks, 3-D and every deformable model; the stress-free control moves; energy bookkeeping;
# bitwise restart (~15 s of CPU; 140 s under the sanitizers on the shared machine).
mpm_add_script_test(test_prestress SCRIPT verification/test_prestress.py
                    LABELS "verification;mpi" TIMEOUT 600)
# The gas-column/slab resonator (cases/fsi_resonator.ini): the first two coupled frequencies
# against the exact roots of Z_g cot(k_g L_g) + Z_s cot(k_s L_s) = 0 at 50, 100, 200 cells per
# metre under velocity (usl; monolithic and multirate) and sharp (usl; monolithic and multirate,
# with its gauge), their convergence, and the gas beside the slab staying 1-D (about 70 s of
# CPU); `long` adds contact, traction, bs32, 400 cells per metre
# and 20 periods at 400 and 800 (bs32 alone took 314 s at 200 cells under load), the named
# hybrid pressure's study and 20 periods at 800 (about 13 minutes of CPU more), and 20 periods at
# 400 and 800 under bs32 with its default pressure beside a solid, the hybrid (12 and 43 minutes
# beside another run: 101,071 and 184,559 steps), and sharp under bs32 and multirate: its study
# (about 20 minutes), 20 periods at 800 (about an hour) and the control at 400 without the gauge.
# Its runs add up to about 6 hours on one core (their single timings, 2026-12-07).
mpm_add_script_test(test_fsi_resonator SCRIPT verification/test_fsi_resonator.py
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_fsi_resonator_long SCRIPT verification/test_fsi_resonator.py ARGS long
                    LABELS "verification;long" TIMEOUT 28800)
# Multirate under bs32 (MRIStep, with the hybrid pressure, auto's choice there): the frequencies
# at 50 to 400 cells per metre and 20 periods at 400 and 800 (85,247 and 170,463 steps: 37 and
# 105 minutes beside other runs).
mpm_add_script_test(test_fsi_resonator_mri SCRIPT verification/test_fsi_resonator.py ARGS mri
                    LABELS "verification;long" TIMEOUT 14400)
# sharp under multirate (usl; bs32, MRIStep), with its gauge: 20 periods at 400 and 800 cells
# per metre, the gas 1-D (208, 1,081, 1,541 and 4,720 s beside other runs; 2026-12-07).
mpm_add_script_test(test_fsi_resonator_sharp_stable SCRIPT verification/test_fsi_resonator.py
                    ARGS stable sharp:usl:multirate sharp:bs32:multirate
                    LABELS "verification;long" TIMEOUT 21600)
# The grid pressure beside a solid under multirate and contact (test_gridp_beside.py): the
# resonator strip stays 1-D and balances under multirate (usl, MRIStep), a body in gas at rest
# stays at rest and a pulse on it keeps the gas's energy booked under contact (23, 5 and 3 s);
# the refusals that remain (staggered, the shared exchange); `long` the strip at 800 cells/m
# to t = 3 (357 s under load).
foreach(part multirate contact input)
  mpm_add_script_test(test_gridp_beside_${part} SCRIPT verification/test_gridp_beside.py
                      ARGS ${part} LABELS verification TIMEOUT 600)
endforeach()
mpm_add_script_test(test_gridp_beside_long SCRIPT verification/test_gridp_beside.py ARGS long
                    LABELS "verification;long" TIMEOUT 3600)
