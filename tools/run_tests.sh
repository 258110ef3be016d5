#!/usr/bin/env bash
# Install, build and run the default test selection (everything but the `long` and
# `benchmark` labels), then the same selection again in a build with AddressSanitizer,
# LeakSanitizer and UBSan. Idempotent.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
bash "$src/tools/setup.sh" "$src/build"
(cd "$src/build" && ctest -LE "long|benchmark" --output-on-failure -j 2 --timeout 900)
bash "$src/tools/setup.sh" "$src/build-asan" -DMPMFSI_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug
(cd "$src/build-asan" && ctest -LE "long|benchmark" --output-on-failure -j 2 --timeout 1800)
