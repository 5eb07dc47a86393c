// SPDX-License-Identifier: BSD-3-Clause
#include "CudaLargeDeformation.h"

#include "CudaInternal.h"
#include "CudaKernels.h"
#include "SparseSolver/SinglePrecisionFactor.h"
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <vector>

namespace faceplan::cuda::detail {

namespace {

// out = the n values at `from`, in the pass that checks them: false when one is not finite.
bool CopyFinite(const double* from, size_t n, Eigen::VectorXd& out) {
  out.resize(static_cast<Eigen::Index>(n));
  double* to = out.data();
  bool finite = true;
  for (size_t i = 0; i < n; ++i) {
    to[i] = from[i];
    finite = finite && std::isfinite(from[i]);
  }
  return finite;
}

// A stream of one object's own.
class OwnStream {
public:
  ~OwnStream() {
    if (stream_)
      cudaStreamDestroy(stream_);
  }
  bool create(std::string& error) {
    FP_CUDA_TRY(cudaSetDevice(0));
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
    return true;
  }
  cudaStream_t get() const { return stream_; }

private:
  cudaStream_t stream_ = nullptr;
};

class CudaForces final : public HyperelasticForces {
public:
  bool init(const HyperelasticCells& c, std::string& error) {
    const size_t m = c.volume.size();
    if (c.corners.size() != 4 * m || c.gradients.size() != 12 * m || c.mu.size() != m ||
        c.kappa.size() != m || c.smallStrain.size() != m ||
        c.frameOf.size() != static_cast<size_t>(c.nodes) || c.frames.size() % 9 != 0) {
      error = "internal: inconsistent large-deformation cells";
      return false;
    }
    for (int node : c.corners)
      if (node < 0 || node >= c.nodes) {
        error = "internal: a cell's corner is not a node";
        return false;
      }
    for (int f : c.frameOf)
      if (f >= static_cast<int>(c.frames.size() / 9)) {
        error = "internal: a node's frame does not exist";
        return false;
      }
    if (!InitDevice(error) || !stream_.create(error))
      return false;
    nodes_ = c.nodes;
    cudaStream_t s = stream_.get();
    if (!Upload(corners_, c.corners, s, error) || !Upload(gradients_, c.gradients, s, error) ||
        !Upload(volume_, c.volume, s, error) || !Upload(mu_, c.mu, s, error) ||
        !Upload(kappa_, c.kappa, s, error) || !Upload(smallStrain_, c.smallStrain, s, error) ||
        !Upload(frameOf_, c.frameOf, s, error) || !Upload(frames_, c.frames, s, error))
      return false;
    const size_t dofs = 3 * static_cast<size_t>(nodes_);
    if (!u_.ensure(sizeof(double) * std::max<size_t>(dofs, 1), error) ||
        !force_.ensure(sizeof(double) * (dofs + 2), error) ||
        !hostU_.ensure(sizeof(double) * std::max<size_t>(dofs, 1), error) ||
        !hostForce_.ensure(sizeof(double) * (dofs + 2), error))
      return false;
    arrays_.cells = static_cast<std::int64_t>(m);
    arrays_.corners = corners_.as<int>();
    arrays_.gradients = gradients_.as<double>();
    arrays_.volume = volume_.as<double>();
    arrays_.mu = mu_.as<double>();
    arrays_.kappa = kappa_.as<double>();
    arrays_.smallStrain = smallStrain_.as<char>();
    arrays_.frameOf = frameOf_.as<int>();
    arrays_.frames = frames_.as<double>();
    FP_CUDA_TRY(cudaStreamSynchronize(s));
    return true;
  }

  Status evaluate(const Eigen::VectorXd& u, double& energy, Eigen::VectorXd& force,
                  bool& admissible) override {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string error;
    if (u.size() != 3 * static_cast<Eigen::Index>(nodes_))
      return Status::Error("internal: a state of the wrong size");
    return run(u, energy, force, admissible, error) ? Status::Ok() : Status::Error(error);
  }

