# Output layer: snapshots, the XDMF index and checkpoints, on 1, 2 and 3 ranks (with a
# refinement hierarchy on one rank: its levels and the particles' level; refused on more). Each run
# writes under its own directory, which tools/check_snapshot.py then inspects (a fixture,
# so the check runs after the test that produced the files and is skipped if it failed).
foreach(np 1 2 3)
  if(np EQUAL 1)
    set(name test_output)
    set(ranks "")
    set(labels unit)
  else()
    set(name test_output_np${np})
    set(ranks RANKS ${np})
    set(labels unit mpi)
  endif()
  set(dir ${CMAKE_CURRENT_BINARY_DIR}/${name}_files)
  if(np EQUAL 1)
    mpm_add_test(${name} SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/unit/test_output.c
                 LABELS ${labels} ARGS ${dir} TIMEOUT 120)
  else()
    mpm_add_test(${name} EXE test_output LABELS ${labels} ${ranks} ARGS ${dir} TIMEOUT 120)
  endif()
  set_tests_properties(${name} PROPERTIES FIXTURES_SETUP ${name}_files)
  mpm_add_script_test(check_snapshot_${name} SCRIPT ../tools/check_snapshot.py
                      LABELS ${labels} ARGS ${dir}/snap2d ${dir}/snap3d TIMEOUT 60)
  set_tests_properties(check_snapshot_${name} PROPERTIES FIXTURES_REQUIRED ${name}_files)
endforeach()

# The XDMF indexes in the form ParaView's readers need (run in ParaView too where pvpython is).
mpm_add_script_test(test_xdmf_paraview SCRIPT verification/test_xdmf_paraview.py
                    LABELS "conformance;mpi" TIMEOUT 120)
