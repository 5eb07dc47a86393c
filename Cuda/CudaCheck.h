// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Error checking for CUDA runtime and cuBLAS calls inside functions that return bool and have a
// `std::string& error` in scope: a failure sets `error` (call, file, line, CUDA's message) and
// returns false. This bool + error form stays inside Cuda/ (the macros need a plain early return);
// every function Cuda/ exposes to Core, the filters, tests and benchmarks turns it into a Status.
// Nothing here aborts or throws, so errors never cross the backend interface.
#include <cublas_v2.h>
#include <cuda_runtime_api.h>

#include <string>

namespace faceplan::cuda::detail {

inline std::string DescribeCudaError(cudaError_t code, const char* call, const char* file,
                                     int line) {
  std::string where = std::string(file);
  const auto slash = where.find_last_of('/');
  if (slash != std::string::npos)
    where = where.substr(slash + 1);
  return std::string("CUDA error ") + cudaGetErrorName(code) + " (" + cudaGetErrorString(code) +
         ") in " + call + " at " + where + ":" + std::to_string(line);
}

inline std::string DescribeCublasError(cublasStatus_t code, const char* call, const char* file,
                                       int line) {
  std::string where = std::string(file);
  const auto slash = where.find_last_of('/');
  if (slash != std::string::npos)
    where = where.substr(slash + 1);
  return std::string("cuBLAS error ") + cublasGetStatusName(code) + " (" +
         cublasGetStatusString(code) + ") in " + call + " at " + where + ":" + std::to_string(line);
}

} // namespace faceplan::cuda::detail

#define FP_CUDA_TRY(expr)                                                                          \
  do {                                                                                             \
    const cudaError_t fpCudaStatus_ = (expr);                                                      \
    if (fpCudaStatus_ != cudaSuccess) {                                                            \
      error =                                                                                      \
          ::faceplan::cuda::detail::DescribeCudaError(fpCudaStatus_, #expr, __FILE__, __LINE__);   \
      return false;                                                                                \
    }                                                                                              \
  } while (0)

#define FP_CUBLAS_TRY(expr)                                                                        \
  do {                                                                                             \
    const cublasStatus_t fpCublasStatus_ = (expr);                                                 \
    if (fpCublasStatus_ != CUBLAS_STATUS_SUCCESS) {                                                \
      error = ::faceplan::cuda::detail::DescribeCublasError(fpCublasStatus_, #expr, __FILE__,      \
                                                            __LINE__);                             \
      return false;                                                                                \
    }                                                                                              \
  } while (0)
