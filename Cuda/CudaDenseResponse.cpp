// SPDX-License-Identifier: BSD-3-Clause
#include "CudaDenseResponse.h"

#include "Common/InversePermutation.h"
#include "Common/ParallelFor.h"
#include "Common/StageTimings.h"
#include "CudaCheck.h"
#include "CudaInternal.h"
#include "CudaKernels.h"
#include "SparseSolver/CholmodViews.h"
#include "SparseSolver/SupernodalTree.h"

#include <cholmod.h>
#include <cusolverDn.h>
#include <cusparse.h>
#include <future>
#include <utility>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <vector>

#define FP_CUSPARSE_TRY(expr)                                                                      \
  do {                                                                                             \
    const cusparseStatus_t fpSparseStatus_ = (expr);                                               \
    if (fpSparseStatus_ != CUSPARSE_STATUS_SUCCESS) {                                              \
      error = std::string("cuSPARSE error ") + cusparseGetErrorName(fpSparseStatus_) + " (" +      \
              cusparseGetErrorString(fpSparseStatus_) + ") in " #expr;                             \
      return false;                                                                                \
    }                                                                                              \
  } while (0)

namespace faceplan::cuda {

using detail::CudaResponse;
using detail::DeviceArray;
using detail::Upload;

namespace {

// The structure and host values of a CHOLMOD supernodal factor, without device data.
SupernodalFactorView ViewOfFactor(const cholmod_factor* L) {
  SupernodalFactorView v;
  v.n = static_cast<int>(L->n);
  v.nsuper = static_cast<int>(L->nsuper);
  v.super = static_cast<const int*>(L->super);
  v.pi = static_cast<const int*>(L->pi);
  v.px = static_cast<const int*>(L->px);
  v.s = static_cast<const int*>(L->s);
  v.x = static_cast<const double*>(L->x);
  v.perm = static_cast<const int*>(L->Perm);
  return v;
}
} // namespace

// SupernodalCholesky: Core's CholmodFactor (ordering, symbolic analysis, CPU factorization and
// solves) plus the GPU copy of its numeric factor.

struct SupernodalCholesky::Impl {
  CholmodFactor factor;
  DeviceArray deviceX; // numeric factor on the GPU (factorOnGpu)
  double analyzeMs = 0.0, factorizeMs = 0.0, downloadMs = 0.0;
  bool hostNumeric = false;

