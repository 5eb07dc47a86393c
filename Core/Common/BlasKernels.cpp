// SPDX-License-Identifier: BSD-3-Clause
#include "Common/BlasKernels.h"

#include <cstdlib>
#include <dlfcn.h>

namespace faceplan {

BlasKernels DescribeBlasKernels() {
  BlasKernels kernels;
  using CoreName = char* (*)();
  if (auto name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename")))
    if (const char* text = name())
      kernels.name = text;
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  kernels.cpuHasAvx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
#endif
  const bool avx2Kernels = kernels.name == "Haswell" || kernels.name == "Zen";
  if (avx2Kernels && kernels.cpuHasAvx512 && !std::getenv("OPENBLAS_CORETYPE"))
    kernels.advice = "OpenBLAS runs its " + kernels.name +
                     " (AVX2) kernels on this AVX-512 CPU; OPENBLAS_CORETYPE=SkylakeX in the "
                     "environment before the program starts selects its AVX-512 kernels";
  return kernels;
}

} // namespace faceplan
