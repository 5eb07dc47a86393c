// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Kernel launchers of the CUDA backend. Plain pointers and sizes only (no Eigen), so the .cu file
// compiles without Eigen. Every launcher returns cudaGetLastError() after its launch.
#include <cuda_runtime_api.h>

#include <cstdint>

namespace faceplan::cuda::detail {

// packed[e*78 + pos(p,q)] = Ke(p,q), p <= q, for every tetrahedron e (same formula and layout
// as Core's ComputePackedElementStiffness). points: n x 3 row-major; tets: m x 4 row-major.
// youngs/poisson hold one value per cell (stride 1) or one for all (stride 0).
cudaError_t LaunchElementStiffness(const double* points, const int* tets, std::int64_t numTets,
                                   const double* youngs, int youngsStride, const double* poisson,
                                   int poissonStride, double* packed, cudaStream_t stream);

// values[k] = sum of packed[packedIndex[g]] for g in [gatherStart[k], gatherStart[k+1]),
// summed in the same order as Core's AssembleFromPacked.
cudaError_t LaunchGather(const int* gatherStart, const int* packedIndex, const double* packed,
                         int nnz, double* values, cudaStream_t stream);

// ---- Dense response (supernodal triangular solves with many right-hand sides) ----
// Right-hand sides are held "row-major": row r of the n x nb block is the nb doubles at Y + r*nb
// (which is a column-major nb x n matrix with leading dimension nb for cuBLAS).

// Y[pinv[row], c] += sign * value for every nonzero of columns [c0, c0 + nb) of a CSC matrix.
cudaError_t LaunchScatterCsc(const int* colStart, const int* rowIndex, const double* values,
                             const int* pinv, int c0, int nb, double sign, double* Y,
                             cudaStream_t stream);

// Y[rows[i], :] -= T[i, :] for i < count (rows distinct).
cudaError_t LaunchScatterSubtractRows(double* Y, const double* T, const int* rows, int count,
                                      int nb, cudaStream_t stream);

// T[i, :] = Y[rows[i], :] for i < count.
cudaError_t LaunchGatherRows(const double* Y, double* T, const int* rows, int count, int nb,
                             cudaStream_t stream);

// out[i + (c0 + c) * ldOut] = -Y[pinv[i], c] for i < keptRows, c < nb (a transposing gather).
cudaError_t LaunchExtractResponse(const double* Y, const int* pinv, int keptRows, int nb, int c0,
                                  double* out, std::int64_t ldOut, cudaStream_t stream);

// sums[c] += sum over rows r of R[r, c]^2 (sums must be zeroed first).
cudaError_t LaunchColumnSquaredNorms(const double* R, std::int64_t rows, int nb, double* sums,
                                     cudaStream_t stream);

// ---- Supernodal Cholesky (numeric, on CHOLMOD's symbolic supernodal structure) ----
// The structure arrays (super, pi, px, s, colSuper = supernode of each column) live on the device.
struct SupernodalStructure {
  const int* super = nullptr;
  const int* pi = nullptr;
  const std::int64_t* px = nullptr;
  const int* s = nullptr;
  const int* colSuper = nullptr;
};

// Lx[...] = A(perm, perm) lower entries, from the upper triangle of A in CSC (Lx zeroed first).
cudaError_t LaunchAssembleSupernodal(const int* colStart, const int* rowIndex, const double* values,
                                     int n, const int* pinv, SupernodalStructure st, double* Lx,
                                     cudaStream_t stream);

// Subtracts the lower triangle of the update C (count x count, column-major) of a supernode whose
// off-diagonal rows are `rows` from the ancestors' blocks.
cudaError_t LaunchScatterUpdate(const double* C, int count, const int* rows, SupernodalStructure st,
                                double* Lx, cudaStream_t stream);

// ---- Large deformation (CudaHyperelasticKernels.cu) ----
// HyperelasticCells (Core/Backend/ComputeBackend.h) on the device.
struct HyperelasticCellArrays {
  std::int64_t cells = 0;
  const int* corners = nullptr;      // 4 per cell
  const double* gradients = nullptr; // 12 per cell
  const double* volume = nullptr;
  const double* mu = nullptr;
  const double* kappa = nullptr;
  const char* smallStrain = nullptr;
  const int* frameOf = nullptr;
  const double* frames = nullptr; // 9 per frame, column-major
};
// force (zeroed first, nodes' frames) += each cell's internal force at u (nodes' frames); *energy
// (zeroed first) += the cells' energy; *inadmissible = 1 when a cell has det F <= 0.
cudaError_t LaunchHyperelasticForces(const HyperelasticCellArrays& cells, const double* u,
                                     double* force, double* energy, int* inadmissible,
                                     cudaStream_t stream);
// Per block of DeformationMeasureBlocks(cells): the smallest det F, the largest absolute principal
// Green strain and the first cell with it (-1 where all are 0), to be merged in block order.
int DeformationMeasureBlocks(std::int64_t cells);
cudaError_t LaunchDeformationMeasures(const HyperelasticCellArrays& cells, const double* u,
                                      double* smallestDet, double* largestStrain,
                                      long long* largestCell, cudaStream_t stream);
// out (zeroed first) += M v for the symmetric M whose upper triangle is given as (row, column,
// value) triplets.
cudaError_t LaunchSymmetricUpperProduct(const int* rows, const int* cols, const double* values,
                                        std::int64_t nnz, const double* v, double* out,
                                        cudaStream_t stream);
// y[k] = b[perm[k]] / *scale (as float); x[perm[k]] = y[k] * *scale (scale in device memory, so
// that a captured graph reads each call's).
cudaError_t LaunchGatherScaled(const double* b, const int* perm, int n, const double* scale,
                               float* y, cudaStream_t stream);
cudaError_t LaunchScatterScaled(const float* y, const int* perm, int n, const double* scale,
                                double* x, cudaStream_t stream);
// A single-precision supernodal factor in CHOLMOD's layout, on the device.
struct SupernodalSweepArrays {
  const int* super = nullptr;
  const int* pi = nullptr;
  const std::int64_t* px = nullptr;
  const int* s = nullptr;
  const float* values = nullptr;
};
// One level of the forward (L y = b) or backward (L^T x = y) sweep of one right-hand side y (in
// elimination order): the `supernodes` supernodes listed at `order`, independent of each other,
// whose every child is in an earlier level (forward) or whose parent is (backward). maxRows: the
// most rows of those supernodes (the dynamic shared memory, in floats).
cudaError_t LaunchSupernodalSweep(const SupernodalSweepArrays& factor, const int* order,
                                  int supernodes, int maxRows, bool forward, float* y,
                                  cudaStream_t stream);
// y[rows[i]] -= t[i] and t[i] = y[rows[i]] for i < count (rows distinct).
cudaError_t LaunchSubtractAtRows(const float* t, const int* rows, int count, float* y,
                                 cudaStream_t stream);
cudaError_t LaunchGatherAtRows(const float* y, const int* rows, int count, float* t,
                               cudaStream_t stream);
// a[i + i n] = value for i < n (a: n x n, column-major).
cudaError_t LaunchSetDiagonal(float* a, int n, float value, cudaStream_t stream);
// Lets the sweeps use `bytes` of dynamic shared memory (above the default 48 KB).
cudaError_t AllowSweepSharedMemory(int bytes);

// Whether the kernels in this library can run on the current device (an sm_90 build on an
// older GPU cannot). cudaSuccess when they can.
cudaError_t CheckKernelImage();

} // namespace faceplan::cuda::detail