  Status measure(const Eigen::VectorXd& u, double& smallestVolumeRatio, double& largestGreenStrain,
                 long long& largestStrainCell) override {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string error;
    if (u.size() != 3 * static_cast<Eigen::Index>(nodes_))
      return Status::Error("internal: a state of the wrong size");
    return measureOnDevice(u, smallestVolumeRatio, largestGreenStrain, largestStrainCell, error)
               ? Status::Ok()
               : Status::Error(error);
  }

private:
  // The force and, after it, the energy and the inadmissible flag (as a double's bits) in one
  // buffer: one copy back.
  bool run(const Eigen::VectorXd& u, double& energy, Eigen::VectorXd& force, bool& admissible,
           std::string& error) {
    const size_t dofs = 3 * static_cast<size_t>(nodes_);
    cudaStream_t s = stream_.get();
    FP_CUDA_TRY(cudaSetDevice(0));
    std::memcpy(hostU_.as<double>(), u.data(), sizeof(double) * dofs);
    FP_CUDA_TRY(cudaMemcpyAsync(u_.as<double>(), hostU_.as<double>(), sizeof(double) * dofs,
                                cudaMemcpyHostToDevice, s));
    FP_CUDA_TRY(cudaMemsetAsync(force_.as<double>(), 0, sizeof(double) * (dofs + 2), s));
    double* out = force_.as<double>();
    FP_CUDA_TRY(LaunchHyperelasticForces(arrays_, u_.as<double>(), out, out + dofs,
                                         reinterpret_cast<int*>(out + dofs + 1), s));
    FP_CUDA_TRY(cudaMemcpyAsync(hostForce_.as<double>(), out, sizeof(double) * (dofs + 2),
                                cudaMemcpyDeviceToHost, s));
    FP_CUDA_TRY(cudaStreamSynchronize(s));
    const double* host = hostForce_.as<double>();
    int flag = 0;
    std::memcpy(&flag, host + dofs + 1, sizeof(int));
    energy = host[dofs];
    admissible = flag == 0 && std::isfinite(energy) && CopyFinite(host, dofs, force);
    return true;
  }

  bool measureOnDevice(const Eigen::VectorXd& u, double& smallestVolumeRatio,
                       double& largestGreenStrain, long long& largestStrainCell,
                       std::string& error) {
    const size_t dofs = 3 * static_cast<size_t>(nodes_);
    const int blocks = DeformationMeasureBlocks(arrays_.cells);
    const size_t bytes = 3 * sizeof(double) * static_cast<size_t>(std::max(blocks, 1));
    if (!measures_.ensure(bytes, error) || !hostMeasures_.ensure(bytes, error))
      return false;
    cudaStream_t s = stream_.get();
    FP_CUDA_TRY(cudaSetDevice(0));
    std::memcpy(hostU_.as<double>(), u.data(), sizeof(double) * dofs);
    FP_CUDA_TRY(cudaMemcpyAsync(u_.as<double>(), hostU_.as<double>(), sizeof(double) * dofs,
                                cudaMemcpyHostToDevice, s));
    double* out = measures_.as<double>();
    FP_CUDA_TRY(LaunchDeformationMeasures(arrays_, u_.as<double>(), out, out + blocks,
                                          reinterpret_cast<long long*>(out + 2 * blocks), s));
    FP_CUDA_TRY(cudaMemcpyAsync(hostMeasures_.as<double>(), out, bytes, cudaMemcpyDeviceToHost, s));
    FP_CUDA_TRY(cudaStreamSynchronize(s));
    const double* host = hostMeasures_.as<double>();
    const long long* cells = reinterpret_cast<const long long*>(host + 2 * blocks);
    smallestVolumeRatio = std::numeric_limits<double>::infinity();
    largestGreenStrain = 0.0;
    largestStrainCell = -1;
    for (int b = 0; b < blocks; ++b) {
      smallestVolumeRatio = std::min(smallestVolumeRatio, host[b]);
      if (host[blocks + b] > largestGreenStrain) {
        largestGreenStrain = host[blocks + b];
        largestStrainCell = cells[b];
      }
    }
    return true;
  }

