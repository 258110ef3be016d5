#!/usr/bin/env bash
# The README's test command on a busy machine: runs tools/run_tests.sh N times in a row (default
# 3) while the main job (cases/supersonic_bar.ini, 2 ranks) runs over and over beside it, and
# writes one row per pass to out/loaded/passes.csv (pass, exit code, minutes, load average). A
# test that fails only here is a defect of the test (a timing assumption or too short a
# TIMEOUT), not of the machine. Build first (tools/setup.sh build) so the load can start at once.
#   bash tools/run_tests_loaded.sh [N]
set -uo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
n=${1:-3}
out=$src/out/loaded
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
bash "$src/tools/setup.sh" "$src/build" >/dev/null
(
  trap 'kill -TERM $job 2>/dev/null; wait; exit 0' TERM
  while :; do
    mpiexec -n 2 "$src/build/app/mpmfsi" run "$src/cases/supersonic_bar.ini" \
      "output.dir=$out/main_job" output.overwrite=true run.progress=off >"$out/main_job.log" 2>&1 &
    job=$!
    wait $job
  done
) &
load=$!
trap 'kill -TERM $load 2>/dev/null; wait $load 2>/dev/null' EXIT
echo "pass,exit,minutes,load_average" >"$out/passes.csv"
status=0
for i in $(seq 1 "$n"); do
  start=$(date +%s)
  bash "$src/tools/run_tests.sh" >"$out/pass$i.log" 2>&1
  rc=$?
  minutes=$(awk -v s="$start" -v e="$(date +%s)" 'BEGIN { printf "%.1f", (e - s) / 60 }')
  echo "$i,$rc,$minutes,$(cut -d' ' -f1-3 /proc/loadavg | tr ' ' '/')" >>"$out/passes.csv"
  echo "pass $i: exit $rc in $minutes min (log: $out/pass$i.log)"
  [ $rc -eq 0 ] || status=1
done
exit $status
