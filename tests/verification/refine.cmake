# The gas on a refinement hierarchy (docs/refinement.md): a uniform stream across a static
# level-1 box and an acoustic pulse through it against their uniform twins (~10 and ~20 s), the
# uniform stream in 3-D (~12 s), a pulse refined dynamically (~25 s), the compression and
# vorticity criteria (~4 s each), the starvation criterion alone and with compression on an
# expanding gas (~8 s), a restart (~5 s), every refusal (~15 s), levels across periodic faces
# (static ~5 s, regridded ~5 s), and
# refine.levels = 1 against no [refine] section (~2 s); the first two again with fluid.ppc = 4
# (long).
foreach(part uniform pulse uniform3d dynamic compression vorticity starvation restart input
             identity periodic wrap)
  mpm_add_script_test(test_refine_gas_${part} SCRIPT verification/test_refine_gas.py ARGS ${part}
                      LABELS verification TIMEOUT 300)
endforeach()
# The grid pressure on 1 and 2 ranks (~5 s).
mpm_add_script_test(test_refine_gas_ranks SCRIPT verification/test_refine_gas.py ARGS ranks
                    LABELS "verification;mpi" TIMEOUT 300)
# The gas's hierarchy on 2 ranks against 1 (fixed steps): a pulse through a static box and a
# stream through a band and a box on the floor (~15 s); the regridded pulse under bs32 and usl,
# its levels' output, the particles per rank, and a restart on 2 ranks across a regrid (~15 s);
# the obstacle scenes at rest on 2 and 3 levels, the disc in a stream and the proximity regrid,
# their forces and surface pressures too (~25 s); a solid alone, a slab in a band beside a gas
# (static and regridded) and a disk in a box with the grid pressure (~25 s).
foreach(part static dynamic obstacles solid)
  mpm_add_script_test(test_refine_ranks_${part} SCRIPT verification/test_refine_ranks.py
                      ARGS ${part} LABELS "verification;mpi" TIMEOUT 300)
endforeach()
# The gas's expansion settings on the levels (refill, light merges, merges and splits by count,
# the neighbourhood step): a centre expanding inside a level-1 box keeps every level-1 span
# filled (emptied without the refill), conserves, and gives the same particles on 2 ranks as
# on 1 (~35 s).
mpm_add_script_test(test_refine_gas_refill SCRIPT verification/test_refine_gas.py ARGS refill
                    LABELS "verification;mpi" TIMEOUT 600)
# The refined output (issue 51 item 6): levels in the snapshots and the XDMF index, the
# particle level, the per-level counts, the timers, ParaView opening it when pvpython is there
# (~8 s).
mpm_add_script_test(test_refine_gas_output SCRIPT verification/test_refine_gas.py ARGS output
                    LABELS verification TIMEOUT 300)
foreach(part uniform pulse)
  mpm_add_script_test(test_refine_gas_${part}_ppc4 SCRIPT verification/test_refine_gas.py
                      ARGS ${part} 4 LABELS verification long TIMEOUT 300)