  std::mutex mutex_;
  OwnStream stream_;
  int nodes_ = 0;
  DeviceArray corners_, gradients_, volume_, mu_, kappa_, smallStrain_, frameOf_, frames_;
  DeviceArray u_, force_, measures_;
  PinnedArray hostU_, hostForce_, hostMeasures_;
  HyperelasticCellArrays arrays_;
};

class CudaFactor final : public FactorOnDevice {
  // A large supernode: its first column, columns, rows below the diagonal block, the offsets of
  // its values, of its diagonal block's inverse and of its rows below in s.
  struct Large {
    int first = 0, columns = 0, rows = 0;
    std::int64_t px = 0, inverse = 0;
    int rowList = 0;
  };
  // From this many columns (or with more rows than a block's shared memory holds comfortably) a
  // supernode is large.
  // FACEPLAN_CUDA_LARGE_COLUMNS overrides the columns, for measuring.
  static constexpr int kLargeColumns = 256, kLargeRows = 8192;
  static int LargeColumns() {
    const char* given = std::getenv("FACEPLAN_CUDA_LARGE_COLUMNS");
    return given && std::atoi(given) > 0 ? std::atoi(given) : kLargeColumns;
  }

public:
  ~CudaFactor() override {
    if (graph_)
      cudaGraphExecDestroy(graph_);
    if (blas_)
      cublasDestroy(blas_);
  }