  // Drops any previous factor (host and device) and runs the ordering and symbolic analysis.
  Status analyze(const SparseMatrix& upper) {
    if (!upper.isCompressed() || upper.rows() != upper.cols())
      return Status::Error("SupernodalCholesky: the matrix must be square and compressed");
    deviceX.release();
    hostNumeric = false;
    downloadMs = 0.0;
    StageClock clock;
    factor.setSupernodeRelaxation(SupernodeRelaxation::Coarse); // the GPU's per-supernode costs
    const Status status = factor.analyze(upper);
    analyzeMs = clock.lapMs();
    return status;
  }
};

SupernodalCholesky::SupernodalCholesky() : impl_(std::make_unique<Impl>()) {}
SupernodalCholesky::~SupernodalCholesky() = default;

Status SupernodalCholesky::factor(const SparseMatrix& upper) {
  Status status = impl_->analyze(upper);
  if (!status)
    return status;
  StageClock clock;
  status = impl_->factor.factorize(upper);
  impl_->factorizeMs = clock.lapMs();
  if (!status)
    return status;
  const cholmod_factor* L = impl_->factor.cholmodFactor();
  if (!L->is_super || !L->is_ll || L->itype != CHOLMOD_INT)
    return Status::Error("CHOLMOD did not return a supernodal LL^T factor with 32-bit indices");
  impl_->hostNumeric = true;
  return Status::Ok();
}

#define FP_CUSOLVER_TRY(expr)                                                                      \
  do {                                                                                             \
    const cusolverStatus_t fpSolverStatus_ = (expr);                                               \
    if (fpSolverStatus_ != CUSOLVER_STATUS_SUCCESS) {                                              \
      error =                                                                                      \
          "cuSOLVER error " + std::to_string(static_cast<int>(fpSolverStatus_)) + " in " #expr;    \
      return false;                                                                                \
    }                                                                                              \
  } while (0)

namespace {
struct FactorResources {
  cudaStream_t stream = nullptr;
  cublasHandle_t blas = nullptr;
  cusolverDnHandle_t solver = nullptr;
  ~FactorResources() {
    if (solver)
      cusolverDnDestroy(solver);
    if (blas)
      cublasDestroy(blas);
    if (stream)
      cudaStreamDestroy(stream);
  }
};
} // namespace

Status SupernodalCholesky::factorOnGpu(const SparseMatrix& upper, bool hostCopy) {
  std::string error;
  if (!detail::InitDevice(error))
    return Status::Error(error);
  Status status = impl_->analyze(upper);
  if (!status)
    return status;
  if (!detail::FactorAnalysedOnGpu(upper, impl_->factor.cholmodFactor(),
                                   impl_->factor.cholmodCommon(), impl_->deviceX, hostCopy,
                                   impl_->factorizeMs, impl_->downloadMs, error))
    return Status::Error(error);
  if (hostCopy) {
    status = impl_->factor.markFactorized();
    if (!status)
      return status;
  }
  impl_->hostNumeric = hostCopy;
  return Status::Ok();
}

namespace detail {

bool FactorAnalysedOnGpu(const SparseMatrix& upper, cholmod_factor* L, cholmod_common* common,
                         DeviceArray& deviceX, bool hostCopy, double& factorizeMs,
                         double& downloadMs, std::string& error) {
  factorizeMs = downloadMs = 0.0;
  if (!upper.isCompressed() || upper.rows() != upper.cols() || !L || !common ||
      L->n != static_cast<size_t>(upper.rows())) {
    error = "GPU factorization: the matrix must be square, compressed and match the analysis";
    return false;
  }
  if (!InitDevice(error))
    return false;
  StageClock clock;
  if (!L->is_super || L->itype != CHOLMOD_INT) {
    error = "CHOLMOD's analysis is not supernodal with 32-bit indices";
    return false;
  }
  const int n = static_cast<int>(L->n), nsuper = static_cast<int>(L->nsuper);
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* px = static_cast<const int*>(L->px);
  const int* perm = static_cast<const int*>(L->Perm);
  const std::vector<int> pinv = InversePermutation(perm, n);
  std::vector<int> colSuper(n);
  std::vector<std::int64_t> px64(nsuper + 1);
  int maxCol = 1, maxRow = 1;
  long long maxUpdate = 1;
  for (int t = 0; t < nsuper; ++t) {
    for (int k = super[t]; k < super[t + 1]; ++k)
      colSuper[k] = t;
    const int nscol = super[t + 1] - super[t], nsrow = pi[t + 1] - pi[t];
    maxCol = std::max(maxCol, nscol);
    maxRow = std::max(maxRow, nsrow);
    maxUpdate = std::max(maxUpdate, static_cast<long long>(nsrow - nscol) * (nsrow - nscol));
  }
  for (int t = 0; t <= nsuper; ++t)
    px64[t] = px[t];
  const size_t xsize = static_cast<size_t>(px[nsuper]);

  FactorResources r;
  FP_CUDA_TRY(cudaStreamCreateWithFlags(&r.stream, cudaStreamNonBlocking));
  FP_CUBLAS_TRY(cublasCreate(&r.blas));
  FP_CUBLAS_TRY(cublasSetStream(r.blas, r.stream));
  FP_CUSOLVER_TRY(cusolverDnCreate(&r.solver));
  FP_CUSOLVER_TRY(cusolverDnSetStream(r.solver, r.stream));
  DeviceArray dSuper, dPi, dPx, dS, dColSuper, dPinv, dStart, dRow, dVal, dC, dWork, dInfo;
  if (!Upload(dSuper, super, nsuper + 1, r.stream, error) ||
      !Upload(dPi, pi, nsuper + 1, r.stream, error) ||
      !Upload(dPx, px64.data(), px64.size(), r.stream, error) ||
      !Upload(dS, static_cast<const int*>(L->s), static_cast<size_t>(pi[nsuper]), r.stream,
              error) ||
      !Upload(dColSuper, colSuper.data(), colSuper.size(), r.stream, error) ||
      !Upload(dPinv, pinv.data(), pinv.size(), r.stream, error) ||
      !Upload(dStart, upper.outerIndexPtr(), static_cast<size_t>(n) + 1, r.stream, error) ||
      !Upload(dRow, upper.innerIndexPtr(), static_cast<size_t>(upper.nonZeros()), r.stream,
              error) ||
      !Upload(dVal, upper.valuePtr(), static_cast<size_t>(upper.nonZeros()), r.stream, error))
    return false;
  if (!deviceX.ensure(sizeof(double) * std::max<size_t>(xsize, 1), error) ||
      !dC.ensure(sizeof(double) * static_cast<size_t>(maxUpdate), error) ||
      !dInfo.ensure(sizeof(int) * std::max(nsuper, 1), error))
    return false;
  int lwork = 0;
  FP_CUSOLVER_TRY(cusolverDnDpotrf_bufferSize(r.solver, CUBLAS_FILL_MODE_LOWER, maxCol,
                                              deviceX.as<double>(), maxRow, &lwork));
  if (!dWork.ensure(sizeof(double) * (2 * static_cast<size_t>(std::max(lwork, 1)) + 256), error))
    return false;
  double* Lx = deviceX.as<double>();
  FP_CUDA_TRY(cudaMemsetAsync(Lx, 0, sizeof(double) * xsize, r.stream));
  FP_CUDA_TRY(cudaMemsetAsync(dInfo.as<int>(), 0, sizeof(int) * std::max(nsuper, 1), r.stream));
  SupernodalStructure st;
  st.super = dSuper.as<int>();
  st.pi = dPi.as<int>();
  st.px = dPx.as<std::int64_t>();
  st.s = dS.as<int>();
  st.colSuper = dColSuper.as<int>();
  FP_CUDA_TRY(LaunchAssembleSupernodal(dStart.as<int>(), dRow.as<int>(), dVal.as<double>(), n,
                                       dPinv.as<int>(), st, Lx, r.stream));
  const double one = 1.0, zero = 0.0;
  for (int t = 0; t < nsuper; ++t) {
    const int nscol = super[t + 1] - super[t], nsrow = pi[t + 1] - pi[t], off = nsrow - nscol;
    double* block = Lx + px64[t];
    FP_CUSOLVER_TRY(cusolverDnDpotrf(r.solver, CUBLAS_FILL_MODE_LOWER, nscol, block, nsrow,
                                     dWork.as<double>(), 2 * std::max(lwork, 1),
                                     dInfo.as<int>() + t));
    if (off > 0) {
      FP_CUBLAS_TRY(cublasDtrsm(r.blas, CUBLAS_SIDE_RIGHT, CUBLAS_FILL_MODE_LOWER, CUBLAS_OP_T,
                                CUBLAS_DIAG_NON_UNIT, off, nscol, &one, block, nsrow, block + nscol,
                                nsrow));
      FP_CUBLAS_TRY(cublasDsyrk(r.blas, CUBLAS_FILL_MODE_LOWER, CUBLAS_OP_N, off, nscol, &one,
                                block + nscol, nsrow, &zero, dC.as<double>(), off));
      FP_CUDA_TRY(LaunchScatterUpdate(dC.as<double>(), off, dS.as<int>() + pi[t] + nscol, st, Lx,
                                      r.stream));
    }
  }
  std::vector<int> info(std::max(nsuper, 1));
  FP_CUDA_TRY(cudaMemcpyAsync(info.data(), dInfo.as<int>(), sizeof(int) * info.size(),
                              cudaMemcpyDeviceToHost, r.stream));
  FP_CUDA_TRY(cudaStreamSynchronize(r.stream));
  factorizeMs = clock.lapMs();
  for (int t = 0; t < nsuper; ++t)
    if (info[t] != 0) {
      deviceX.release();
      error = "matrix is not positive definite (GPU factorization stopped at column " +
              std::to_string(super[t] + std::abs(info[t]) - 1) + ")";
      return false;
    }
  if (hostCopy) {
    if (!AllocateHostFactor(L, common, error) || !DownloadFactor(L, deviceX, r.stream, error))
      return false;
    downloadMs = clock.lapMs();
  }
  return true;
}

bool AllocateHostFactor(cholmod_factor* L, cholmod_common* common, std::string& error) {
  const size_t xsize = static_cast<size_t>(static_cast<const int*>(L->px)[L->nsuper]);
  if (!cholmod_change_factor(CHOLMOD_REAL, 1, 1, 1, 1, L, common) || !L->x || L->xsize != xsize) {
    error = "CHOLMOD could not allocate the numeric factor";
    return false;
  }
  return true;
}

bool DownloadFactor(cholmod_factor* L, const DeviceArray& deviceX, cudaStream_t stream,
                    std::string& error) {
  const size_t xsize = static_cast<size_t>(static_cast<const int*>(L->px)[L->nsuper]);
  if (!L->x || L->xsize != xsize) {
    error = "internal: the host factor is not allocated";
    return false;
  }
  if (!DownloadLarge(L->x, deviceX.as<double>(), sizeof(double) * xsize, stream, error))
    return false;
  L->minor = L->n;
  return true;
}

} // namespace detail

void SupernodalCholesky::releaseDevice() {
  impl_->deviceX.release();
}

Status SupernodalCholesky::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  if (!impl_->hostNumeric)
    return Status::Error("SupernodalCholesky: no numeric factor on the host");
  return impl_->factor.solve(b, x);
}

