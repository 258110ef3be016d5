#!/usr/bin/env bash
# Install, build and run the default test selection (everything but `long` and `benchmark`),
# then the unit tests again under AddressSanitizer and UBSan.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
bash "$src/tools/setup.sh" "$src/build"
cd "$src/build"
ctest -LE "long|benchmark" --output-on-failure -j 2 --timeout 900
bash "$src/tools/setup.sh" "$src/build-asan" -DMPMFSI_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug
cd "$src/build-asan"
# Open MPI's own allocations at MPI_Init are not ours to fix: leak checks cover our code via
# the suppression file.
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 LSAN_OPTIONS=suppressions=$src/tests/lsan.supp \
  ctest -L unit -LE "mpi|long|benchmark" --output-on-failure -j 2
