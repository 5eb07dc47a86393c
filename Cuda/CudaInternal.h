// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal pieces shared by the CUDA backend's translation units (not installed, not public).
#include "Backend/ComputeBackend.h"
#include "Common/ParallelFor.h"
#include "CudaCheck.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

struct cholmod_factor_struct;
struct cholmod_common_struct;

namespace faceplan::cuda::detail {

// Device memory that frees itself; grows on demand, never shrinks until release().
class DeviceArray {
public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& o) noexcept : ptr_(o.ptr_), capacity_(o.capacity_) {
    o.ptr_ = nullptr;
    o.capacity_ = 0;
  }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    if (this != &o) {
      release();
      std::swap(ptr_, o.ptr_);
      std::swap(capacity_, o.capacity_);
    }
    return *this;
  }
  ~DeviceArray() { release(); }
  bool ensure(size_t bytes, std::string& error) {
    if (bytes <= capacity_)
      return true;
    release();
    void* p = nullptr;
    FP_CUDA_TRY(cudaMalloc(&p, bytes));
    ptr_ = p;
    capacity_ = bytes;
    return true;
  }
  void release() {
    if (ptr_)
      cudaFree(ptr_);
    ptr_ = nullptr;
    capacity_ = 0;
  }
  size_t capacity() const { return capacity_; }
  template <class T> T* as() const { return static_cast<T*>(ptr_); }

private:
  void* ptr_ = nullptr;
  size_t capacity_ = 0;
};

// Copies `count` host values into dst (grown to hold them, at least one) on `stream`.
template <class T>
bool Upload(DeviceArray& dst, const T* src, size_t count, cudaStream_t stream, std::string& error) {
  if (!dst.ensure(sizeof(T) * std::max<size_t>(count, 1), error))
    return false;
  if (count > 0)
    FP_CUDA_TRY(
        cudaMemcpyAsync(dst.as<T>(), src, sizeof(T) * count, cudaMemcpyHostToDevice, stream));
  return true;
}
template <class T>
bool Upload(DeviceArray& dst, const std::vector<T>& src, cudaStream_t stream, std::string& error) {
  return Upload(dst, src.data(), src.size(), stream, error);
}

// Page-locked host memory (fast, truly asynchronous copies).
class PinnedArray {
public:
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() {
    if (ptr_)
      cudaFreeHost(ptr_);
  }
  bool ensure(size_t bytes, std::string& error) {
    if (bytes <= capacity_)
      return true;
    if (ptr_)
      cudaFreeHost(ptr_);
    ptr_ = nullptr;
    capacity_ = 0;
    void* p = nullptr;
    FP_CUDA_TRY(cudaMallocHost(&p, std::max<size_t>(bytes, 64)));
    ptr_ = p;
    capacity_ = bytes;
    return true;
  }
  template <class T> T* as() const { return static_cast<T*>(ptr_); }

private:
  void* ptr_ = nullptr;
  size_t capacity_ = 0;
};

// memcpy split over the hardware threads (one thread cannot saturate host memory, and first-touch
// page faults of a fresh destination are spread too).
inline void ParallelCopy(void* dst, const void* src, size_t bytes) {
  constexpr size_t chunk = size_t(2) << 20;
  const std::int64_t chunks = static_cast<std::int64_t>((bytes + chunk - 1) / chunk);
  ParallelFor(chunks, 4, [&](std::int64_t begin, std::int64_t end) {
    const size_t from = static_cast<size_t>(begin) * chunk,
                 to = std::min(bytes, static_cast<size_t>(end) * chunk);
    if (to > from)
      std::memcpy(static_cast<char*>(dst) + from, static_cast<const char*>(src) + from, to - from);
  });
}

// Writes zeros over `count` doubles on every core: the first touch of freshly allocated host
// memory (its page faults), done beside GPU work so that a later copy into it is a plain copy.
inline void TouchPagesInParallel(double* data, std::int64_t count) {
  ParallelFor(count, std::int64_t(1) << 20, [data](std::int64_t begin, std::int64_t end) {
    std::fill(data + begin, data + end, 0.0);
  });
}

// Large device-to-host copy into pageable memory: through three page-locked 64 MB buffers (kept
// for the process), the device copy of one chunk overlapping the host threads' copies of the
// previous ones. Safe to call from two threads at once (each takes its own buffers).
bool DownloadLarge(void* dst, const void* src, size_t bytes, cudaStream_t stream,
                   std::string& error);

// kept = response * roi with the response in GPU memory: cuBLAS DGEMV on one stream, pinned
// host buffers for the two small vectors, one mutex (apply may be called from several threads).
class CudaResponse final : public ResponseOperator {
public:
  ~CudaResponse() override {
    if (handle_)
      cublasDestroy(handle_);
    if (stream_)
      cudaStreamDestroy(stream_);
  }

  // Uploads a host response.
  bool init(const Eigen::MatrixXd& response, std::string& error) {
    if (!checkDims(response.rows(), response.cols(), error))
      return false;
    const size_t bytes = matrixBytes();
    size_t freeBytes = 0, totalBytes = 0;
    FP_CUDA_TRY(cudaSetDevice(0));
    FP_CUDA_TRY(cudaMemGetInfo(&freeBytes, &totalBytes));
    if (static_cast<double>(bytes) > 0.95 * static_cast<double>(freeBytes)) {
      std::ostringstream why;
      why << "the dense response (" << bytes / 1e9 << " GB) does not fit in the GPU's free "
          << freeBytes / 1e9 << " GB";
      error = why.str();
      return false;
    }
    if (!setUp(error) || !matrix_.ensure(std::max<size_t>(bytes, 8), error))
      return false;
    if (bytes > 0) {
      FP_CUDA_TRY(cudaMemcpyAsync(matrix_.as<double>(), response.data(), bytes,
                                  cudaMemcpyHostToDevice, stream_));
      FP_CUDA_TRY(cudaStreamSynchronize(stream_));
    }
    return true;
  }

