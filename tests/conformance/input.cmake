# Input safety: every case's resolved text reads back to itself (and a case with obstacles
# restarts), a key twice on the command line, incomplete sections from the command line,
# a self-crossing solid outline, devices/FIFOs/huge files as cases, non-finite field
# expressions, and garbage (capped errors).
mpm_add_script_test(test_input_safety SCRIPT conformance/test_input_safety.py
                    LABELS conformance TIMEOUT 300 NO_LEAK_CHECK)
