# Checkpoint integrity (tests/verification/test_checkpoint_integrity.py): a bit-flip fuzz of
# small solid and gas-solid checkpoints (every damaged copy refused with exit 2 or restarted
# to exactly the reference state), edits that get past the checksums and must be refused by
# the validation (NaN time, negative mass, duplicate ids, a body index out of range, ...),
# raw edits the checksums must catch, and a write to a full disk (a small tmpfs; skipped
# where mounting is not allowed).
# Under the sanitizers (4-5 times slower) the fuzz takes 48 copies instead of 240: its purpose
# there is to catch memory errors on damaged input, which the plain build's 240 already probe
# for crashes. Nearly every process here ends at a refusal, so it runs without the leak check at
# exit (NO_LEAK_CHECK); the restarts that run to their end are leak-checked in test_restart.
if(MPMFSI_SANITIZE)
  set(fuzz_copies 48)
else()
  set(fuzz_copies 240)
endif()
mpm_add_script_test(test_checkpoint_integrity SCRIPT verification/test_checkpoint_integrity.py
                    ARGS ${fuzz_copies} LABELS verification TIMEOUT 600 NO_LEAK_CHECK)
