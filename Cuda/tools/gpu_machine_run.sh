#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Builds Core + Cuda + the GPU tests + gpu_benchmark on a GPU host and runs them there; the plugin
# is not built (a GPU host may have no ParaView).
# Dependencies: the host's own packages (Debian: libeigen3-dev libsuitesparse-dev libopenblas-dev
# libgtest-dev zlib1g-dev, plus nvcc, CMake and ninja). A host without the development packages
# can take them from FACEPLAN_DEPS, a folder holding Debian packages and Eigen's headers, made on a
# Debian 12 machine with
#   (cd "$FACEPLAN_DEPS/debs" && apt-get download libcholmod3 libsuitesparse-dev \
#      libsuitesparseconfig5 libamd2 libcamd2 libcolamd2 libccolamd2 libmetis5 libopenblas0-pthread \
#      libgfortran5 libquadmath0 libgomp1 libgtest-dev zlib1g-dev)
#   tar -czf "$FACEPLAN_DEPS/eigen3.tar.gz" -C / usr/include/eigen3 usr/share/eigen3/cmake
# They are unpacked into a private root (dpkg -x), nothing is installed.
# It builds the working tree as it is and fails when that does not build (no stale fallback).
# FACEPLAN_CUDA_ARCHITECTURES sets CMAKE_CUDA_ARCHITECTURES (Cuda/CMakeLists.txt's default: 90).
# Usage: OUT=<results dir> [BUILD=<dir>] [SKIP_BENCHMARK=1] [SKIP_TESTS=1] [TARGETS="..."]
#        [FACEPLAN_DEPS=<dir>] [BENCHMARK=large_deformation_gpu]
#        Cuda/tools/gpu_machine_run.sh [the benchmark's arguments...]
# Two trees may build side by side (two BUILD folders): the unpacked dependencies are shared, and
# unpacked once.
set -uo pipefail
[ -n "${FACEPLAN_DEPS:-}" ] && FACEPLAN_DEPS=$(realpath "$FACEPLAN_DEPS")
cd "$(dirname "$0")/../.."
ROOT=$PWD
OUT=${OUT:-/tmp/faceplan-gpu-out}
mkdir -p "$OUT"
DEPARGS=()
[ -n "${FACEPLAN_CUDA_ARCHITECTURES:-}" ] && DEPARGS+=(-DCMAKE_CUDA_ARCHITECTURES="$FACEPLAN_CUDA_ARCHITECTURES")
RUNLIBS=
if [ -n "${FACEPLAN_DEPS:-}" ]; then
  DC=/tmp/faceplan-deps-root
  if [ ! -e "$DC/.unpacked" ]; then
    rm -rf "$DC" && mkdir -p "$DC"
    for f in "$FACEPLAN_DEPS"/debs/*.deb; do dpkg -x "$f" "$DC"; done
    tar -xzf "$FACEPLAN_DEPS/eigen3.tar.gz" -C "$DC"
    touch "$DC/.unpacked"
  fi
  LIB=$DC/usr/lib/x86_64-linux-gnu
  RUNLIBS=$LIB:$LIB/openblas-pthread
  DEPARGS+=(-DEigen3_DIR="$DC/usr/share/eigen3/cmake" -DGTest_DIR="$LIB/cmake/GTest"
           -DCHOLMOD_INCLUDE_DIR="$DC/usr/include/suitesparse" -DCHOLMOD_LIBRARY="$LIB/libcholmod.so"
           -DSUITESPARSECONFIG_LIBRARY="$LIB/libsuitesparseconfig.so"
           -DCMAKE_EXE_LINKER_FLAGS="-Wl,-rpath-link,$RUNLIBS -Wl,-rpath,$RUNLIBS")
  # zlib (Testing/Support/VtuReader): the host's own libz.so.1 with the unpacked header when the
  # host has no zlib development files.
  if [ ! -e /usr/include/zlib.h ]; then
    ZSO=$(ls /lib/x86_64-linux-gnu/libz.so.1 /usr/lib/x86_64-linux-gnu/libz.so.1 2>/dev/null | head -1)
    ln -sf "$ZSO" "$LIB/libz.so"
    DEPARGS+=(-DZLIB_INCLUDE_DIR="$DC/usr/include" -DZLIB_LIBRARY="$LIB/libz.so")
  fi
fi
{ nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.mem --format=csv; nproc; uname -r;
  cat /etc/os-release | head -2; g++ --version | head -1; nvcc --version | tail -2; cmake --version | head -1; } \
  > "$OUT/machine.txt" 2>&1
cat "$OUT/machine.txt"

configure() { # $1 source dir, $2 build dir
  cmake -S "$1" -B "$2" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFACEPLAN_BUILD_PLUGIN=OFF -DFACEPLAN_ENABLE_CUDA=ON \
    "${DEPARGS[@]}"
}
# BUILD: the build folder (two trees side by side use two); SKIP_BENCHMARK=1 builds and tests only.
BUILD=${BUILD:-/tmp/build}
TARGETS=${TARGETS:-"TestCudaBackend TestCudaLargeDeformation TestCudaFallback gpu_benchmark large_deformation_gpu"}
ok=0
if configure "$ROOT" "$BUILD" > "$OUT/configure.log" 2>&1 && \
   cmake --build "$BUILD" -j "$(nproc)" --target $TARGETS > "$OUT/build.log" 2>&1; then
  ok=1
  TESTDIR=$BUILD/Testing/Cuda
fi
if [ $ok != 1 ]; then
  echo "BUILD FAILED"
  tail -40 "$OUT"/configure*.log "$OUT"/build*.log
  exit 1
fi
echo "build ok in $BUILD"
[ -n "$RUNLIBS" ] && export LD_LIBRARY_PATH=$RUNLIBS:${LD_LIBRARY_PATH:-}
# At most 8 OpenBLAS threads: with 16, CHOLMOD's CPU factorization ran many times slower
# (BENCHMARKS.md, "GPU: the CUDA backend"); the GPU paths do not depend on it.
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-8}
tests_ok=1
if [ "${SKIP_TESTS:-0}" != 1 ]; then
  (cd "$TESTDIR" && ctest --output-on-failure -L gpu) > "$OUT/ctest-gpu.log" 2>&1 || tests_ok=0
  (cd "$TESTDIR" && ctest --output-on-failure -L cuda) >> "$OUT/ctest-gpu.log" 2>&1 || tests_ok=0
  grep -E "tests passed|Passed|Failed|Skipped|relative|residual" "$OUT/ctest-gpu.log" | tail -30
  (cd "$TESTDIR" && ctest -L gpu -V 2>&1 | grep -E "relative|residual|passes" ) | head -20
  [ "$tests_ok" = 1 ] || echo "TESTS FAILED (see ctest-gpu.log)"
fi
# The benchmark still runs after a test failure (its figures help find the cause); the exit status
# says the tests failed.
bench_ok=1
if [ "${SKIP_BENCHMARK:-0}" != 1 ]; then
  if [ "${BENCHMARK:-gpu_benchmark}" = large_deformation_gpu ]; then
    "$BUILD/bin/large_deformation_gpu" --json "$OUT/large_deformation_gpu.json" "$@" 2>&1 | tee "$OUT/large_deformation_gpu.txt" || bench_ok=0
  else
    "$BUILD/bin/gpu_benchmark" --out "$OUT/gpu_benchmark.json" "$@" 2>&1 | tee "$OUT/gpu_benchmark.txt" || bench_ok=0
  fi
fi
[ "$tests_ok" = 1 ] && [ "$bench_ok" = 1 ]
