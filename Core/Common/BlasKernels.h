// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Which BLAS kernels this process runs, so that a timing says what it was measured with, and
// whether faster ones would run on this CPU. OpenBLAS picks its kernels once, when it loads, by CPU
// family and model, or as OPENBLAS_CORETYPE says. An OpenBLAS older than the CPU picks worse ones:
// Debian 12's 0.3.21 runs its AVX2 kernels on AVX-512 AMD CPUs and its SSE3 kernels (Prescott,
// about a seventh of the AVX-512 rate) on Intel models it does not know, such as Emerald Rapids
// (family 6, model 207) and some virtual machines' CPUs. An environment can also force slower
// kernels (an OPENBLAS_CORETYPE=Haswell set for a whole machine keeps AVX2 kernels where AVX-512
// ones would run). FacePlan cannot change the choice after load: it reports it, suggests the value
// that selects the CPU's kernels, and advises only when no one chose.
#include <string>

namespace faceplan {

struct BlasKernels {
  std::string name; // OpenBLAS's core name ("Haswell", "SkylakeX", ...); empty if not OpenBLAS
  bool cpuHasAvx512 = false; // AVX-512 F, DQ, BW and VL: what OpenBLAS's SkylakeX kernels need
  bool cpuHasAvx2 = false;   // AVX2 and FMA: what its Haswell and Zen kernels need
  bool amd = false;
  bool userChose = false; // OPENBLAS_CORETYPE was set
  // The OPENBLAS_CORETYPE that selects faster kernels than `name` on this CPU ("SkylakeX",
  // "Haswell" or "Zen"); empty where `name` already uses the CPU's widest vectors.
  std::string suggested;
  std::string advice; // non-empty when `suggested` is and the user made no choice
};

BlasKernels DescribeBlasKernels();

// The suggestion and advice for the kernels `k.name` on a CPU with k's features (what
// DescribeBlasKernels fills in after reading them).
void AdviseBlasKernels(BlasKernels& k);

} // namespace faceplan
