# The gas on a static refinement hierarchy (docs/refinement.md): a uniform stream across a
# level-1 box and an acoustic pulse through it against their uniform twins (~25 s each), every
# refusal of the slice (~12 s), and refine.levels = 1 against no [refine] section (~2 s).
foreach(part uniform pulse input identity)
  mpm_add_script_test(test_refine_gas_${part} SCRIPT verification/test_refine_gas.py ARGS ${part}
                      LABELS verification TIMEOUT 300)
endforeach()
