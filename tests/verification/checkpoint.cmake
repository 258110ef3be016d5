# Checkpoint integrity (tests/verification/test_checkpoint_integrity.py): a bit-flip fuzz of
# small solid and gas-solid checkpoints (every damaged copy refused with exit 2 or restarted
# to exactly the reference state), edits that get past the checksums and must be refused by
# the validation (NaN time, negative mass, duplicate ids, a body index out of range, ...),
# raw edits the checksums must catch, and a write to a full disk (a small tmpfs; skipped
# where mounting is not allowed).
mpm_add_script_test(test_checkpoint_integrity SCRIPT verification/test_checkpoint_integrity.py
                    LABELS verification TIMEOUT 600)
