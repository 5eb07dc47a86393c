#!/usr/bin/env bash
# Issue 14 §1 with Backend = CUDA, measured through ParaView: Benchmarks/pipeline_latency.py run by
# Debian's pvpython on the lent GPU machine, which has no ParaView. The files pvpython opens for that
# run (found with strace here, less the C runtime the GPU machine has) travel with it: ~140 MB
# compressed, more than one call may carry (64 MiB), so they go in parts over successive calls while
# the machine is warm (30 s), each part appended to /tmp/pvpython.tar.xz there.
#
#   here:  Cuda/tools/gpu_pipeline_latency.sh pack          -> .pvcarry/part-*, .pvcarry/plugin/
#          (pack --stage-only: only the files, in /tmp/pvpython-pack, to try them here)
#   there: Cuda/tools/gpu_pipeline_latency.sh receive part-aa   (one call per part, in order, each
#          carrying only its part: carry [".pvcarry/part-aa"]; the last also ".pvcarry/plugin")
#   there: OUT=<dir> Cuda/tools/gpu_pipeline_latency.sh run [ROUNDS] [EDITS]
#
# `run` alternates Backend = CUDA and = CPU on the ~100k shell scene (--shell-only) and fails when the
# CUDA run did not run on CUDA (pipeline_latency.py checks the filter's Backend field).
set -uo pipefail
cd "$(dirname "$0")/../.."
PART_BYTES=$((40 * 1024 * 1024)) # with the working tree under the 64 MiB a call carries
ROOT=/tmp/pvroot

pack() {
  local build=${FACEPLAN_BUILD_DIR:-build} stage=/tmp/pvpython-pack
  local plugin
  plugin=$(find "$build" -name FacePlan.so -path '*paraview*plugins*' | head -n 1)
  [ -n "$plugin" ] || { echo "no FacePlan.so under $build: build with the plugin and CUDA first"; return 1; }
  mkdir -p out/pipeline_latency
  [ -f out/pipeline_latency/shell100k.vtk ] ||
    "$build/bin/export_shell_scene" --subdivisions 18 --layers 5 --out out/pipeline_latency/shell100k.vtk
  # Record every file this very run opens (CPU backend: the Python side is the same for CUDA).
  strace -f -e trace=openat,open -o /tmp/pvpython.trace pvpython --no-mpi Benchmarks/pipeline_latency.py \
    --plugin "$plugin" --data "$PWD/Data" --shell-scene out/pipeline_latency/shell100k.vtk --edits 2 \
    --shell-only >/dev/null 2>&1 || { echo "the traced pvpython run failed"; return 1; }
  rm -rf "$stage" && mkdir -p "$stage/usr/lib/x86_64-linux-gnu" "$stage/usr/bin"
  # realpath -s: /usr/bin/../lib/x.so (pvpython's RUNPATH) becomes /usr/lib/x.so, links kept.
  grep -v ENOENT /tmp/pvpython.trace | grep -oE '"/[^"]+"' | tr -d '"' | xargs realpath -s | sort -u |
    grep -vE '^/(work|tmp|proc|sys|dev|etc|usr/local/cuda)/' |
    grep -vE '/(libc|libm|libpthread|libdl|librt|libresolv|libstdc\+\+|libgcc_s)\.so|/ld-linux|/libnss_|nvidia|/libcuda\.|-nspkg\.pth$' |
    while read -r f; do
      [ -f "$f" ] || continue
      case "$f" in
        */__pycache__/*.pyc) # Python uses a cached module only beside its source, same mtime
          local src
          src="$(dirname "$(dirname "$f")")/$(basename "$f" | sed 's/\.cpython-[0-9]*\.pyc$//').py"
          mkdir -p "$stage/usr$(dirname "${f#/usr}")"
          cp -L --preserve=timestamps "$f" "$stage/usr${f#/usr}"
          [ -f "$src" ] && cp -L --preserve=timestamps "$src" "$stage/usr${src#/usr}" ;;
        */python3*/*|/usr/bin/*) # kept in place: Python finds modules by path
          mkdir -p "$stage/usr$(dirname "${f#/usr}")"
          cp -L --preserve=timestamps "$f" "$stage/usr${f#/usr}" ;;
        *.so|*.so.*) # by the name the loader asked for, where Debian keeps it (VTK finds its
          # Python packages relative to its libraries)
          cp -L "$f" "$stage/usr/lib/x86_64-linux-gnu/$(basename "$f")" ;;
        *) mkdir -p "$stage/usr$(dirname "${f#/usr}")" && cp -L "$f" "$stage/usr${f#/usr}" ;;
      esac
    done
  cp -L "$(command -v pvpython)" "$stage/usr/bin/pvpython" # the executable is not opened by openat
  cp out/pipeline_latency/shell100k.vtk "$stage/"
  [ "${1:-}" = --stage-only ] && return 0 # to try the staged files here first
  rm -rf .pvcarry && mkdir -p .pvcarry/plugin
  cp "$plugin" "$(dirname "$plugin")/libFacePlanFilters.so" .pvcarry/plugin/
  tar -C "$stage" -cf - . | xz -T2 -9 | split -b "$PART_BYTES" - .pvcarry/part-
  ls -l .pvcarry .pvcarry/plugin
}

receive() { # $1: the part this call carried (an earlier call's part may still lie there)
  [ -f ".pvcarry/$1" ] || { echo "no .pvcarry/$1"; return 1; }
  [ "$1" = part-aa ] && rm -f /tmp/pvpython.tar.xz
  cat ".pvcarry/$1" >>/tmp/pvpython.tar.xz && rm -f ".pvcarry/$1"
  echo "received $1; /tmp/pvpython.tar.xz is $(stat -c %s /tmp/pvpython.tar.xz) bytes"
}

run() {
  local out=${OUT:-/tmp/faceplan-pipeline-latency} rounds=${1:-3} edits=${2:-30}
  mkdir -p "$out"
  rm -rf "$ROOT" && mkdir -p "$ROOT"
  xz -dc /tmp/pvpython.tar.xz | tar -xf - -C "$ROOT" || { echo "the pvpython pack is incomplete"; return 1; }
  export LD_LIBRARY_PATH=$ROOT/usr/lib/x86_64-linux-gnu:$PWD/.pvcarry/plugin:/usr/local/cuda/lib64:/usr/local/cuda/lib:${LD_LIBRARY_PATH:-}
  export PYTHONHOME=$ROOT/usr OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
  if ldd "$ROOT/usr/bin/pvpython" .pvcarry/plugin/*.so | grep "not found"; then
    echo "missing libraries"
    return 1
  fi
  { nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; } >"$out/machine.txt" 2>&1
  local status=0 round backend
  for round in $(seq 1 "$rounds"); do
    for backend in CUDA CPU; do
      "$ROOT/usr/bin/pvpython" --no-mpi Benchmarks/pipeline_latency.py --plugin .pvcarry/plugin/FacePlan.so \
        --data "$PWD/Data" --shell-scene "$ROOT/shell100k.vtk" --shell-only --edits "$edits" \
        --backend "$backend" --json "$out/pipeline_latency_${backend}_r$round.json" 2>&1 |
        grep -v 'WARN|' | tee -a "$out/pipeline_latency.txt"
      [ "${PIPESTATUS[0]}" = 0 ] || status=1
    done
  done
  return $status
}

case "${1:-}" in
  pack) pack "${2:-}" ;;
  receive) receive "${2:-}" ;;
  run) shift; run "$@" ;;
  *) echo "usage: $0 pack | receive PART | run [ROUNDS] [EDITS]"; exit 2 ;;
esac
