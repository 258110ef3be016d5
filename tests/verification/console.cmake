# What a user sees while and after a run: run.log (start-up to summary, appended on restart),
# the refined step estimate, no \r in a non-terminal console, the live line under a terminal
# (through `script`) with mpiexec, plural ranks, the coupling energy with its scale.
mpm_add_script_test(test_console SCRIPT verification/test_console.py
                    LABELS "verification;mpi" TIMEOUT 300)