endforeach()
# The solid on a static hierarchy (issue 51): an elastic pulse along a bar crossing a level-1
# box against its uniform twins, with the grid sums (~4 s), and under usl (~2 s); a block
# translating across the box (~1 s); a prestressed block with a box inside it (~2 s); a
# restart (~3 s); every refusal (~3 s); a pulse reflecting from a wall inside a box (~4 s); a
# clamped bar on a wall on 2 and 3 levels against its uniform twins (~6 s).
foreach(part wave stream prestress usl restart input walls clamp)
  mpm_add_script_test(test_refine_solid_${part} SCRIPT verification/test_refine_solid.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
# Sod with a fine region following the waves against its uniform twin at the finest spacing
# (issue 51's acceptance, L1 within 10 %): 2 levels (~3 s); 3 levels under long (~15 s); the
# cost bar's settings, 4 levels under usl (~15 s).
mpm_add_script_test(test_refine_sod SCRIPT verification/test_refine_sod.py LABELS verification
                    TIMEOUT 300)
mpm_add_script_test(test_refine_sod_cost SCRIPT verification/test_refine_sod.py ARGS cost
                    LABELS verification TIMEOUT 600)
mpm_add_script_test(test_refine_sod_long SCRIPT verification/test_refine_sod.py ARGS long
                    LABELS "verification;long" TIMEOUT 600)
# Finer levels at slip and no-slip walls (the gas): gas at rest in a closed box refined in its
# corner (~3 s), a uniform stream along the walls through a band touching them (~4 s), an
# acoustic pulse reflecting from a slip wall in a band against its uniform twins (~5 s), the
# regridded pulse whose regions reach the walls, on 2 and 3 levels (~9 s); the stream part also
# runs in 3-D (~4 s).
foreach(part rest stream pulse dynamic)
  mpm_add_script_test(test_refine_walls_${part} SCRIPT verification/test_refine_walls.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
# Open faces with the gas on the hierarchy (level 0 alone reaches them): a uniform stream
# through inflow | outflow and subsonic faces across static level-1 and level-2 boxes (~15 s),
# through farfield faces with a sponge in 2-D and 3-D (~15 s), a Mach 3 shock entering through
# the inflow face across a regridded region against its uniform twins, with a restart (~10 s);
# the grid pressure through farfield faces on 1 and 2 ranks (~5 s).
foreach(part stream farfield shock)
  mpm_add_script_test(test_refine_open_${part} SCRIPT verification/test_refine_open.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
mpm_add_script_test(test_refine_open_ranks SCRIPT verification/test_refine_open.py ARGS ranks
                    LABELS "verification;mpi" TIMEOUT 300)
# A gas beside a solid on a static hierarchy (the coupling on every level): gas and a
# prestressed slab at rest across a level-1 band (~5 s), an acoustic pulse striking the slab
# inside the band against the impedance solution and the uniform twins (~30 s), both again
# under usl (~3 s, ~12 s) and refined under coupling.scheme = traction (~20 s), a restart
# (~10 s), regrids beside the slab (~25 s), every refusal (~5 s), the main job's scene on two
# levels to 1 ms (~15 s).
foreach(part rest pulse rest_usl pulse_usl traction restart regrid input bar)
  mpm_add_script_test(test_refine_fsi_${part} SCRIPT verification/test_refine_fsi.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
# A body inside a refined gas (fluid.pressure = grid beside a solid): a disk at rest in a level-1
# box to t = 1, on the uniform grid, and the slab at rest on it (~15 s), a sphere at rest in 3-D
# (~15 s), a pulse striking the disk, refined and its uniform twins (~6 s), the refusals (~3 s).
foreach(part rest sphere pulse input)
  mpm_add_script_test(test_refine_body_${part} SCRIPT verification/test_refine_body.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
# The classic update (time.method = usl, then musl) on the hierarchy (the gas): gas at rest and
# a uniform stream across static level-1 and level-2 boxes at the walls, FLIP, a PIC share and
# APIC (~10 s); the acoustic pulse crossing a box against its coarse twin (~8 s); Sod with a
# regridded fine region against its uniform twin (~5 s); a pulse reflected from a wall in a
# level-1 band against its fine twin (~8 s); conservation through regrids and a restart (~8 s).
foreach(method usl musl)
  foreach(part uniform pulse sod wall regrid)
    mpm_add_script_test(test_refine_${method}_${part} SCRIPT verification/test_refine_usl.py
                        ARGS ${part} ${method} LABELS verification TIMEOUT 300)
  endforeach()
endforeach()
# Sod over 4 levels whose regrids refine by up to three levels at once: the particles follow
# their new levels at the regrid (~7 s).
mpm_add_script_test(test_refine_usl_follow SCRIPT verification/test_refine_usl.py
                    ARGS follow usl LABELS verification TIMEOUT 300)
# Static obstacles on every level (the gas): gas at rest around a circle and a box's corner in
# refined boxes, on 2 and 3 levels (~4 s); a uniform stream along a slab's face through bands
# over it and its uniform twin (~6 s); a stream past a circle in a band against its aligned fine
# twin (~8 s); the bodies regridded by the proximity criterion (~4 s).
foreach(part rest stream disc rest3d proximity)
  mpm_add_script_test(test_refine_obstacles_${part} SCRIPT verification/test_refine_obstacles.py
                      ARGS ${part} LABELS verification TIMEOUT 300)
endforeach()
# The 3-D sphere at Mach 0.8 (cases/sphere_m08.ini) at 20^3 level-0 cells for 3 steps: the case
# runs on its three levels, keeps its mass and its symmetry, and the sphere feels the stream
# (~5 s). Its cost and stability at full size: bench/bench_sphere.py.
mpm_add_script_test(test_refine_sphere_smoke SCRIPT verification/test_refine_sphere.py
                    LABELS verification TIMEOUT 300)