  // Takes over a response already in device memory (column-major, rows x cols).
  bool adopt(Eigen::Index rows, Eigen::Index cols, DeviceArray&& matrix, std::string& error) {
    if (!checkDims(rows, cols, error))
      return false;
    FP_CUDA_TRY(cudaSetDevice(0));
    if (matrix.capacity() < matrixBytes()) {
      error = "internal: adopted response buffer too small";
      return false;
    }
    matrix_ = std::move(matrix);
    return setUp(error);
  }

  Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) override {
    if (roi.size() != cols_)
      return Status::Error("ROI vector does not match the response");
    std::lock_guard<std::mutex> lock(mutex_);
    std::string error;
    return applyOnDevice(roi, kept, error) ? Status::Ok() : Status::Error(error);
  }

private:
  bool applyOnDevice(const Eigen::VectorXd& roi, Eigen::VectorXd& kept, std::string& error) {
    kept.resize(rows_);
    if (rows_ == 0)
      return true;
    if (cols_ == 0) {
      kept.setZero();
      return true;
    }
    FP_CUDA_TRY(cudaSetDevice(0));
    std::memcpy(hostX_.as<double>(), roi.data(), sizeof(double) * cols_);
    FP_CUDA_TRY(cudaMemcpyAsync(x_.as<double>(), hostX_.as<double>(), sizeof(double) * cols_,
                                cudaMemcpyHostToDevice, stream_));
    const double one = 1.0, zero = 0.0;
    FP_CUBLAS_TRY(cublasDgemv(handle_, CUBLAS_OP_N, rows_, cols_, &one, matrix_.as<double>(), rows_,
                              x_.as<double>(), 1, &zero, y_.as<double>(), 1));
    FP_CUDA_TRY(cudaMemcpyAsync(hostY_.as<double>(), y_.as<double>(), sizeof(double) * rows_,
                                cudaMemcpyDeviceToHost, stream_));
    FP_CUDA_TRY(cudaStreamSynchronize(stream_));
    std::memcpy(kept.data(), hostY_.as<double>(), sizeof(double) * rows_);
    return true;
  }

  size_t matrixBytes() const {
    return sizeof(double) * static_cast<size_t>(rows_) * static_cast<size_t>(cols_);
  }

  bool checkDims(Eigen::Index rows, Eigen::Index cols, std::string& error) {
    if (rows > std::numeric_limits<int>::max() || cols > std::numeric_limits<int>::max()) {
      error = "response too large for cuBLAS's 32-bit dimensions";
      return false;
    }
    rows_ = static_cast<int>(rows);
    cols_ = static_cast<int>(cols);
    return true;
  }

  bool setUp(std::string& error) {
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
    FP_CUBLAS_TRY(cublasCreate(&handle_));
    FP_CUBLAS_TRY(cublasSetStream(handle_, stream_));
    FP_CUBLAS_TRY(cublasSetPointerMode(handle_, CUBLAS_POINTER_MODE_HOST));
    return x_.ensure(sizeof(double) * std::max(cols_, 1), error) &&
           y_.ensure(sizeof(double) * std::max(rows_, 1), error) &&
           hostX_.ensure(sizeof(double) * std::max(cols_, 1), error) &&
           hostY_.ensure(sizeof(double) * std::max(rows_, 1), error);
  }

  std::mutex mutex_;
  int rows_ = 0, cols_ = 0;
  cudaStream_t stream_ = nullptr;
  cublasHandle_t handle_ = nullptr;
  DeviceArray matrix_, x_, y_;
  PinnedArray hostX_, hostY_;
};

// Checks the device once (driver, presence, kernel image); used by every entry point.
bool InitDevice(std::string& error);

// Numeric supernodal LL^T factorization on the GPU of `upper` (upper triangle, the matrix that
// `L` was analysed for by cholmod_analyze with `common`): right-looking per supernode (cuSOLVER
// DPOTRF, cuBLAS DTRSM + DSYRK, updates scattered into the ancestors). The values stay in
// `deviceX` (CHOLMOD's supernodal layout); with `hostCopy` they are also written into L (made
// numeric with cholmod_change_factor), so CPU solves work as after cholmod_factorize.
// Defined in CudaDenseResponse.cpp.
bool FactorAnalysedOnGpu(const SparseMatrix& upper, cholmod_factor_struct* L,
                         cholmod_common_struct* common, DeviceArray& deviceX, bool hostCopy,
                         double& factorizeMs, double& downloadMs, std::string& error);

// The host copy of FactorAnalysedOnGpu's factor, in two steps so that the copy can run beside
// other GPU work: AllocateHostFactor makes L numeric (cholmod_change_factor; not to be run
// concurrently with other uses of L), DownloadFactor then copies deviceX into L->x on `stream`
// (it touches only L->x's memory and sets L->minor, so L's structure may be read meanwhile).
bool AllocateHostFactor(cholmod_factor_struct* L, cholmod_common_struct* common,
                        std::string& error);
bool DownloadFactor(cholmod_factor_struct* L, const DeviceArray& deviceX, cudaStream_t stream,
                    std::string& error);

} // namespace faceplan::cuda::detail
