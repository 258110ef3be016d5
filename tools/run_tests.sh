#!/usr/bin/env bash
# Install, build and run the default test selection (everything but the `long` and
# `benchmark` labels), then the same selection again in a build with AddressSanitizer,
# LeakSanitizer and UBSan, less the two gas flow cases (test_wedge, test_forward_step: 7 minutes
# under the sanitizers, 33 s without), the coupled wave cases (test_fsi_waves: 6 minutes under
# the sanitizers) and test_decomposition (11 minutes under the sanitizers with 3 and 4 ranks
# oversubscribed on 2 cores, 20 s without; the halo, migration and P2G on 1-4 ranks run under the
# sanitizers in test_halo_np*, test_migrate_np*, test_p2g_np* and test_ranks_solid), the main
# job's scene (test_supersonic_bar, a flow case like the wedge; its rigid twin is `long`) and the
# near-vacuum convergence
# study (test_near_vacuum_order; test_near_vacuum runs the refill and the shifting there),
# and test_restart_cases (every case's restart: 3 minutes under the sanitizers; the checkpoint
# code it runs is test_restart's, test_gas_output's and test_coupling_ranks', which do run there).
# Also left to the plain pass are physics studies whose code other tests run under the
# sanitizers (1-4 minutes each there): the solid benchmarks test_csm1, test_csm3_fast,
# test_axial_bar, test_cantilever3d, test_model_swap, test_ranks_solid, test_periodic and
# test_stability (their materials, kernels, halos and wraps: test_materials, test_j2,
# test_kernels_*, test_halo_np*, test_periodic_*, test_ballistic, test_rigid, test_traction)
# and the gas tubes test_sod and test_strong_shock (the same gas path as test_gas_output,
# test_gas_conservation and test_gas_boundaries), and the ERK pairs' time-order study
# test_gas_time_order (its current-strain-rate path runs there in every bs32 gas test). The temporal-coupling studies test_piperno_farhat
# and test_timeschemes (1-2 minutes each in the plain pass; test_timeschemes_mri 3 minutes, 9.5
# under the sanitizers) run there as test_timeschemes_quick: every temporal scheme's held, loaded
# and joint cycles and MRIStep's, checkpoint and restart, on 1 and 2 ranks.
# The code they run is the open faces', the obstacles', the gas module's and the coupler's, which
# test_gas_boundaries, test_obstacles, test_sod, test_coupling, test_coupling_ranks and
# test_coupling_rigid run under the sanitizers. Also left to the plain pass (2-3 minutes each
# under the sanitizers): test_run_safety (output folders, locks, signals, restarts into new
# folders: the checkpoint and folder code runs there in test_restart and test_output), test_disks
# (its multi-body solid and restart run there in test_restart) and test_gas_shear (the viscous
# stress runs there in test_gas_conservation and test_stable_step), and
# test_blowup_guard_coupled (three blow-ups of the main job's scene inside a coupling step, 3
# minutes under the sanitizers: the fault it guards against was a segmentation fault, which the
# plain pass sees; the held and loaded cycles run there in test_timeschemes_quick). The input
# refusal drivers (test_input_safety, test_bad_input, test_cases) run there without the leak
# check at exit (NO_LEAK_CHECK in tests/CMakeLists.txt). The wall-treatment flow cases
# test_slanted_wall, test_slanted_wall_max and test_bluff_bodies (45-100 s
# each under the sanitizers, 5-14 s without) stay in the plain pass too: the least-squares fit,
# its moments, halo exchanges and heat run under the sanitizers in test_obstacles and
# test_obstacles_energy (slip and no-slip, usl and musl, 1 and 2 ranks). Idempotent.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
bash "$src/tools/setup.sh" "$src/build"
(cd "$src/build" && ctest -LE "long|benchmark" --output-on-failure -j 2 --timeout 900)
# -O2 (asserts on): the sanitizers instrument every access at any level, and the pass is what
# keeps CI near 20 minutes: test_regularise takes 38 s against 53 s at -O1 and 88 s at -O0.
bash "$src/tools/setup.sh" "$src/build-asan" -DMPMFSI_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug \
  "-DCMAKE_C_FLAGS_DEBUG=-g -O2"
(cd "$src/build-asan" &&
  ctest -LE "long|benchmark" -E "^test_(blowup_guard_coupled|wedge|forward_step|fsi_waves|decomposition|supersonic_bar|supersonic_bar_standoff|near_vacuum_order|restart_cases|csm1|csm3_fast|axial_bar|cantilever3d|model_swap|ranks_solid|periodic|stability|sod|strong_shock|gas_time_order|piperno_farhat|timeschemes|timeschemes_mri|run_safety|disks|gas_shear|slanted_wall|slanted_wall_max|bluff_bodies)$" \
    --output-on-failure -j 2 --timeout 1800)
