# The gas on a static refinement hierarchy (docs/refinement.md): a uniform stream across a
# level-1 box and an acoustic pulse through it against their uniform twins (~10 and ~20 s), every
# refusal of the slice (~12 s), and refine.levels = 1 against no [refine] section (~2 s); the
# first two again with fluid.ppc = 4 (~25 and ~35 s: long).
foreach(part uniform pulse input identity)
  mpm_add_script_test(test_refine_gas_${part} SCRIPT verification/test_refine_gas.py ARGS ${part}
                      LABELS verification TIMEOUT 300)
endforeach()
# The refined output (issue 51 item 6): levels in the snapshots and the XDMF index, the
# particle level, the per-level counts, the timers, ParaView opening it when pvpython is there
# (~8 s).
mpm_add_script_test(test_refine_gas_output SCRIPT verification/test_refine_gas.py ARGS output
                    LABELS verification TIMEOUT 300)
# The first two with fluid.pressure = grid, which meets their targets (~8 and ~17 s).
foreach(part uniform pulse)
  mpm_add_script_test(test_refine_gas_${part}_grid SCRIPT verification/test_refine_gas.py
                      ARGS ${part} 2 grid LABELS verification TIMEOUT 300)
endforeach()
foreach(part uniform pulse)
  mpm_add_script_test(test_refine_gas_${part}_ppc4 SCRIPT verification/test_refine_gas.py
                      ARGS ${part} 4 LABELS verification long TIMEOUT 300)
endforeach()