  bool init(const SinglePrecisionFactor& factor, const SparseMatrix& upper, std::string& error) {
    // The values were converted (and checked finite) by SinglePrecisionFactor::assign: they are
    // copied as they are.
    const SinglePrecisionFactor::Layout f = factor.layout();
    if (!f.super) {
      error = "internal: the single-precision factor is empty";
      return false;
    }
    n_ = f.n;
    if (upper.rows() != n_ || upper.cols() != n_) {
      error = "internal: the matrix does not match the factor";
      return false;
    }
    const int nsuper = f.nsuper;
    const int* super = f.super;
    const int* pi = f.pi;
    const std::int64_t* px = f.px;
    const size_t valueCount = static_cast<size_t>(px[nsuper]);
    // Levels: a supernode's parent is always later in CHOLMOD's order, so one ascending pass gives
    // each its height above the leaves.
    const faceplan::SupernodalStructure tree{n_, nsuper, super, pi, f.s};
    const std::vector<int> parent = SupernodeParents(tree, SupernodeOfColumns(tree));
    std::vector<int> level(nsuper, 0);
    int levels = 0;
    for (int k = 0; k < nsuper; ++k) {
      levels = std::max(levels, level[k] + 1);
      if (parent[k] >= 0)
        level[parent[k]] = std::max(level[parent[k]], level[k] + 1);
    }
    // Small supernodes go to the level kernels; large ones (the top of the tree, where a level has
    // few supernodes and one thread block each would leave the GPU idle) to cuBLAS products with
    // their diagonal block's inverse and their off-diagonal block, each spread over the GPU.
    const int largeColumns = LargeColumns();
    levelStart_.assign(levels + 1, 0);
    levelRows_.assign(levels, 0);
    big_.assign(levels, {});
    std::int64_t inverseEntries = 0;
    int bigColumns = 0, bigRows = 0;
    for (int k = 0; k < nsuper; ++k) {
      const int nc = super[k + 1] - super[k], nr = pi[k + 1] - pi[k];
      if (nc >= largeColumns || nr > kLargeRows) {
        big_[level[k]].push_back({super[k], nc, nr - nc, px[k], inverseEntries, pi[k] + nc});
        inverseEntries += std::int64_t(nc) * nc;
        bigColumns = std::max(bigColumns, nc);
        bigRows = std::max(bigRows, nr - nc);
        ++largeCount_;
        continue;
      }
      ++levelStart_[level[k] + 1];
      levelRows_[level[k]] = std::max(levelRows_[level[k]], nr);
    }
    for (int l = 0; l < levels; ++l)
      levelStart_[l + 1] += levelStart_[l];
    std::vector<int> order(std::max(levelStart_.back(), 1)),
        next(levelStart_.begin(), levelStart_.end() - 1);
    for (int k = 0; k < nsuper; ++k) {
      const int nc = super[k + 1] - super[k], nr = pi[k + 1] - pi[k];
      if (!(nc >= largeColumns || nr > kLargeRows))
        order[next[level[k]]++] = k;
    }
    maxRows_ = levels > 0 ? *std::max_element(levelRows_.begin(), levelRows_.end()) : 0;
    // Upper triangle as triplets.
    std::vector<int> rows, cols;
    std::vector<double> entries;
    rows.reserve(upper.nonZeros());
    cols.reserve(upper.nonZeros());
    entries.reserve(upper.nonZeros());
    for (int col = 0; col < upper.outerSize(); ++col)
      for (SparseMatrix::InnerIterator it(upper, col); it; ++it)
        if (it.row() <= col) {
          rows.push_back(static_cast<int>(it.row()));
          cols.push_back(col);
          entries.push_back(it.value());
        }
    nnz_ = static_cast<std::int64_t>(entries.size());

    if (!InitDevice(error) || !stream_.create(error))
      return false;
    cudaDeviceProp prop{};
    FP_CUDA_TRY(cudaGetDeviceProperties(&prop, 0));
    const size_t shared = sizeof(float) * static_cast<size_t>(maxRows_);
    if (shared > prop.sharedMemPerBlockOptin) {
      error = "a supernode of " + std::to_string(maxRows_) +
              " rows does not fit the GPU's shared memory";
      return false;
    }
    if (shared > 48 * 1024)
      FP_CUDA_TRY(AllowSweepSharedMemory(static_cast<int>(shared)));
    cudaStream_t st = stream_.get();
    const size_t ends = static_cast<size_t>(nsuper) + 1;
    if (!Upload(super_, super, ends, st, error) || !Upload(pi_, pi, ends, st, error) ||
        !Upload(px_, px, ends, st, error) ||
        !Upload(s_, f.s, static_cast<size_t>(pi[nsuper]), st, error) ||
        !Upload(values_, f.values, valueCount, st, error) ||
        !Upload(perm_, f.perm, static_cast<size_t>(n_), st, error) ||
        !Upload(order_, order, st, error) || !Upload(rows_, rows, st, error) ||
        !Upload(cols_, cols, st, error) || !Upload(entries_, entries, st, error))
      return false;
    const size_t bytes = sizeof(double) * (n_ + 1); // a right-hand side and its scale
    if (!b_.ensure(bytes, error) || !x_.ensure(bytes, error) ||
        !y_.ensure(sizeof(float) * std::max(n_, 1), error) || !hostIn_.ensure(bytes, error) ||
        !hostOut_.ensure(bytes, error))
      return false;
    arrays_.super = super_.as<int>();
    arrays_.pi = pi_.as<int>();
    arrays_.px = px_.as<std::int64_t>();
    arrays_.s = s_.as<int>();
    arrays_.values = values_.as<float>();
    valueBytes_ = 4.0 * double(valueCount);
    FP_CUBLAS_TRY(cublasCreate(&blas_));
    FP_CUBLAS_TRY(cublasSetStream(blas_, st));
    FP_CUBLAS_TRY(cublasSetPointerMode(blas_, CUBLAS_POINTER_MODE_HOST));
    if (!inverses_.ensure(sizeof(float) * std::max<std::int64_t>(inverseEntries, 1), error) ||
        !work_.ensure(sizeof(float) * std::max(bigColumns, 1), error) ||
        !rowWork_.ensure(sizeof(float) * std::max(bigRows, 1), error))
      return false;
    if (inverseEntries > 0)
      FP_CUDA_TRY(cudaMemsetAsync(inverses_.as<float>(), 0, sizeof(float) * inverseEntries, st));
    const float one = 1.0f;
    for (const std::vector<Large>& level : big_)
      for (const Large& b : level) {
        float* inverse = inverses_.as<float>() + b.inverse;
        FP_CUDA_TRY(LaunchSetDiagonal(inverse, b.columns, 1.0f, st));
        FP_CUBLAS_TRY(cublasStrsm(blas_, CUBLAS_SIDE_LEFT, CUBLAS_FILL_MODE_LOWER, CUBLAS_OP_N,
                                  CUBLAS_DIAG_NON_UNIT, b.columns, b.columns, &one,
                                  values_.as<float>() + b.px, b.columns + b.rows, inverse,
                                  b.columns));
      }
    supernodes_ = nsuper;
    FP_CUDA_TRY(cudaStreamSynchronize(st));
    if (!std::getenv("FACEPLAN_CUDA_NO_GRAPH"))
      captureSubstitution();
    return true;
  }

