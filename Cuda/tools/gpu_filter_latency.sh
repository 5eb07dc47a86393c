#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# On a GPU host: the Condensed FEM Deform filter's edit latency at ~100k cells with Backend = CPU
# and = CUDA, alternated (Benchmarks/FilterLatency/filter_latency). With a FacePlan build with the
# plugin and CUDA there, BUILD=<that build> runs its binaries. A host without ParaView takes them
# from VTKRUN, a tarball of the filter library, the driver, export_shell_scene and the
# ParaView-bundled VTK libraries they need, made on a machine with that build:
#   mkdir -p /tmp/vtkrun/lib /tmp/vtkrun/bin
#   cp build/bin/filter_latency build/bin/export_shell_scene /tmp/vtkrun/bin/
#   cp build/lib/paraview-5.11/plugins/FacePlan/libFacePlanFilters.so /tmp/vtkrun/lib/
#   ldd build/bin/filter_latency | awk '{print $1, $3}' | grep -E "vtk|double-conversion|gmp|mpfr" |
#     while read n p; do cp -L "$p" /tmp/vtkrun/lib/"$n"; done
#   tar -cJf vtkrun.tar.xz -C /tmp vtkrun
# CHOLMOD, METIS and OpenBLAS come from the host, or from FACEPLAN_DEPS as for
# Cuda/tools/gpu_machine_run.sh.
# Usage: OUT=<dir> (BUILD=<build dir> | VTKRUN=<vtkrun.tar.xz>) [FACEPLAN_DEPS=<dir>]
#        Cuda/tools/gpu_filter_latency.sh [ROUNDS] [EDITS]
set -uo pipefail
[ -n "${FACEPLAN_DEPS:-}" ] && FACEPLAN_DEPS=$(realpath "$FACEPLAN_DEPS")
[ -n "${VTKRUN:-}" ] && VTKRUN=$(realpath "$VTKRUN")
[ -n "${BUILD:-}" ] && BUILD=$(realpath "$BUILD")
cd "$(dirname "$0")/../.."
OUT=${OUT:-/tmp/faceplan-filter-latency}
rounds=${1:-3} edits=${2:-30}
mkdir -p "$OUT"
if [ -n "${VTKRUN:-}" ]; then
  rm -rf /tmp/vtkrun && tar -xJf "$VTKRUN" -C /tmp
  bin=/tmp/vtkrun/bin
  export LD_LIBRARY_PATH=/tmp/vtkrun/lib:${LD_LIBRARY_PATH:-}
elif [ -n "${BUILD:-}" ]; then
  bin=$BUILD/bin
else
  echo "set BUILD (a build with the plugin and CUDA) or VTKRUN (see the header)"
  exit 2
fi
if [ -n "${FACEPLAN_DEPS:-}" ]; then
  DC=/tmp/faceplan-deps-root
  rm -rf "$DC" && mkdir -p "$DC"
  for f in "$FACEPLAN_DEPS"/debs/*.deb; do dpkg -x "$f" "$DC"; done
  LIB=$DC/usr/lib/x86_64-linux-gnu
  export LD_LIBRARY_PATH=$LIB:$LIB/openblas-pthread:${LD_LIBRARY_PATH:-}
fi
export LD_LIBRARY_PATH=${LD_LIBRARY_PATH:-}:/usr/local/cuda/lib64:/usr/local/cuda/lib
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
if ldd "$bin/filter_latency" | grep "not found"; then
  echo "missing libraries"
  exit 1
fi
{ nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; } > "$OUT/machine.txt" 2>&1
"$bin/export_shell_scene" --subdivisions 18 --layers 5 --out /tmp/shell.vtk
status=0
for round in $(seq 1 "$rounds"); do
  for backend in CPU CUDA; do
    "$bin/filter_latency" --scene /tmp/shell.vtk --backend "$backend" --edits "$edits" \
      --json "$OUT/filter_latency_${backend}_r$round.json" 2>&1 | tee -a "$OUT/filter_latency.txt" || status=1
  done
done
exit $status
