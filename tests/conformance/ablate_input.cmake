# The ablation harness's input (bench/ablate.py): every bad case, key, option or binary refused
# before any run with one line and exit 2; a cut or damaged row of runs.csv never tabulated and
# run again on resume; runs.csv replaced whole; --repeat's medians exact (~10 s; a stand-in for
# mpmfsi makes parts 2-4 independent of the machine's speed).
mpm_add_script_test(test_ablate_input SCRIPT conformance/test_ablate_input.py LABELS conformance
                    TIMEOUT 300)
