#pragma once
// Which BLAS kernels this process runs, and whether faster ones would run on this CPU. An OpenBLAS
// older than the CPU picks its kernels by CPU family and can fall back to AVX2 kernels on a CPU
// with AVX-512 (Debian 12's OpenBLAS 0.3.21 runs "Haswell" kernels on AMD Zen 5, at ~60 % of the
// AVX-512 kernels' dense-product rate). OpenBLAS reads its choice once, at load, from
// OPENBLAS_CORETYPE, so FacePlan can only report it; the README says how to set it.
#include <string>

namespace faceplan {

struct BlasKernels {
  std::string name;   // OpenBLAS's core name ("Haswell", "SkylakeX", ...); empty if not OpenBLAS
  bool cpuHasAvx512 = false; // AVX-512 F, DQ, BW and VL: what OpenBLAS's SkylakeX kernels need
  std::string advice; // non-empty when AVX2 kernels run on an AVX-512 CPU without a user choice
};

BlasKernels DescribeBlasKernels();

} // namespace faceplan