SupernodalFactorView SupernodalCholesky::view() const {
  const cholmod_factor* L = impl_->factor.cholmodFactor();
  if (!L || !L->is_super)
    return SupernodalFactorView();
  SupernodalFactorView v = ViewOfFactor(L);
  if (!impl_->hostNumeric)
    v.x = nullptr;
  v.deviceX = impl_->deviceX.capacity() > 0 ? impl_->deviceX.as<double>() : nullptr;
  return v;
}

double SupernodalCholesky::analyzeMs() const {
  return impl_->analyzeMs;
}
double SupernodalCholesky::factorizeMs() const {
  return impl_->factorizeMs;
}
double SupernodalCholesky::downloadMs() const {
  return impl_->downloadMs;
}
double SupernodalCholesky::factorNonzeros() const {
  return impl_->factor.factorNonzeros();
}

// ---------------------------------------------------------------------------------------------
// BuildDenseResponse

namespace {

// Streams of the backward sweep: the supernodes of different subtrees of the elimination tree are
// independent there, so subtrees run on their own streams, each with its own cuBLAS handle and
// workspace, and wait only for their parent supernode. FACEPLAN_CUDA_SWEEP_STREAMS overrides the
// count (1: one stream, the supernodes in sequence), for measuring.
int SweepStreamCount() {
  if (const char* text = std::getenv("FACEPLAN_CUDA_SWEEP_STREAMS"); text && *text)
    return std::clamp(std::atoi(text), 1, 16);
  return 4;
}

// The extra streams (entries 1..count-1; entry 0 stays null: stream 0 is the response's own), their
// handles and events.
struct SweepStreams {
  std::vector<cudaStream_t> stream;
  std::vector<cublasHandle_t> blas;
  std::vector<cudaEvent_t> done;       // per supernode that has a child on another stream
  std::vector<cudaEvent_t> streamDone; // per extra stream, at the end of a sweep
  ~SweepStreams() {
    for (cublasHandle_t h : blas)
      if (h)
        cublasDestroy(h);
    for (cudaEvent_t e : done)
      if (e)
        cudaEventDestroy(e);
    for (cudaEvent_t e : streamDone)
      if (e)
        cudaEventDestroy(e);
    for (cudaStream_t q : stream)
      if (q)
        cudaStreamDestroy(q);
  }
};

struct Resources {
  cudaStream_t stream = nullptr;
  cudaStream_t download = nullptr; // the response's columns to the host, beside the residual
  cublasHandle_t blas = nullptr;
  cusparseHandle_t sparse = nullptr;
  cusparseSpMatDescr_t K = nullptr;
  cudaEvent_t ev[8] = {};
  ~Resources() {
    if (K)
      cusparseDestroySpMat(K);
    if (sparse)
      cusparseDestroy(sparse);
    if (blas)
      cublasDestroy(blas);
    for (cudaEvent_t& e : ev)
      if (e)
        cudaEventDestroy(e);
    if (stream)
      cudaStreamDestroy(stream);
    if (download)
      cudaStreamDestroy(download);
  }
};

// Full symmetric K_perm = P K P^T in CSR (sorted columns), for the residual check.
struct PermutedCsr {
  std::vector<int> rowStart, col;
  std::vector<double> val;
};

// K_perm from the upper triangle of K and the inverse permutation.
void PermutedFullCsr(const SparseMatrix& upper, const std::vector<int>& pinv, PermutedCsr& out) {
  std::vector<int>& rowStart = out.rowStart;
  std::vector<int>& col = out.col;
  std::vector<double>& val = out.val;
  const int n = static_cast<int>(upper.cols());
  rowStart.assign(n + 1, 0);
  const int* outer = upper.outerIndexPtr();
  const int* inner = upper.innerIndexPtr();
  const double* v = upper.valuePtr();
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      const int i = inner[p];
      ++rowStart[pinv[i] + 1];
      if (i != j)
        ++rowStart[pinv[j] + 1];
    }
  for (int r = 0; r < n; ++r)
    rowStart[r + 1] += rowStart[r];
  col.resize(rowStart[n]);
  val.resize(rowStart[n]);
  std::vector<int> fill(rowStart.begin(), rowStart.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      const int i = inner[p], a = pinv[i], b = pinv[j];
      col[fill[a]] = b;
      val[fill[a]++] = v[p];
      if (i != j) {
        col[fill[b]] = a;
        val[fill[b]++] = v[p];
      }
    }
  ParallelFor(n, 20000, [&](std::int64_t begin, std::int64_t end) {
    std::vector<std::pair<int, double>> row;
    for (std::int64_t r = begin; r < end; ++r) {
      const int s = rowStart[r], e = rowStart[r + 1];
      row.clear();
      for (int k = s; k < e; ++k)
        row.emplace_back(col[k], val[k]);
      std::sort(row.begin(), row.end(),
                [](const auto& x, const auto& y) { return x.first < y.first; });
      for (int k = s; k < e; ++k) {
        col[k] = row[k - s].first;
        val[k] = row[k - s].second;
      }
    }
  });
}

