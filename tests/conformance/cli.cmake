# The command line and the key reference (app/main.c, app/cli_help.c, app/cli_keys.c):
# conventional help and version, and docs/keys.md equal to `mpmfsi keys --markdown`.
# test_cli starts mpmfsi some 30 times, each to its first output only (no leak can accumulate);
# test_keys, which builds the whole schema, keeps the leak check.
mpm_add_script_test(test_cli SCRIPT conformance/test_cli.py LABELS conformance TIMEOUT 120 NO_LEAK_CHECK)
mpm_add_script_test(test_keys SCRIPT conformance/test_keys.py LABELS conformance TIMEOUT 120)
