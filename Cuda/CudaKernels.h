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

// Whether the kernels in this library can run on the current device (an sm_90 build on an
// older GPU cannot). cudaSuccess when they can.
cudaError_t CheckKernelImage();

} // namespace faceplan::cuda::detail
