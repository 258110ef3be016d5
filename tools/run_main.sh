#!/usr/bin/env bash
# Install, build and run the main job: Mach 2.5 air over a soft elastic bar
# (cases/supersonic_bar.ini) on 2 MPI ranks, then draw its density strip and its tip and
# force histories (tools/supersonic_bar.py). Extra arguments are passed to mpmfsi as
# key=value overrides, e.g. grid.dx=0.001 to refine, or output.dir=out/bar_fine.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
bash "$src/tools/setup.sh" "$src/build"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
cd "$src"
out=out/supersonic_bar
# Running the main job again replaces its earlier results (output.overwrite=true), unless the
# command line says otherwise.
overwrite=output.overwrite=true
for arg in "$@"; do
  case "$arg" in
    output.dir=*) out=${arg#output.dir=} ;;
    output.overwrite=*) overwrite= ;;
  esac
done
mpiexec -n 2 "$src/build/app/mpmfsi" run "$src/cases/supersonic_bar.ini" ${overwrite:+"$overwrite"} "$@"
/usr/bin/python3 "$src/tools/supersonic_bar.py" "$out"
echo "output: $src/$out (series.xmf for ParaView; density_strip.png, tip.png, force.png)"
