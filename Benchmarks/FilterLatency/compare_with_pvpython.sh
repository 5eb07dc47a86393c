#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What ParaView's proxy layer adds to the Condensed FEM Deform filter's edit: the shell scene's edit
# timed through pvpython (Benchmarks/pipeline_latency.py --shell-only) and through the VTK-level
# driver (filter_latency), CPU backend, alternated on this machine.
#   Benchmarks/FilterLatency/compare_with_pvpython.sh OUT_DIR [ROUNDS] [EDITS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$1 rounds=${2:-3} edits=${3:-30}
build="${FACEPLAN_BUILD_DIR:-build}"
mkdir -p "$out"
plugin="$(find "$build" -name FacePlan.so -path '*paraview*plugins*' | head -n 1)"
[ -f "$out/shell100k.vtk" ] || "$build/bin/export_shell_scene" --subdivisions 18 --layers 5 --out "$out/shell100k.vtk"
for round in $(seq 1 "$rounds"); do
  pvpython Benchmarks/pipeline_latency.py --plugin "$plugin" --data "$PWD/Data" --shell-only \
    --shell-scene "$out/shell100k.vtk" --edits "$edits" --json "$out/pvpython_r$round.json" 2>&1 | grep -v 'WARN|'
  "$build/bin/filter_latency" --scene "$out/shell100k.vtk" --backend CPU --edits "$edits" \
    --json "$out/vtk_r$round.json" 2>&1 | grep -v 'WARN|'
done