  Status solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (b.size() != n_)
      return Status::Error("internal: a right-hand side of the wrong size");
    // b into the pinned buffer with its largest magnitude, in one pass (a step's host work is
    // mostly such passes over the state's length).
    double* in = hostIn_.as<double>();
    double scale = 0.0;
    bool finite = true;
    for (int i = 0; i < n_; ++i) {
      const double v = b[i];
      in[i] = v;
      scale = std::max(scale, std::abs(v));
      finite = finite && std::isfinite(v);
    }
    if (!finite)
      return Status::Error("the right-hand side is not finite");
    if (!(scale > 0.0)) {
      x.setZero(n_);
      return Status::Ok();
    }
    in[n_] = scale;
    std::string error;
    if (!substitute(x, error))
      return Status::Error(error);
    return Status::Ok();
  }

  Status multiply(const Eigen::VectorXd& v, Eigen::VectorXd& out) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (v.size() != n_)
      return Status::Error("internal: a vector of the wrong size");
    std::string error;
    return product(v, out, error) ? Status::Ok() : Status::Error(error);
  }

  std::string describe() const override {
    std::ostringstream line;
    line << supernodes_ << " supernodes (" << largeCount_ << " large) in " << levelRows_.size()
         << " levels, the largest small one of " << maxRows_ << " rows, " << valueBytes_ / 1e6
         << " MB of single-precision values, " << (graph_ ? "one CUDA graph" : "separate launches")
         << " per substitution";
    return line.str();
  }

  SweepShape shape() const {
    SweepShape s;
    s.supernodes = supernodes_;
    s.levels = static_cast<int>(levelRows_.size());
    s.maxRows = maxRows_;
    s.large = largeCount_;
    s.valueBytes = valueBytes_;
    return s;
  }

private:
  bool upload(const Eigen::VectorXd& v, std::string& error) {
    std::memcpy(hostIn_.as<double>(), v.data(), sizeof(double) * n_);
    FP_CUDA_TRY(cudaMemcpyAsync(b_.as<double>(), hostIn_.as<double>(), sizeof(double) * n_,
                                cudaMemcpyHostToDevice, stream_.get()));
    return true;
  }
  bool download(Eigen::VectorXd& out, std::string& error) {
    FP_CUDA_TRY(cudaMemcpyAsync(hostOut_.as<double>(), x_.as<double>(), sizeof(double) * n_,
                                cudaMemcpyDeviceToHost, stream_.get()));
    FP_CUDA_TRY(cudaStreamSynchronize(stream_.get()));
    out = Eigen::Map<const Eigen::VectorXd>(hostOut_.as<double>(), n_);
    return true;
  }

  // The substitution's copies and kernels, in order on `st`: b and its scale (hostIn_[n]) up,
  // the permuted scaled copy, both sweeps level by level, back to the original order, x down.
  bool enqueueSubstitution(cudaStream_t st, std::string& error) {
    FP_CUDA_TRY(cudaMemcpyAsync(b_.as<double>(), hostIn_.as<double>(), sizeof(double) * (n_ + 1),
                                cudaMemcpyHostToDevice, st));
    const double* scale = b_.as<double>() + n_;
    float* y = y_.as<float>();
    FP_CUDA_TRY(LaunchGatherScaled(b_.as<double>(), perm_.as<int>(), n_, scale, y, st));
    const int levels = static_cast<int>(levelRows_.size());
    const int* order = order_.as<int>();
    for (int l = 0; l < levels; ++l) {
      FP_CUDA_TRY(LaunchSupernodalSweep(arrays_, order + levelStart_[l],
                                        levelStart_[l + 1] - levelStart_[l], levelRows_[l], true, y,
                                        st));
      for (const Large& b : big_[l])
        if (!forwardLarge(b, y, st, error))
          return false;
    }
    for (int l = levels - 1; l >= 0; --l) {
      FP_CUDA_TRY(LaunchSupernodalSweep(arrays_, order + levelStart_[l],
                                        levelStart_[l + 1] - levelStart_[l], levelRows_[l], false,
                                        y, st));
      for (const Large& b : big_[l])
        if (!backwardLarge(b, y, st, error))
          return false;
    }
    FP_CUDA_TRY(LaunchScatterScaled(y, perm_.as<int>(), n_, scale, x_.as<double>(), st));
    FP_CUDA_TRY(cudaMemcpyAsync(hostOut_.as<double>(), x_.as<double>(), sizeof(double) * n_,
                                cudaMemcpyDeviceToHost, st));
    return true;
  }

