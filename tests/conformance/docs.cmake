# The README and the user guide: the README's length and its two commands near the top, CI
# calling the README's test command, and every relative link and #anchor in README.md,
# docs/*.md, CHANGELOG.md and bench/results/*.md resolving (reads the source tree only).
mpm_add_script_test(test_docs SCRIPT conformance/test_docs.py LABELS conformance TIMEOUT 60)
