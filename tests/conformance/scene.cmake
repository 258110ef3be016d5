# Scene errors: a solid overlapping the gas or another solid, refused by check and run with both
# names on 1 and 2 ranks; touching bodies accepted; any [coupling] key in a one-phase scene
# refused naming the key.
mpm_add_script_test(test_scene SCRIPT conformance/test_scene.py LABELS conformance mpi
                    TIMEOUT 300 NO_LEAK_CHECK)