  // A large supernode's forward step: x1 = L11^-1 y1 (a product with the inverse), the rows below
  // get L21 x1 subtracted.
  bool forwardLarge(const Large& b, float* y, cudaStream_t st, std::string& error) {
    const float one = 1.0f, zero = 0.0f;
    const float* L = values_.as<float>() + b.px;
    float* x1 = work_.as<float>();
    FP_CUBLAS_TRY(cublasSgemv(blas_, CUBLAS_OP_N, b.columns, b.columns, &one,
                              inverses_.as<float>() + b.inverse, b.columns, y + b.first, 1, &zero,
                              x1, 1));
    if (b.rows > 0) {
      FP_CUBLAS_TRY(cublasSgemv(blas_, CUBLAS_OP_N, b.rows, b.columns, &one, L + b.columns,
                                b.columns + b.rows, x1, 1, &zero, rowWork_.as<float>(), 1));
      FP_CUDA_TRY(
          LaunchSubtractAtRows(rowWork_.as<float>(), s_.as<int>() + b.rowList, b.rows, y, st));
    }
    FP_CUDA_TRY(
        cudaMemcpyAsync(y + b.first, x1, sizeof(float) * b.columns, cudaMemcpyDeviceToDevice, st));
    return true;
  }

  // A large supernode's backward step: y1 -= L21^T y[rows below], then x1 = L11^-T y1.
  bool backwardLarge(const Large& b, float* y, cudaStream_t st, std::string& error) {
    const float one = 1.0f, minusOne = -1.0f, zero = 0.0f;
    const float* L = values_.as<float>() + b.px;
    if (b.rows > 0) {
      FP_CUDA_TRY(
          LaunchGatherAtRows(y, s_.as<int>() + b.rowList, b.rows, rowWork_.as<float>(), st));
      FP_CUBLAS_TRY(cublasSgemv(blas_, CUBLAS_OP_T, b.rows, b.columns, &minusOne, L + b.columns,
                                b.columns + b.rows, rowWork_.as<float>(), 1, &one, y + b.first, 1));
    }
    float* x1 = work_.as<float>();
    FP_CUBLAS_TRY(cublasSgemv(blas_, CUBLAS_OP_T, b.columns, b.columns, &one,
                              inverses_.as<float>() + b.inverse, b.columns, y + b.first, 1, &zero,
                              x1, 1));
    FP_CUDA_TRY(
        cudaMemcpyAsync(y + b.first, x1, sizeof(float) * b.columns, cudaMemcpyDeviceToDevice, st));
    return true;
  }

