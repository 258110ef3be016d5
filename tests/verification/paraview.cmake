# The main job as a ParaView 5.11 user meets it (tests/verification/test_paraview.py): a short
# run (dx = 4 mm to 1.5 ms, 2 ranks), opened with the default XDMF reader in pvpython under
# xvfb-run; the reader alone must not draw one uniform colour, and the run folder's view.py
# (tools/paraview_view.py) must show the bar and the bow shock. Fails, naming the package,
# without pvpython (paraview) or xvfb-run (xvfb).
mpm_add_script_test(test_paraview SCRIPT verification/test_paraview.py
                    LABELS "verification;mpi" TIMEOUT 600)
set_tests_properties(test_paraview PROPERTIES PROCESSORS 2)
