#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# On a GPU host: the working tree built and tested (Cuda/tools/gpu_machine_run.sh), then
# the ordering's parts (Benchmarks/ordering_breakdown) for each dissection split asked for, then
# gpu_benchmark ROUNDS times, so that one machine gives the median of the 1M precompute.
# FACEPLAN_DEPS as for gpu_machine_run.sh.
# Usage: OUT=<dir> Cuda/tools/gpu_precompute_runs.sh ROUNDS "LEAVES..." [gpu_benchmark args]
#   e.g. OUT=$OUT Cuda/tools/gpu_precompute_runs.sh 3 "8 16" --no-blas-sweep --cpu-edit-budget-ms 100 --cases 1M
# Writes $OUT/runs.txt (the precompute lines of every run, the ordering breakdowns) and
# $OUT/runs.tar.gz (every log, JSON and stdout).
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
rounds=$1 leaves=$2
shift 2
work=/tmp/faceplan-runs
rm -rf "$work" && mkdir -p "$work"
if ! OUT="$work/build" BUILD="$work/build-tree" SKIP_BENCHMARK=1 "$root/Cuda/tools/gpu_machine_run.sh" > "$work/build.txt" 2>&1; then
  tail -40 "$work/build.txt"
  tar -czf "$OUT/runs.tar.gz" -C "$work" build build.txt 2>/dev/null
  exit 1
fi
cmake --build "$work/build-tree" --target ordering_breakdown > "$work/build_breakdown.log" 2>&1
if [ -n "${FACEPLAN_DEPS:-}" ]; then # unpacked by gpu_machine_run.sh
  lib=/tmp/faceplan-deps-root/usr/lib/x86_64-linux-gnu
  export LD_LIBRARY_PATH=$lib:$lib/openblas-pthread:${LD_LIBRARY_PATH:-}
fi
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
summary="$OUT/runs.txt"
grep -E "tests passed|TESTS FAILED" "$work/build.txt" > "$summary"
for l in $leaves; do
  echo "== ordering_breakdown, FACEPLAN_DISSECTION_LEAVES=$l" >> "$summary"
  FACEPLAN_DISSECTION_LEAVES=$l "$work/build-tree/bin/ordering_breakdown" --repeats 3 > "$work/breakdown_$l.txt" 2>&1
  grep -E "median|factor" "$work/breakdown_$l.txt" >> "$summary"
done
for round in $(seq 1 "$rounds"); do
  name="$work/run_r$round"
  "$work/build-tree/bin/gpu_benchmark" --out "$name.json" "$@" > "$name.txt" 2>&1
  { echo "== round $round"; grep -E "^== |core_precompute|GPU factor|beside the stages" "$name.txt"; } >> "$summary"
done
cat "$summary"
tar -czf "$OUT/runs.tar.gz" -C "$work" build build.txt $(cd "$work" && ls ./*.txt ./*.json 2>/dev/null)