  // The substitution as one CUDA graph: a sweep is as many kernels as the tree has levels, and a
  // graph launches them for a fraction of their separate launches' cost. Without one (its capture
  // failed), the kernels are launched one by one.
  void captureSubstitution() {
    std::string error;
    cudaStream_t st = stream_.get();
    cudaGraph_t graph = nullptr;
    if (cudaStreamBeginCapture(st, cudaStreamCaptureModeThreadLocal) != cudaSuccess)
      return;
    const bool enqueued = enqueueSubstitution(st, error);
    const bool ended = cudaStreamEndCapture(st, &graph) == cudaSuccess;
    if (enqueued && ended && graph && cudaGraphInstantiate(&graph_, graph, 0) != cudaSuccess)
      graph_ = nullptr;
    if (graph)
      cudaGraphDestroy(graph);
    cudaGetLastError(); // a failed capture leaves no error behind for the next call
    // A graph's first launch uploads it to the device, and the first substitution with a fresh
    // factor is the drag step's predictor, which the user waits for: here, on the background
    // thread that made the factor, it is uploaded and run once on a zero right-hand side.
    if (graph_) {
      std::fill(hostIn_.as<double>(), hostIn_.as<double>() + n_, 0.0);
      hostIn_.as<double>()[n_] = 1.0;
      if (cudaGraphUpload(graph_, st) != cudaSuccess ||
          cudaGraphLaunch(graph_, st) != cudaSuccess || cudaStreamSynchronize(st) != cudaSuccess) {
        cudaGraphExecDestroy(graph_);
        graph_ = nullptr;
        cudaGetLastError();
      }
    }
  }

  // x from hostIn_'s right-hand side and scale (hostIn_[n]).
  bool substitute(Eigen::VectorXd& x, std::string& error) {
    cudaStream_t st = stream_.get();
    FP_CUDA_TRY(cudaSetDevice(0));
    if (graph_) {
      FP_CUDA_TRY(cudaGraphLaunch(graph_, st));
    } else if (!enqueueSubstitution(st, error)) {
      return false;
    }
    FP_CUDA_TRY(cudaStreamSynchronize(st));
    if (!CopyFinite(hostOut_.as<double>(), static_cast<size_t>(n_), x)) {
      error = "the single-precision substitution overflowed";
      return false;
    }
    return true;
  }

  bool product(const Eigen::VectorXd& v, Eigen::VectorXd& out, std::string& error) {
    cudaStream_t st = stream_.get();
    FP_CUDA_TRY(cudaSetDevice(0));
    if (!upload(v, error))
      return false;
    FP_CUDA_TRY(cudaMemsetAsync(x_.as<double>(), 0, sizeof(double) * n_, st));
    FP_CUDA_TRY(LaunchSymmetricUpperProduct(rows_.as<int>(), cols_.as<int>(), entries_.as<double>(),
                                            nnz_, b_.as<double>(), x_.as<double>(), st));
    return download(out, error);
  }

  std::mutex mutex_;
  OwnStream stream_;
  cudaGraphExec_t graph_ = nullptr;
  cublasHandle_t blas_ = nullptr;
  std::vector<std::vector<Large>> big_; // per level
  DeviceArray inverses_, work_, rowWork_;
  int largeCount_ = 0;
  int n_ = 0, supernodes_ = 0, maxRows_ = 0;
  std::int64_t nnz_ = 0;
  double valueBytes_ = 0.0;
  std::vector<int> levelStart_, levelRows_;
  DeviceArray super_, pi_, px_, s_, values_, perm_, order_, rows_, cols_, entries_;
  DeviceArray b_, x_, y_;
  PinnedArray hostIn_, hostOut_;
  SupernodalSweepArrays arrays_;
};

} // namespace

Status MakeCudaHyperelasticForces(const HyperelasticCells& cells,
                                  std::unique_ptr<HyperelasticForces>& forces) {
  auto made = std::make_unique<CudaForces>();
  std::string error;
  if (!made->init(cells, error))
    return Status::Error(error);
  forces = std::move(made);
  return Status::Ok();
}

Status MakeCudaFactorOnDevice(const SinglePrecisionFactor& factor, const SparseMatrix& upper,
                              std::unique_ptr<FactorOnDevice>& device) {
  auto made = std::make_unique<CudaFactor>();
  std::string error;
  if (!made->init(factor, upper, error))
    return Status::Error(error);
  device = std::move(made);
  return Status::Ok();
}

bool ShapeOfFactorOnDevice(const FactorOnDevice& device, SweepShape& shape) {
  const auto* made = dynamic_cast<const CudaFactor*>(&device);
  if (!made)
    return false;
  shape = made->shape();
  return true;
}

} // namespace faceplan::cuda::detail
