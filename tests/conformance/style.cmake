# What a reviewer checks besides the physics: the formatting of every C file (the -Werror
# build is tools/run_tests.sh's; the key reference's currency is test_keys in cli.cmake).
mpm_add_script_test(test_format SCRIPT conformance/test_format.py LABELS conformance TIMEOUT 120)