bool Elapsed(cudaEvent_t a, cudaEvent_t b, double& accumulate, std::string& error) {
  float ms = 0.f;
  FP_CUDA_TRY(cudaEventElapsedTime(&ms, a, b));
  accumulate += ms;
  return true;
}

// The dense response on the GPU, in stages: check the inputs, plan the forward sweep's reach and
// the backward sweep's streams, upload the fixed data, size the passes, then per pass of columns
// scatter the right-hand sides, sweep forward and backward, extract the kept rows (and copy them
// to the host beside the rest), check the residual and collect the pass's device times; finally
// hand the response to its operator. Members are declared in the order they must outlive each
// other: the host copy (`download`), declared last, is waited for first.
class ResponseBuilder {
public:
  ResponseBuilder(const SupernodalFactorView& L, const SparseMatrix* kff, const SparseMatrix& kfr,
                  Eigen::MatrixXd* responseHost, std::unique_ptr<ResponseOperator>* op,
                  DenseResponseDetail& detail, std::string& error)
      : L(L), kff(kff), kfr(kfr), responseHost(responseHost), op(op), detail(detail), error(error) {
  }

  // `prepared`: K_perm already made (FactorAndBuildResponse makes it while the GPU factorizes),
  // or null to make it here.
  bool run(Eigen::Index keptRowsIn, int maxColumnsPerPass, PermutedCsr* prepared) {
    if (!checkInputs(keptRowsIn))
      return false;
    if (responseHost)
      responseHost->resize(keptRows, roi);
    if (keptRows == 0 || roi == 0)
      return finishEmpty();
    startHostPageTouch();
    if (!planForwardSweep() || !createResources() || !planSweepStreams() ||
        !uploadFixedData(prepared) || !sizePasses(maxColumnsPerPass))
      return false;
    for (int c0 = 0; c0 < roi; c0 += nbMax) {
      const int nb = std::min(nbMax, roi - c0);
      ++detail.blocks;
      if (!scatterRightHandSides(c0, nb) || !forwardSweep(nb) || !backwardSweep(nb) ||
          !extractAndDownload(c0, nb) || !checkResidual(c0, nb) || !collectPass(c0, nb))
        return false;
    }
    return finish();
  }

private:
  bool checkInputs(Eigen::Index keptRowsIn) {
    n = L.n;
    if (n <= 0 || !L.super || !L.pi || !L.px || !L.s || !(L.x || L.deviceX) || !L.perm) {
      error = "BuildDenseResponse: no supernodal factor";
      return false;
    }
    if (kfr.rows() != n || keptRowsIn < 0 || keptRowsIn > n || !kfr.isCompressed() ||
        (kff && (kff->rows() != n || kff->cols() != n || !kff->isCompressed()))) {
      error = "BuildDenseResponse: the matrices do not match the factor";
      return false;
    }
    keptRows = static_cast<int>(keptRowsIn);
    roi = static_cast<int>(kfr.cols());
    return detail::InitDevice(error);
  }

  bool finishEmpty() {
    if (responseHost)
      responseHost->setZero();
    if (op) {
      auto cudaOp = std::make_unique<CudaResponse>();
      if (!cudaOp->init(Eigen::MatrixXd::Zero(keptRows, roi), error))
        return false;
      *op = std::move(cudaOp);
    }
    return true;
  }

  // The host response's pages are first touched here, on every core, while the GPU sweeps run:
  // faulted in by the download itself, the copy of a response of several GB ran at a fraction of
  // the link's rate. The future waits in its destructor, so no exit path leaves it running.
  void startHostPageTouch() {
    if (responseHost)
      hostPagesTouched =
          std::async(std::launch::async, [host = responseHost]() {
            detail::TouchPagesInParallel(host->data(), static_cast<std::int64_t>(host->size()));
          }).share();
  }

  // Host-side structure: inverse permutation, largest off-diagonal block, flops. The forward
  // sweep visits only the supernodes that L^-1 K_FR can be non-zero on: those of the rows K_FR
  // touches and the ones above them. With the ROI-coupled DOFs ordered last that is the trailing
  // block alone.
  bool planForwardSweep() {
    pinv = InversePermutation(L.perm, n);
    detail.supernodes = L.nsuper;
    std::vector<int> coupledRows(kfr.innerIndexPtr(), kfr.innerIndexPtr() + kfr.nonZeros());
    for (int& row : coupledRows)
      row = pinv[row];
    if (const Status marked = MarkSupernodesAbove(tree, coupledRows, reached); !marked) {
      error = marked.message;
      return false;
    }
    for (int s = 0; s < L.nsuper; ++s) {
      const SupernodeShape shape = tree.shape(s);
      maxOff = std::max(maxOff, shape.offDiagonal);
      flopsPerColumn += (reached[s] ? 2.0 : 1.0) * shape.flops();
    }
    return true;
  }

