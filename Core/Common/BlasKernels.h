// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Which BLAS kernels this process runs, so that a timing says what it was measured with, and
// whether faster ones would run on this CPU. OpenBLAS picks its kernels once, when it loads, by CPU
// family, or as OPENBLAS_CORETYPE says: an OpenBLAS older than the CPU can fall back to AVX2
// kernels on a CPU with AVX-512, and an environment can force them (an OPENBLAS_CORETYPE=Haswell
// set for a whole machine keeps AVX2 kernels where faster AVX-512 ones would run).
// FacePlan cannot change the choice after load; it reports it, and advises only when no one chose.
#include <string>

namespace faceplan {

struct BlasKernels {
  std::string name; // OpenBLAS's core name ("Haswell", "SkylakeX", ...); empty if not OpenBLAS
  bool cpuHasAvx512 = false; // AVX-512 F, DQ, BW and VL: what OpenBLAS's SkylakeX kernels need
  std::string advice; // non-empty when AVX2 kernels run on an AVX-512 CPU without a user choice
};

BlasKernels DescribeBlasKernels();

} // namespace faceplan
