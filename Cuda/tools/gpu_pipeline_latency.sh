#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The edit latency through ParaView with Backend = CUDA: Benchmarks/pipeline_latency.py on a GPU
# host, alternating Backend = CUDA and = CPU on the ~100k shell scene (--shell-only); fails when the
# CUDA run did not run on CUDA (pipeline_latency.py checks the filter's Backend field).
# On a host with ParaView and a FacePlan build with the plugin and CUDA:
#   OUT=<dir> [FACEPLAN_BUILD_DIR=build] Cuda/tools/gpu_pipeline_latency.sh run [ROUNDS] [EDITS]
# A GPU host without ParaView runs Debian's pvpython from a pack of the files it opens
# (paraview_pack.sh), with the plugin beside:
#   Cuda/tools/gpu_pipeline_latency.sh pack      -> out/pvpython-pack.tar.xz, out/pvpython-plugin/
#          (pack --stage-only: only the files, in /tmp/pvpython-pack, to try them first)
#   OUT=<dir> PACK=out/pvpython-pack.tar.xz PLUGIN_DIR=out/pvpython-plugin \
#     Cuda/tools/gpu_pipeline_latency.sh run [ROUNDS] [EDITS]
# BASELINE_PLUGIN_DIR=<dir> (a plugin folder of another commit, as pack makes it) runs beside, in
# the same rounds in alternating order, and the summary gives each round's pair and the median
# ratio: this host's speed differs from one process to the next, so only such pairs compare builds.
set -uo pipefail
. "$(dirname "$0")/paraview_pack.sh"
cd "$(dirname "$0")/../.."

pack() {
  local build=${FACEPLAN_BUILD_DIR:-build} stage=/tmp/pvpython-pack
  local plugin
  plugin=$(pack_find_plugin "with the plugin and CUDA") || return 1
  mkdir -p out/pipeline_latency
  [ -f out/pipeline_latency/shell100k.vtk ] ||
    "$build/bin/export_shell_scene" --subdivisions 18 --layers 5 --out out/pipeline_latency/shell100k.vtk
  # Record every file this very run opens (CPU backend: the Python side is the same for CUDA).
  strace -f -e trace=openat,open -o /tmp/pvpython.trace pvpython --no-mpi Benchmarks/pipeline_latency.py \
    --plugin "$plugin" --data "$PWD/Data" --shell-scene out/pipeline_latency/shell100k.vtk --edits 2 \
    --shell-only >/dev/null 2>&1 || { echo "the traced pvpython run failed"; return 1; }
  pack_stage /tmp/pvpython.trace "$stage"
  cp -L "$(command -v pvpython)" "$stage/usr/bin/pvpython" # the executable is not opened by openat
  cp out/pipeline_latency/shell100k.vtk "$stage/"
  [ "${1:-}" = --stage-only ] && return 0 # to try the staged files first
  rm -rf out/pvpython-plugin && mkdir -p out/pvpython-plugin
  cp "$plugin" "$(dirname "$plugin")/libFacePlanFilters.so" out/pvpython-plugin/
  pack_write "$stage" out/pvpython-pack.tar.xz
  ls -l out/pvpython-plugin
}

run() {
  local out=${OUT:-/tmp/faceplan-pipeline-latency} rounds=${1:-3} edits=${2:-30}
  local pvpython plugin scene build=${FACEPLAN_BUILD_DIR:-build}
  mkdir -p "$out"
  if [ -n "${PACK:-}" ]; then
    pack_unpack "$PACK" "$ROOT" || return 1
    pack_environment "$ROOT" "$PLUGIN_DIR"
    pvpython=$ROOT/usr/bin/pvpython plugin=$PLUGIN_DIR/FacePlan.so scene=$ROOT/shell100k.vtk
  else
    pvpython=$(command -v pvpython) || { echo "no pvpython: set PACK (see the header)"; return 1; }
    plugin=$(pack_find_plugin "with the plugin and CUDA") || return 1
    scene=out/pipeline_latency/shell100k.vtk
    mkdir -p out/pipeline_latency
    [ -f "$scene" ] || "$build/bin/export_shell_scene" --subdivisions 18 --layers 5 --out "$scene"
  fi
  export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
  if ldd "$pvpython" "$plugin" | grep "not found"; then
    echo "missing libraries"
    return 1
  fi
  { nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; } >"$out/machine.txt" 2>&1
  local status=0 round backend variant dir tag
  for round in $(seq 1 "$rounds"); do
    for backend in CUDA CPU; do
      for variant in $(pack_variants "$round"); do
        dir=$(dirname "$plugin") tag=${backend}_r$round
        [ "$variant" = baseline ] && dir=$BASELINE_PLUGIN_DIR tag=${backend}_r${round}_baseline
        LD_LIBRARY_PATH=$dir:${LD_LIBRARY_PATH:-} "$pvpython" --no-mpi Benchmarks/pipeline_latency.py \
          --plugin "$dir/FacePlan.so" --data "$PWD/Data" --shell-scene "$scene" --shell-only \
          --edits "$edits" --backend "$backend" --json "$out/pipeline_latency_$tag.json" 2>&1 |
          grep -v 'WARN|' | sed "s/^/[$variant] /" | tee -a "$out/pipeline_latency.txt"
        [ "${PIPESTATUS[0]}" = 0 ] || status=1
      done
    done
  done
  # The host's own Python: the pack's environment (PYTHONHOME) is for its pvpython.
  [ -z "${BASELINE_PLUGIN_DIR:-}" ] || env -u PYTHONHOME -u LD_LIBRARY_PATH python3 - "$out" "$rounds" <<'EOF' | tee -a "$out/pipeline_latency.txt"
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
for backend in ("CUDA", "CPU"):
    pairs = []
    for r in range(1, rounds + 1):
        try:
            a = json.load(open("%s/pipeline_latency_%s_r%d.json" % (out, backend, r)))[0]
            b = json.load(open("%s/pipeline_latency_%s_r%d_baseline.json" % (out, backend, r)))[0]
        except (OSError, ValueError, IndexError):
            continue
        pairs.append((a["fem_update_ms_median"], b["fem_update_ms_median"],
                      a["overhead_ms_median"], b["overhead_ms_median"]))
    if pairs:
        print("%s: Condensed FEM Deform update per round, this / baseline (ms): %s; median ratio "
              "baseline/this %.3f; overhead (update - solve) medians %.2f / %.2f ms" % (
                  backend, ", ".join("%.2f/%.2f" % p[:2] for p in pairs),
                  statistics.median(p[1] / p[0] for p in pairs),
                  statistics.median(p[2] for p in pairs), statistics.median(p[3] for p in pairs)))
EOF
  return $status
}

case "${1:-}" in
  pack) pack "${2:-}" ;;
  run) shift; run "$@" ;;
  *) echo "usage: $0 pack [--stage-only] | run [ROUNDS] [EDITS]"; exit 2 ;;
esac