  bool createResources() {
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&r.stream, cudaStreamNonBlocking));
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&r.download, cudaStreamNonBlocking));
    for (cudaEvent_t& e : r.ev)
      FP_CUDA_TRY(cudaEventCreate(&e));
    FP_CUBLAS_TRY(cublasCreate(&r.blas));
    FP_CUBLAS_TRY(cublasSetStream(r.blas, r.stream));
    FP_CUBLAS_TRY(cublasSetPointerMode(r.blas, CUBLAS_POINTER_MODE_HOST));
    return true;
  }

  // The backward sweep's subtrees on streams: each supernode's parent is the supernode of its
  // first off-diagonal row; going down from the roots, a supernode's first child keeps its stream
  // and the others take the next stream in turn. A supernode waits for its parent's event only
  // when the parent ran on another stream (the parent's own wait covers the ancestors above it).
  bool planSweepStreams() {
    streamCount = SweepStreamCount();
    parentOf = SupernodeParents(tree, SupernodeOfColumns(tree));
    sweepStream.assign(L.nsuper, 0);
    needsEvent.assign(L.nsuper, 0);
    std::vector<char> parentHasChild(L.nsuper, 0);
    int nextStream = 0;
    for (int s = L.nsuper - 1; s >= 0; --s) {
      const int p = parentOf[s];
      if (p < 0 || streamCount == 1) {
        sweepStream[s] = p < 0 ? 0 : sweepStream[p];
      } else if (!parentHasChild[p]) {
        sweepStream[s] = sweepStream[p];
      } else {
        nextStream = (nextStream + 1) % streamCount;
        sweepStream[s] = nextStream;
      }
      if (p >= 0) {
        parentHasChild[p] = 1;
        if (sweepStream[s] != sweepStream[p])
          needsEvent[p] = 1;
      }
    }
    sweep.stream.assign(streamCount, nullptr);
    sweep.blas.assign(streamCount, nullptr);
    sweep.streamDone.assign(streamCount, nullptr);
    sweep.done.assign(L.nsuper, nullptr);
    for (int q = 1; q < streamCount; ++q) {
      FP_CUDA_TRY(cudaStreamCreateWithFlags(&sweep.stream[q], cudaStreamNonBlocking));
      FP_CUBLAS_TRY(cublasCreate(&sweep.blas[q]));
      FP_CUBLAS_TRY(cublasSetStream(sweep.blas[q], sweep.stream[q]));
      FP_CUBLAS_TRY(cublasSetPointerMode(sweep.blas[q], CUBLAS_POINTER_MODE_HOST));
      FP_CUDA_TRY(cudaEventCreateWithFlags(&sweep.streamDone[q], cudaEventDisableTiming));
    }
    for (int s = 0; s < L.nsuper; ++s)
      if (needsEvent[s])
        FP_CUDA_TRY(cudaEventCreateWithFlags(&sweep.done[s], cudaEventDisableTiming));
    return true;
  }
  cudaStream_t streamFor(int q) const { return q == 0 ? r.stream : sweep.stream[q]; }
  cublasHandle_t blasFor(int q) const { return q == 0 ? r.blas : sweep.blas[q]; }

  // Fixed device data: factor, permutation, K_FR, K_perm (for the residual); between events 0
  // and 1.
  bool uploadFixedData(PermutedCsr* prepared) {
    const size_t lxCount = static_cast<size_t>(L.px[L.nsuper]);
    const size_t lsCount = static_cast<size_t>(L.pi[L.nsuper]);
    kPerm = prepared ? prepared : &madeHere;
    if (kff && !prepared)
      PermutedFullCsr(*kff, pinv, madeHere);
    if (kff && kPerm->rowStart.size() != static_cast<size_t>(n) + 1) {
      error = "internal: the prepared K_perm does not match the factor";
      return false;
    }
    detail.hostPrepareMs = hostClock.lapMs();

    FP_CUDA_TRY(cudaEventRecord(r.ev[0], r.stream));
    if ((!L.deviceX && !Upload(dLx, L.x, lxCount, r.stream, error)) ||
        !Upload(dLs, L.s, lsCount, r.stream, error) ||
        !Upload(dPinv, pinv.data(), pinv.size(), r.stream, error) ||
        !Upload(dFrStart, kfr.outerIndexPtr(), static_cast<size_t>(roi) + 1, r.stream, error) ||
        !Upload(dFrRow, kfr.innerIndexPtr(), static_cast<size_t>(kfr.nonZeros()), r.stream,
                error) ||
        !Upload(dFrVal, kfr.valuePtr(), static_cast<size_t>(kfr.nonZeros()), r.stream, error))
      return false;
    if (kff && (!Upload(dKStart, kPerm->rowStart.data(), kPerm->rowStart.size(), r.stream, error) ||
                !Upload(dKCol, kPerm->col.data(), kPerm->col.size(), r.stream, error) ||
                !Upload(dKVal, kPerm->val.data(), kPerm->val.size(), r.stream, error)))
      return false;
    FP_CUDA_TRY(cudaEventRecord(r.ev[1], r.stream));
    hostClock.lapMs();
    return dResponse.ensure(sizeof(double) * static_cast<size_t>(keptRows) * roi, error);
  }

  // Columns per pass: Y (n x nb) and T (maxOff x nb per sweep stream); R is fixed (n x chunk).
  // The residual is checked in chunks of kResidualColumns columns through one n x chunk buffer:
  // one n x nb buffer could cost a second pass on the largest meshes, and each pass walks every
  // supernode.
  bool sizePasses(int maxColumnsPerPass) {
    size_t freeBytes = 0, totalBytes = 0;
    FP_CUDA_TRY(cudaMemGetInfo(&freeBytes, &totalBytes));
    constexpr int kResidualColumns = 512;
    residualColumns = std::min(kResidualColumns, roi);
    const double perColumn = 8.0 * (double(n) + double(streamCount) * double(maxOff)) + 8.0;
    const double usable = double(freeBytes) * 0.9 - 512.0 * 1024 * 1024 -
                          (kff ? 8.0 * double(n) * double(residualColumns) : 0.0);
    const long long fit = usable > 0 ? static_cast<long long>(usable / perColumn) : 0;
    if (fit < 1) {
      error = "not enough GPU memory for the dense response's right-hand sides";
      return false;
    }
    nbMax = static_cast<int>(std::min<long long>(roi, fit));
    if (maxColumnsPerPass > 0)
      nbMax = std::min(nbMax, maxColumnsPerPass);
    detail.columnsPerBlock = nbMax;
    const size_t yCount = static_cast<size_t>(n) * nbMax;
    if (!dY.ensure(sizeof(double) * yCount, error) ||
        !dT.ensure(sizeof(double) *
                       std::max<size_t>(static_cast<size_t>(streamCount) * maxOff * nbMax, 1),
                   error) ||
        !dSums.ensure(sizeof(double) * nbMax, error))
      return false;
    if (kff) {
      if (!dR.ensure(sizeof(double) * static_cast<size_t>(n) * std::min(residualColumns, nbMax),
                     error))
        return false;
      FP_CUSPARSE_TRY(cusparseCreate(&r.sparse));
      FP_CUSPARSE_TRY(cusparseSetStream(r.sparse, r.stream));
      FP_CUSPARSE_TRY(cusparseCreateCsr(&r.K, n, n, static_cast<int64_t>(kPerm->col.size()),
                                        dKStart.as<int>(), dKCol.as<int>(), dKVal.as<double>(),
                                        CUSPARSE_INDEX_32I, CUSPARSE_INDEX_32I,
                                        CUSPARSE_INDEX_BASE_ZERO, CUDA_R_64F));
    }

    // Norms of the right-hand sides (columns of K_FR) for the relative residual.
    rhsNorm.assign(roi, 0.0);
    for (int c = 0; c < roi; ++c)
      for (int p = kfr.outerIndexPtr()[c]; p < kfr.outerIndexPtr()[c + 1]; ++p)
        rhsNorm[c] += kfr.valuePtr()[p] * kfr.valuePtr()[p];

    detail.allocateMs = hostClock.lapMs();
    Y = dY.as<double>();
    T = dT.as<double>();
    Lx = L.deviceX ? L.deviceX : dLx.as<double>();
    Ls = dLs.as<int>();
    sums.resize(nbMax);
    return true;
  }

  // Y = P K_FR(:, c0 : c0 + nb), row-major; event 2 marks the forward sweep's start.
  bool scatterRightHandSides(int c0, int nb) {
    FP_CUDA_TRY(cudaMemsetAsync(Y, 0, sizeof(double) * static_cast<size_t>(n) * nb, r.stream));
    FP_CUDA_TRY(detail::LaunchScatterCsc(dFrStart.as<int>(), dFrRow.as<int>(), dFrVal.as<double>(),
                                         dPinv.as<int>(), c0, nb, 1.0, Y, r.stream));
    FP_CUDA_TRY(cudaEventRecord(r.ev[2], r.stream));
    return true;
  }

  // Forward: L Z = Y. Rows of a supernode are columns of the cuBLAS view (nb x n, ld nb).
  bool forwardSweep(int nb) {
    for (int s = 0; s < L.nsuper; ++s) {
      if (!reached[s])
        continue; // Y stays zero there
      const int k1 = L.super[s], nscol = L.super[s + 1] - k1, nsrow = L.pi[s + 1] - L.pi[s];
      const int off = nsrow - nscol;
      const double* block = Lx + L.px[s];
      double* Y1 = Y + static_cast<size_t>(k1) * nb;
      FP_CUBLAS_TRY(cublasDtrsm(r.blas, CUBLAS_SIDE_RIGHT, CUBLAS_FILL_MODE_LOWER, CUBLAS_OP_T,
                                CUBLAS_DIAG_NON_UNIT, nb, nscol, &one, block, nsrow, Y1, nb));
      if (off > 0) {
        FP_CUBLAS_TRY(cublasDgemm(r.blas, CUBLAS_OP_N, CUBLAS_OP_T, nb, off, nscol, &one, Y1, nb,
                                  block + nscol, nsrow, &zero, T, nb));
        FP_CUDA_TRY(
            detail::LaunchScatterSubtractRows(Y, T, Ls + L.pi[s] + nscol, off, nb, r.stream));
      }
    }
    FP_CUDA_TRY(cudaEventRecord(r.ev[3], r.stream));
    return true;
  }

  // Backward: L^T X = Z, the subtrees on their streams (SweepStreams); event 4 at its end.
  bool backwardSweep(int nb) {
    for (int q = 1; q < streamCount; ++q)
      FP_CUDA_TRY(cudaStreamWaitEvent(sweep.stream[q], r.ev[3], 0));
    for (int s = L.nsuper - 1; s >= 0; --s) {
      const int k1 = L.super[s], nscol = L.super[s + 1] - k1, nsrow = L.pi[s + 1] - L.pi[s];
      const int off = nsrow - nscol;
      const int q = sweepStream[s];
      cudaStream_t stream = streamFor(q);
      cublasHandle_t blas = blasFor(q);
      double* Tq = T + static_cast<size_t>(q) * maxOff * nb;
      if (parentOf[s] >= 0 && sweepStream[parentOf[s]] != q)
        FP_CUDA_TRY(cudaStreamWaitEvent(stream, sweep.done[parentOf[s]], 0));
      const double* block = Lx + L.px[s];
      double* X1 = Y + static_cast<size_t>(k1) * nb;
      if (off > 0) {
        FP_CUDA_TRY(detail::LaunchGatherRows(Y, Tq, Ls + L.pi[s] + nscol, off, nb, stream));
        FP_CUBLAS_TRY(cublasDgemm(blas, CUBLAS_OP_N, CUBLAS_OP_N, nb, nscol, off, &minusOne, Tq, nb,
                                  block + nscol, nsrow, &one, X1, nb));
      }
      FP_CUBLAS_TRY(cublasDtrsm(blas, CUBLAS_SIDE_RIGHT, CUBLAS_FILL_MODE_LOWER, CUBLAS_OP_N,
                                CUBLAS_DIAG_NON_UNIT, nb, nscol, &one, block, nsrow, X1, nb));
      if (needsEvent[s])
        FP_CUDA_TRY(cudaEventRecord(sweep.done[s], stream));
    }
    for (int q = 1; q < streamCount; ++q) {
      FP_CUDA_TRY(cudaEventRecord(sweep.streamDone[q], sweep.stream[q]));
      FP_CUDA_TRY(cudaStreamWaitEvent(r.stream, sweep.streamDone[q], 0));
    }
    FP_CUDA_TRY(cudaEventRecord(r.ev[4], r.stream));
    return true;
  }

  // Each pass's response columns go to the host on their own stream and thread as soon as they
  // are extracted, while the GPU checks that pass's residual (and runs the next pass). One copy
  // at a time.
  void startDownload(int c0, int nb) {
    const size_t offset = static_cast<size_t>(keptRows) * c0;
    const size_t bytes = sizeof(double) * static_cast<size_t>(keptRows) * nb;
    download = std::async(std::launch::async, [this, offset, bytes]() {
      StageClock own;
      hostPagesTouched.wait();
      hostTouchWaitMs += own.lapMs();
      const bool ok =
          detail::DownloadLarge(responseHost->data() + offset, dResponse.as<double>() + offset,
                                bytes, r.download, downloadError);
      downloadOwnMs += own.lapMs();
      return ok;
    });
  }

  // The kept rows into the response (events 4 to 5), then their copy to the host.
  bool extractAndDownload(int c0, int nb) {
    FP_CUDA_TRY(detail::LaunchExtractResponse(Y, dPinv.as<int>(), keptRows, nb, c0,
                                              dResponse.as<double>(), keptRows, r.stream));
    FP_CUDA_TRY(cudaEventRecord(r.ev[5], r.stream));
    if (responseHost) {
      if (download.valid() && !download.get()) {
        error = downloadError;
        return false;
      }
      FP_CUDA_TRY(cudaStreamWaitEvent(r.download, r.ev[5], 0)); // enqueued before the copies
      startDownload(c0, nb);
    }
    return true;
  }

  // Residual in the permuted numbering: R = K_perm Y - P b (norms are permutation-invariant),
  // column sums of squares into `sums`; event 6 at its end.
  bool checkResidual(int c0, int nb) {
    if (kff) {
      FP_CUDA_TRY(cudaMemsetAsync(dSums.as<double>(), 0, sizeof(double) * nb, r.stream));
      for (int j0 = 0; j0 < nb; j0 += residualColumns) {
        const int cols = std::min(residualColumns, nb - j0);
        // Columns j0.. of the row-major Y (leading dimension nb) into R (n x cols, row-major).
        cusparseDnMatDescr_t dnY = nullptr, dnR = nullptr;
        FP_CUSPARSE_TRY(
            cusparseCreateDnMat(&dnY, n, cols, nb, Y + j0, CUDA_R_64F, CUSPARSE_ORDER_ROW));
        FP_CUSPARSE_TRY(cusparseCreateDnMat(&dnR, n, cols, cols, dR.as<double>(), CUDA_R_64F,
                                            CUSPARSE_ORDER_ROW));
        size_t bufferBytes = 0;
        bool ok = cusparseSpMM_bufferSize(r.sparse, CUSPARSE_OPERATION_NON_TRANSPOSE,
                                          CUSPARSE_OPERATION_NON_TRANSPOSE, &one, r.K, dnY, &zero,
                                          dnR, CUDA_R_64F, CUSPARSE_SPMM_ALG_DEFAULT,
                                          &bufferBytes) == CUSPARSE_STATUS_SUCCESS;
        ok = ok && dSpmmBuffer.ensure(std::max<size_t>(bufferBytes, 8), error);
        const cusparseStatus_t st =
            ok ? cusparseSpMM(r.sparse, CUSPARSE_OPERATION_NON_TRANSPOSE,
                              CUSPARSE_OPERATION_NON_TRANSPOSE, &one, r.K, dnY, &zero, dnR,
                              CUDA_R_64F, CUSPARSE_SPMM_ALG_DEFAULT, dSpmmBuffer.as<void>())
               : CUSPARSE_STATUS_INTERNAL_ERROR;
        cusparseDestroyDnMat(dnY);
        cusparseDestroyDnMat(dnR);
        if (st != CUSPARSE_STATUS_SUCCESS) {
          if (error.empty())
            error = std::string("cuSPARSE SpMM failed: ") + cusparseGetErrorString(st);
          return false;
        }
        FP_CUDA_TRY(detail::LaunchScatterCsc(dFrStart.as<int>(), dFrRow.as<int>(),
                                             dFrVal.as<double>(), dPinv.as<int>(), c0 + j0, cols,
                                             -1.0, dR.as<double>(), r.stream));
        FP_CUDA_TRY(detail::LaunchColumnSquaredNorms(dR.as<double>(), n, cols,
                                                     dSums.as<double>() + j0, r.stream));
      }
      FP_CUDA_TRY(cudaMemcpyAsync(sums.data(), dSums.as<double>(), sizeof(double) * nb,
                                  cudaMemcpyDeviceToHost, r.stream));
    }
    FP_CUDA_TRY(cudaEventRecord(r.ev[6], r.stream));
    return true;
  }

  // Waits for the pass, adds its device times and its columns' relative residuals.
  bool collectPass(int c0, int nb) {
    FP_CUDA_TRY(cudaStreamSynchronize(r.stream));
    if (c0 == 0 && !Elapsed(r.ev[0], r.ev[1], detail.uploadMs, error))
      return false;
    if (!Elapsed(r.ev[2], r.ev[3], detail.forwardMs, error) ||
        !Elapsed(r.ev[3], r.ev[4], detail.backwardMs, error) ||
        !Elapsed(r.ev[4], r.ev[5], detail.extractMs, error) ||
        !Elapsed(r.ev[5], r.ev[6], detail.residualMs, error))
      return false;
    if (kff)
      for (int c = 0; c < nb; ++c) {
        const double b = std::sqrt(rhsNorm[c0 + c]);
        if (b > 0.0)
          detail.worstRelativeResidual =
              std::max(detail.worstRelativeResidual, std::sqrt(sums[c]) / b);
        if (!std::isfinite(sums[c]))
          detail.worstRelativeResidual = INFINITY;
      }
    return true;
  }

  // Waits for the host copy, frees the work buffers (after the copy: a free waits for the
  // device) and hands the device response to the operator.
  bool finish() {
    detail.flops = flopsPerColumn * roi;
    if (!std::isfinite(detail.worstRelativeResidual)) {
      error = "the GPU response has non-finite values";
      return false;
    }
    if (responseHost) {
      StageClock clock;
      const bool downloaded = download.get();
      detail.downloadWaitMs = clock.lapMs();
      detail.downloadMs = downloadOwnMs;
      detail.hostTouchWaitMs = hostTouchWaitMs;
      if (!downloaded) {
        error = downloadError;
        return false;
      }
    }
    dY.release();
    dT.release();
    dR.release();
    dLx.release();
    if (op) {
      auto cudaOp = std::make_unique<CudaResponse>();
      if (!cudaOp->adopt(keptRows, roi, std::move(dResponse), error))
        return false;
      *op = std::move(cudaOp);
    }
    return true;
  }

  static constexpr double one = 1.0, minusOne = -1.0, zero = 0.0;

  const SupernodalFactorView& L;
  const SparseMatrix* kff;
  const SparseMatrix& kfr;
  Eigen::MatrixXd* responseHost;
  std::unique_ptr<ResponseOperator>* op;
  DenseResponseDetail& detail;
  std::string& error;
  StageClock hostClock;

  int n = 0, keptRows = 0, roi = 0;
  const SupernodalStructure tree{L.n, L.nsuper, L.super, L.pi, L.s};
  std::vector<int> pinv;
  std::vector<char> reached; // supernodes the forward sweep visits
  int maxOff = 0;
  double flopsPerColumn = 0.0; // the backward sweep everywhere, the forward one where it runs
  int streamCount = 1;
  std::vector<int> parentOf, sweepStream;
  std::vector<char> needsEvent;
  int nbMax = 0, residualColumns = 0;
  std::vector<double> rhsNorm, sums;

  std::shared_future<void> hostPagesTouched;
  Resources r;
  SweepStreams sweep;
  DeviceArray dLx, dLs, dPinv, dFrStart, dFrRow, dFrVal, dKStart, dKCol, dKVal, dResponse, dY, dT,
      dR, dSums, dSpmmBuffer;
  PermutedCsr madeHere;
  PermutedCsr* kPerm = nullptr;
  double* Y = nullptr;
  double* T = nullptr;
  const double* Lx = nullptr;
  const int* Ls = nullptr;
  std::string downloadError;
  double downloadOwnMs = 0.0, hostTouchWaitMs = 0.0;
  std::future<bool> download; // last: destroyed (waited for) first
};

