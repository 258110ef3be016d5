# Messages that name the key or the real cause (issue 54, item 7): one line for a misspelt
# section, the limit of an instance name, the face a solid particle reached at Mach 50
# (conformance); a restart switching time.method, rhs_evals across a restart, SIGHUP as
# SIGTERM (verification: runs, restarts and a signal). Most runs of test_messages end at a
# refusal, so it runs without the leak check at exit (NO_LEAK_CHECK, as test_bad_input).
mpm_add_script_test(test_messages SCRIPT conformance/test_messages.py LABELS conformance
                    TIMEOUT 300 NO_LEAK_CHECK)
mpm_add_script_test(test_messages_run SCRIPT conformance/test_messages_run.py
                    LABELS verification TIMEOUT 600)
