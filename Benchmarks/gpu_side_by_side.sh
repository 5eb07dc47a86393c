#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# On a GPU host: a base commit's tree and the working tree, each built and tested with
# Cuda/tools/gpu_machine_run.sh, then their gpu_benchmark binaries run alternately (base, new,
# base, new, ...) so that both see the same card and the same machine state. Timings of different
# machines are not comparable (BENCHMARKS.md); this gives a ratio measured in one run.
# Prepare:  git archive --format=tar.gz -o base.tar.gz <base commit>
# Run:      OUT=<dir> [FACEPLAN_DEPS=<dir>] Benchmarks/gpu_side_by_side.sh base.tar.gz ROUNDS [gpu_benchmark args]
# Writes $OUT/side_by_side.txt (the precompute lines of every run) and $OUT/side_by_side.tar.gz
# (every log, JSON and stdout).
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
base_tar=$1 rounds=$2
shift 2
work=/tmp/faceplan-side-by-side
rm -rf "$work" && mkdir -p "$work/base-src"
tar -xzf "$base_tar" -C "$work/base-src"
[ -n "${FACEPLAN_DEPS:-}" ] && export FACEPLAN_DEPS=$(cd "$FACEPLAN_DEPS" && pwd)
# The base builds with this tree's runner (same configure flags; its own may lack BUILD).
cp "$root/Cuda/tools/gpu_machine_run.sh" "$work/base-src/Cuda/tools/gpu_machine_run.sh"
for which in base new; do
  src=$root
  [ "$which" = base ] && src=$work/base-src
  if ! OUT="$work/$which" BUILD="$work/build-$which" SKIP_BENCHMARK=1 "$src/Cuda/tools/gpu_machine_run.sh"; then
    echo "$which: build or tests failed"
    tar -czf "$OUT/side_by_side.tar.gz" -C "$work" base new 2>/dev/null
    exit 1
  fi
done
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
summary="$OUT/side_by_side.txt"
: > "$summary"
for round in $(seq 1 "$rounds"); do
  for which in base new; do
    name="$work/${which}_r$round"
    "$work/build-$which/bin/gpu_benchmark" --out "$name.json" "$@" > "$name.txt" 2>&1
    { echo "== round $round $which"; grep -E "^== |core_precompute|GPU factor|beside the stages" "$name.txt"; } >> "$summary"
  done
done
cat "$summary"
tar -czf "$OUT/side_by_side.tar.gz" -C "$work" base new $(cd "$work" && ls ./*_r*.txt ./*_r*.json)