bool Build(const SupernodalFactorView& L, const SparseMatrix* kff, const SparseMatrix& kfr,
           Eigen::Index keptRows, Eigen::MatrixXd* responseHost,
           std::unique_ptr<ResponseOperator>* op, DenseResponseDetail& detail, std::string& error,
           int maxColumnsPerPass, PermutedCsr* prepared) {
  ResponseBuilder builder(L, kff, kfr, responseHost, op, detail, error);
  return builder.run(keptRows, maxColumnsPerPass, prepared);
}

} // namespace

Status BuildDenseResponse(const SupernodalFactorView& factor, const SparseMatrix* kffUpper,
                          const SparseMatrix& kfr, Eigen::Index keptRows,
                          Eigen::MatrixXd* responseHost, std::unique_ptr<ResponseOperator>* op,
                          DenseResponseDetail& detail, int maxColumnsPerPass) {
  detail = DenseResponseDetail{};
  StageClock clock;
  std::string error;
  const bool ok = Build(factor, kffUpper, kfr, keptRows, responseHost, op, detail, error,
                        maxColumnsPerPass, nullptr);
  detail.wallMs = clock.elapsedMs();
  return ok ? Status::Ok() : Status::Error(error);
}

Status FactorAndBuildResponse(const SparseMatrix& kffUpper, const SparseMatrix& kfr,
                              Eigen::Index keptDofs, CholmodFactor& factor,
                              Eigen::MatrixXd& response, std::unique_ptr<ResponseOperator>& op,
                              FactorAndResponseDetail& detail) {
  detail = FactorAndResponseDetail{};
  StageClock clock;
  cholmod_factor* L = factor.cholmodFactor();
  if (!L)
    return Status::Error("FactorAndBuildResponse: the factor has not been analysed");
  detail.factorNonzeros = factor.factorNonzeros();
  // K_perm for the response's residual check depends only on K_FF and the ordering: made on the
  // host while the GPU factorizes.
  const int n = static_cast<int>(L->n);
  std::future<PermutedCsr> kPermMade = std::async(
      std::launch::async,
      [&kffUpper, pinv = InversePermutation(static_cast<const int*>(L->Perm), n)]() {
        PermutedCsr k; // left empty for a matrix of another size: Build refuses it with a message
        if (kffUpper.rows() == static_cast<Eigen::Index>(pinv.size()) &&
            kffUpper.cols() == kffUpper.rows() && kffUpper.isCompressed())
          PermutedFullCsr(kffUpper, pinv, k);
        return k;
      });
  DeviceArray deviceX;
  std::string error;
  double unused = 0.0;
  // The host factor is allocated first and its pages touched on every core while the GPU
  // factorizes (which reads only the factor's structure): faulted in by the copy below, a factor
  // of several GB would slow that copy and crowd the response's own download.
  if (!detail::AllocateHostFactor(L, factor.cholmodCommon(), error))
    return Status::Error(error);
  std::future<void> hostFactorTouched = std::async(std::launch::async, [L]() {
    detail::TouchPagesInParallel(static_cast<double*>(L->x), static_cast<std::int64_t>(L->xsize));
  });
  if (!detail::FactorAnalysedOnGpu(kffUpper, L, factor.cholmodCommon(), deviceX, false,
                                   detail.factorizeMs, unused, error))
    return Status::Error(error);
  hostFactorTouched.get();
  // The factor's copy into CHOLMOD (for CPU solves) runs beside the response, on its own stream
  // and thread: both only read the device factor, and the copy's device-to-host traffic and host
  // memcpy overlap the response's kernels. So does marking it factorized, which extracts the
  // dense trailing block for CPU solves:
  // the response reads only the factor's structure on the host, which neither step changes.
  std::future<Status> download = std::async(std::launch::async, [&]() -> Status {
    StageClock copyClock;
    std::string copyError;
    cudaStream_t stream = nullptr;
    bool ok = cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking) == cudaSuccess;
    if (!ok)
      copyError = "could not create a stream for the factor's copy";
    ok = ok && detail::DownloadFactor(L, deviceX, stream, copyError);
    if (stream)
      cudaStreamDestroy(stream);
    detail.factorDownloadMs = copyClock.lapMs();
    if (!ok)
      return Status::Error("copying the GPU factor into CHOLMOD: " + copyError);
    const Status marked = factor.markFactorized();
    detail.markFactorizedMs = copyClock.lapMs();
    return marked;
  });
  SupernodalFactorView view = ViewOfFactor(L);
  view.deviceX = deviceX.as<double>();
  StageClock responseClock;
  PermutedCsr kPerm = kPermMade.get();
  detail.response = DenseResponseDetail{};
  const bool builtOk =
      Build(view, &kffUpper, kfr, keptDofs, &response, &op, detail.response, error, 0, &kPerm);
  detail.response.wallMs = responseClock.elapsedMs();
  const Status built = builtOk ? Status::Ok() : Status::Error(error);
  StageClock waitClock;
  const Status copied = download.get();
  detail.factorDownloadWaitMs = waitClock.elapsedMs();
  deviceX.release();
  detail.wallMs = clock.elapsedMs();
  if (!copied)
    return copied;
  return built;
}

} // namespace faceplan::cuda
