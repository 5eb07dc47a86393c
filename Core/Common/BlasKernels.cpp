// SPDX-License-Identifier: BSD-3-Clause
#include "Common/BlasKernels.h"

#include <cstdlib>
#include <dlfcn.h>

namespace faceplan {

namespace {

bool IsAvx512Kernels(const std::string& name) {
  return name == "SkylakeX" || name == "Cooperlake" || name == "SapphireRapids";
}

bool IsAvx2Kernels(const std::string& name) {
  return name == "Haswell" || name == "Zen" || name == "Excavator" || IsAvx512Kernels(name);
}

} // namespace

void AdviseBlasKernels(BlasKernels& k) {
  k.suggested.clear();
  k.advice.clear();
  if (k.name.empty())
    return;
  if (k.cpuHasAvx512 && !IsAvx512Kernels(k.name))
    k.suggested = "SkylakeX";
  else if (k.cpuHasAvx2 && !IsAvx2Kernels(k.name))
    k.suggested = k.amd ? "Zen" : "Haswell";
  if (k.suggested.empty() || k.userChose)
    return;
  k.advice = "OpenBLAS runs its " + k.name + " kernels on this " +
             (k.cpuHasAvx512 ? "AVX-512" : "AVX2") + " CPU; OPENBLAS_CORETYPE=" + k.suggested +
             " in the environment before the program starts selects faster ones";
}

BlasKernels DescribeBlasKernels() {
  BlasKernels kernels;
  using CoreName = char* (*)();
  if (auto name = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename")))
    if (const char* text = name())
      kernels.name = text;
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  kernels.cpuHasAvx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
  kernels.cpuHasAvx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  kernels.amd = __builtin_cpu_is("amd");
#endif
  kernels.userChose = std::getenv("OPENBLAS_CORETYPE") != nullptr;
  AdviseBlasKernels(kernels);
  return kernels;
}

} // namespace faceplan
