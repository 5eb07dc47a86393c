#!/usr/bin/env bash
# On the lent GPU machine (no ParaView there): the Condensed FEM Deform filter's edit latency at
# ~100k cells with Backend = CPU and = CUDA, alternated (Benchmarks/FilterLatency/filter_latency).
# The filter library, the driver, export_shell_scene and the ParaView-bundled VTK libraries they
# need travel in .devcarry/vtkrun.tar.xz, made on the development machine after building with the
# plugin and CUDA (the default there):
#   mkdir -p /tmp/vtkrun/lib /tmp/vtkrun/bin
#   cp build/bin/filter_latency build/bin/export_shell_scene /tmp/vtkrun/bin/
#   cp build/lib/paraview-5.11/plugins/FacePlan/libFacePlanFilters.so /tmp/vtkrun/lib/
#   ldd build/bin/filter_latency | awk '{print $1, $3}' | grep -E "vtk|double-conversion|gmp|mpfr" |
#     while read n p; do cp -L "$p" /tmp/vtkrun/lib/"$n"; done
#   tar -cJf .devcarry/vtkrun.tar.xz -C /tmp vtkrun
# CHOLMOD, METIS and OpenBLAS come from .devcarry/debs as for Cuda/tools/gpu_machine_run.sh.
# Usage there: OUT=<dir> Cuda/tools/gpu_filter_latency.sh [ROUNDS] [EDITS]
set -uo pipefail
cd "$(dirname "$0")/../.."
OUT=${OUT:-/tmp/faceplan-filter-latency}
rounds=${1:-3} edits=${2:-30}
mkdir -p "$OUT"
DC=/tmp/devroot
rm -rf "$DC" /tmp/vtkrun && mkdir -p "$DC"
for f in .devcarry/debs/*.deb; do dpkg -x "$f" "$DC"; done
tar -xJf .devcarry/vtkrun.tar.xz -C /tmp
LIB=$DC/usr/lib/x86_64-linux-gnu
export LD_LIBRARY_PATH=/tmp/vtkrun/lib:$LIB:$LIB/openblas-pthread:/usr/local/cuda/lib64:/usr/local/cuda/lib:${LD_LIBRARY_PATH:-}
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
if ldd /tmp/vtkrun/bin/filter_latency | grep "not found"; then
  echo "missing libraries"
  exit 1
fi
{ nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; } > "$OUT/machine.txt" 2>&1
/tmp/vtkrun/bin/export_shell_scene --subdivisions 18 --layers 5 --out /tmp/shell.vtk
status=0
for round in $(seq 1 "$rounds"); do
  for backend in CPU CUDA; do
    /tmp/vtkrun/bin/filter_latency --scene /tmp/shell.vtk --backend "$backend" --edits "$edits" \
      --json "$OUT/filter_latency_${backend}_r$round.json" 2>&1 | tee -a "$OUT/filter_latency.txt" || status=1
  done
done
exit $status
