// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The dense response of a condensed system, built on the GPU (precompute):
//
//   response = -(rows [0, keptRows) of K_FF^-1 K_FR)        (kept DOFs x ROI DOFs)
//
// from a CHOLMOD supernodal Cholesky factor L L^T = P K_FF P^T. All ROI columns (or as many as
// fit) go through one forward and one backward supernodal sweep at once: per supernode a cuBLAS
// DTRSM on its diagonal block and a DGEMM with its off-diagonal block plus a row scatter/gather,
// so the work is matrix-matrix (BLAS3) with thousands of right-hand sides. The residual
// ||K_FF x - b|| / ||b|| of every column is checked on the GPU with cuSPARSE SpMM, and the
// response can stay on the GPU as the per-edit operator (no second upload).
//
// The numeric factorization runs on the GPU too (FactorAndBuildResponse below, on Core's own
// CholmodFactor after its CPU analysis; that is what Precompute() uses with the CUDA backend), or
// on the CPU (SupernodalCholesky::factor, for comparisons).
#include "Backend/ComputeBackend.h"
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"
#include "SparseSolver/CholmodFactor.h"

#include <Eigen/Core>
#include <memory>
#include <string>

namespace faceplan::cuda {

// A read-only view of a CHOLMOD supernodal LL^T factor with 32-bit indices (cholmod_factor's
// super, pi, px, s, x and Perm arrays): L L^T = A(perm, perm).
struct SupernodalFactorView {
  int n = 0;
  int nsuper = 0;
  const int* super = nullptr; // nsuper + 1: first column of each supernode
  const int* pi = nullptr;    // nsuper + 1: start of each supernode's row indices in s
  const int* px = nullptr;    // nsuper + 1: start of each supernode's dense block in x
  const int* s = nullptr;     // row indices
  const double* x = nullptr;  // column-major nsrow x nscol blocks
  const int* perm = nullptr;  // n
  const double* deviceX =
      nullptr; // x already in GPU memory (SupernodalCholesky::factorOnGpu), or null
};

// Core's CholmodFactor (ordering, symbolic analysis, CPU factorization and solves) of a symmetric
// positive definite matrix given by its upper triangle, with its numeric factorization optionally
// on the GPU and the GPU copy of the factor kept for BuildDenseResponse.
class SupernodalCholesky {
public:
  SupernodalCholesky();
  ~SupernodalCholesky();
  SupernodalCholesky(const SupernodalCholesky&) = delete;
  SupernodalCholesky& operator=(const SupernodalCholesky&) = delete;

  // Ordering, symbolic and numeric factorization on the CPU (CholmodFactor).
  Status factor(const SparseMatrix& upper);
  // CHOLMOD ordering and symbolic analysis on the CPU, numeric factorization on the GPU
  // (right-looking supernodal: cuSOLVER DPOTRF, cuBLAS DTRSM and DSYRK per supernode, updates
  // scattered into the ancestors). The factor stays in GPU memory (view().deviceX); with
  // `hostCopy` it is also copied into the CHOLMOD factor, so that CPU solves work as after
  // factor().
  Status factorOnGpu(const SparseMatrix& upper, bool hostCopy = true);
  // Frees the GPU copy (the host factor, if any, stays).
  void releaseDevice();
  SupernodalFactorView view() const;
  // x = A^-1 b on the CPU (needs the host factor).
  Status solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;
  double analyzeMs() const;
  double factorizeMs() const; // numeric factorization (GPU: including uploads)
  double downloadMs() const;  // GPU factor to the CHOLMOD factor (factorOnGpu with hostCopy)
  double factorNonzeros() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct DenseResponseDetail {
  int supernodes = 0;
  int blocks = 0; // passes over the ROI columns (1 when all fit in GPU memory)
  int columnsPerBlock = 0;
  double flops = 0.0; // of the two triangular sweeps
  double hostPrepareMs =
      0.0; // host work before the uploads (permutation, reach, K_perm when made here)
  double allocateMs = 0.0; // device buffers for the right-hand sides and the residual
  double uploadMs = 0.0;   // factor, K_FF and K_FR to the device
  double forwardMs = 0.0;  // device time of the forward sweeps
  double backwardMs = 0.0; // device time of the backward sweeps
  double residualMs = 0.0; // device time of the residual check
  double extractMs = 0.0;  // device time of the kept-row extraction
  double downloadMs =
      0.0; // response to the host (when asked for), on its own thread beside the residual
  double downloadWaitMs = 0.0; // of that copy, left after the last pass's residual check
  double hostTouchWaitMs =
      0.0;             // the copy waiting for the host response's pages, touched beside the sweeps
  double wallMs = 0.0; // the whole call on the host clock
  double worstRelativeResidual = 0.0; // max over columns of ||K_FF x - b|| / ||b||
};

// Builds the response on the GPU. `kffUpper` (the matrix `factor` factors, upper triangle) is
// used for the residual check; pass null to skip it. With `responseHost`, the response is also
// copied to the host; with `op`, a ResponseOperator that keeps the device copy is returned.
// Fails on any device failure (the caller then uses the CPU path).
// maxColumnsPerPass > 0 caps the right-hand sides per pass (otherwise: as many as fit).
Status BuildDenseResponse(const SupernodalFactorView& factor, const SparseMatrix* kffUpper,
                          const SparseMatrix& kfr, Eigen::Index keptRows,
                          Eigen::MatrixXd* responseHost, std::unique_ptr<ResponseOperator>* op,
                          DenseResponseDetail& detail, int maxColumnsPerPass = 0);

// The CUDA backend's ComputeBackend::factorAndBuildResponse (what Precompute() runs for
// DenseResponse with the CUDA backend): numeric factorization of `factor` (after
// factor.analyze(kffUpper), CHOLMOD's ordering and symbolic analysis on the CPU) on the GPU, copied
// into `factor` for CPU solves (factor.markFactorized()); then BuildDenseResponse from the factor
// still on the GPU, with the residual check, the response copied to the host and kept on the GPU
// as `op`. The device copy of the factor is freed before returning.
struct FactorAndResponseDetail {
  double factorizeMs =
      0.0; // GPU numeric factorization (uploads of the structure and K_FF included)
  double factorDownloadMs = 0.0; // the factor copied into the CHOLMOD factor (beside the response)
  double factorDownloadWaitMs = 0.0; // of the copy and marking, left after the response was built
  double markFactorizedMs =
      0.0; // CholmodFactor::markFactorized after the copy (beside the response)
  DenseResponseDetail response;
  double wallMs = 0.0; // the whole call
  double factorNonzeros = 0.0;
  bool succeeded = false;
  long long call = 0; // the backend's count of factorAndBuildResponse calls, this one included
};
Status FactorAndBuildResponse(const SparseMatrix& kffUpper, const SparseMatrix& kfr,
                              Eigen::Index keptDofs, CholmodFactor& factor,
                              Eigen::MatrixXd& response, std::unique_ptr<ResponseOperator>& op,
                              FactorAndResponseDetail& detail);

// The detail of the most recent factorAndBuildResponse call of a backend made by MakeCudaBackend
// (see `succeeded` and `call`); false when it has had none or `backend` is not a CUDA backend.
bool LastFactorAndResponseDetail(const ComputeBackend& backend, FactorAndResponseDetail& detail);

} // namespace faceplan::cuda
