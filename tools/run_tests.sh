#!/usr/bin/env bash
# Install, build and run the default test selection (everything but the `long` and `benchmark`
# labels), each test once in one of two builds (except the unit tests, a few seconds, and the
# checkpoint fuzz, which run in both):
#
# - build-asan/ (-O2 with asserts, AddressSanitizer, LeakSanitizer and UBSan) runs every test
#   whose run there costs at most a few minutes: the unit, conformance and MPI tests, the input
#   refusal drivers, the checkpoint and restart tests, and the smaller gas, solid and coupling
#   cases. A failure there is a failure of the physics check as much as of the memory check.
# - build/ (the optimised build users run) runs the rest: the flow and physics studies that the
#   sanitizers slow 4-10 fold (PLAIN_ONLY below, with the reason for each group), and the
#   checkpoint fuzz in full (240 damaged copies there, 48 under the sanitizers, whose purpose is
#   memory errors on damaged input).
#
# PLAIN_ONLY, by group (their code runs under the sanitizers in the smaller tests named):
# - gas flow cases: test_wedge, test_forward_step (7 minutes under the sanitizers, 33 s
#   without), the main job's scene test_supersonic_bar and its stand-off study, the
#   near-vacuum convergence study test_near_vacuum_order (test_near_vacuum runs the refill and
#   the shifting there), the wall-treatment flow cases test_slanted_wall
#   and test_bluff_bodies (45-100 s each under the sanitizers; the least-squares fit runs there
#   in test_obstacles and test_obstacles_energy), the gas tubes test_sod, test_strong_shock and
#   the ERK pairs' time-order study test_gas_time_order (test_gas_output, test_gas_conservation,
#   test_gas_boundaries), and test_gas_shear and test_gas_shear_3d (the viscous stress:
#   test_stable_step; the 3-D gas: test_obstacles_3d);
# - gas studies: test_farfield_gauge (141 s under the sanitizers; the gauge and the sponge run
#   there in test_farfield_gauge_ranks), test_mol_damping (131 s; the damping in
#   test_mol_damping_shift), ssprk2's time order test_time_order_gas (31 s; ssprk2 runs there in
#   test_ssprk2_input) and the wedge's particle noise test_gas_noise (32 s; the least-squares wall
#   in test_obstacles, the output field rho_grid in every gas test's snapshots);
# - coupled studies: test_fsi_waves (6 minutes under the sanitizers), test_fsi_reflection,
#   test_fsi_resonator, test_multirate_face, test_prestress and test_bar_in_gas (15-80 s each
#   plain, 140 s instrumented for test_prestress; the initial stress's solve runs there in
#   test_materials and test_bad_input, the interface in test_traction_ls, multirate in
#   test_timeschemes_quick),
#   multirate's coupling-step and predictor study test_multirate_step (63 s there; the damped
#   viscous step and the predictor run in test_timeschemes_quick's restarts), test_piperno_farhat,
#   test_timeschemes and test_timeschemes_mri (9.5 minutes there; test_timeschemes_quick runs
#   every temporal scheme's cycles, checkpoint and restart on 1 and 2 ranks there),
#   test_blowup_guard_coupled (three blow-ups of the main job's scene: the fault it guards
#   against was a segmentation fault, which the plain build sees);
# - solid benchmarks: test_csm1, test_csm3_fast, test_axial_bar, test_cantilever3d,
#   test_model_swap, test_ranks_solid, test_periodic, test_stability, test_disks (test_materials,
#   test_j2, test_kernels_*, test_halo_np*, test_periodic_*, test_ballistic, test_rigid,
#   test_traction, test_restart);
# - decomposition and runs: test_decomposition (11 minutes there with 3 and 4 ranks
#   oversubscribed on 2 cores; test_halo_np*, test_migrate_np*, test_p2g_np*), test_restart_cases
#   (every case's restart, 3 minutes there; test_restart, test_gas_output,
#   test_coupling_ranks) and test_run_safety (output folders, locks, signals: test_restart,
#   test_output);
# - refinement studies: test_refine_gas_pulse, test_refine_gas_uniform3d and
#   test_refine_gas_dynamic (10-25 s each plain; the hierarchy, the grid pressure, splits,
#   merges and regrids run there in test_refine_gas_uniform, _restart, _identity, test_span and
#   test_hier_*), the classic update's studies test_refine_usl_{pulse,sod,wall} and
#   test_refine_musl_{pulse,sod,wall,regrid} (its transfer, remap and regrids run there in
#   test_refine_usl_uniform, _regrid and test_refine_musl_uniform), the gas beside a solid's
#   pulse studies test_refine_fsi_pulse, _pulse_usl and _traction (its coupling on every level
#   in test_refine_fsi_rest and _restart), the open faces' test_refine_open_stream and _shock
#   (in test_refine_open_farfield and _ranks) and the obstacles' test_refine_obstacles_disc and
#   _rest3d (in test_refine_obstacles_rest and _stream), the ranks' comparisons
#   test_refine_ranks_static and _dynamic (the levels over ranks in test_hier_ranks,
#   test_refine_ranks_obstacles and test_refine_gas_ranks), the bodies in a box
#   test_refine_body_rest and _sphere (in _pulse and _input), the expansion settings on the levels
#   test_refine_gas_refill (2.5 minutes there; refill, merges and the neighbourhood step on level 1
#   run there in test_refine_fsi_bar);
# - test_euler_reference: the inviscid aerofoil reference in numpy, which runs no mpmfsi at all.
# The input refusal drivers (test_input_safety, test_bad_input, test_cases) run under the
# sanitizers without the leak check at exit (NO_LEAK_CHECK in tests/CMakeLists.txt).
# Idempotent.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
PLAIN_ONLY="wedge|forward_step|supersonic_bar|supersonic_bar_standoff|supersonic_bar_bs32"
PLAIN_ONLY+="|near_vacuum_order"
PLAIN_ONLY+="|slanted_wall|bluff_bodies|sod|strong_shock|gas_time_order|gas_shear|gas_shear_3d"
PLAIN_ONLY+="|farfield_gauge|mol_damping|time_order_gas|gas_noise|multirate_step"
PLAIN_ONLY+="|fsi_waves|fsi_reflection|fsi_resonator|multirate_face|prestress|bar_in_gas"
PLAIN_ONLY+="|piperno_farhat|timeschemes|timeschemes_mri|blowup_guard_coupled"
PLAIN_ONLY+="|csm1|csm3_fast|axial_bar|cantilever3d|model_swap|ranks_solid|periodic|stability|disks"
PLAIN_ONLY+="|decomposition|restart_cases|run_safety|euler_reference"
PLAIN_ONLY+="|refine_gas_pulse|refine_gas_uniform3d|refine_gas_dynamic"
PLAIN_ONLY+="|refine_usl_pulse|refine_usl_sod|refine_usl_wall|refine_musl_pulse|refine_musl_sod"
PLAIN_ONLY+="|refine_musl_wall|refine_musl_regrid|refine_fsi_pulse|refine_fsi_pulse_usl"
PLAIN_ONLY+="|refine_fsi_traction"
PLAIN_ONLY+="|refine_open_stream|refine_open_shock|refine_obstacles_disc|refine_obstacles_rest3d"
PLAIN_ONLY+="|refine_ranks_static|refine_ranks_dynamic|refine_body_rest|refine_body_sphere"
PLAIN_ONLY+="|refine_gas_refill"
BOTH="checkpoint_integrity"

# The tests also need clang-format (test_format) and ParaView under Xvfb (test_paraview), and
# both builds treat warnings as errors, as a reviewer would.
export MPMFSI_EXTRA_PACKAGES="clang-format paraview xvfb xauth"
bash "$src/tools/setup.sh" "$src/build" -DMPMFSI_WERROR=ON
(cd "$src/build" &&
  ctest -LE "long|benchmark" -R "^test_(${PLAIN_ONLY}|${BOTH})$" --output-on-failure -j 2 \
    --timeout 900 && ctest -L unit --output-on-failure -j 2)
# -O2 (asserts on): the sanitizers instrument every access at any level, and -O2 keeps the
# pass short: test_regularise takes 38 s against 53 s at -O1 and 88 s at -O0.
bash "$src/tools/setup.sh" "$src/build-asan" -DMPMFSI_SANITIZE=ON -DMPMFSI_WERROR=ON -DCMAKE_BUILD_TYPE=Debug \
  "-DCMAKE_C_FLAGS_DEBUG=-g -O2"
(cd "$src/build-asan" &&
  ctest -LE "long|benchmark" -E "^test_(${PLAIN_ONLY})$" --output-on-failure -j 2 --timeout 1800)
