// SPDX-License-Identifier: BSD-3-Clause
// The BLAS kernels this process gets (Common/BlasKernels.h). `--suggest` prints only the
// OPENBLAS_CORETYPE that selects faster kernels on this CPU (nothing when there are none, or when
// OPENBLAS_CORETYPE is already set): scripts/blas_env exports it before FacePlan's programs start.
#include "Common/BlasKernels.h"
#include "SparseSolver/Blas.h"

#include <cstdio>
#include <cstring>

int main(int argc, char** argv) {
  // One product, so that this program loads the BLAS that FacePlan's libraries load.
  const int one = 1;
  const float a = 1.0f, zero = 0.0f;
  float c = 0.0f;
  sgemm_("N", "N", &one, &one, &one, &a, &a, &one, &a, &one, &zero, &c, &one);
  const faceplan::BlasKernels k = faceplan::DescribeBlasKernels();
  if (argc > 1 && std::strcmp(argv[1], "--suggest") == 0) {
    if (!k.userChose && !k.suggested.empty())
      std::printf("%s\n", k.suggested.c_str());
    return 0;
  }
  std::printf("OpenBLAS kernels: %s\nCPU: %s%s\nOPENBLAS_CORETYPE: %s\nsuggested: %s\n",
              k.name.empty() ? "(not OpenBLAS)" : k.name.c_str(),
              k.cpuHasAvx512 ? "AVX-512" : (k.cpuHasAvx2 ? "AVX2" : "no AVX2"),
              k.amd ? " (AMD)" : "", k.userChose ? "set" : "unset",
              k.suggested.empty() ? "(none)" : k.suggested.c_str());
  return 0;
}
