// SPDX-License-Identifier: BSD-3-Clause
// Kernels of the large-deformation solve's steps (CudaLargeDeformation.cpp): the cells' energy and
// internal force, the symmetric product with an upper triangle, and the supernodal triangular
// sweeps of one right-hand side in single precision.
#include "CudaKernels.h"

#include <math_constants.h>

namespace faceplan::cuda::detail {

namespace {

constexpr int kCellsPerBlock = 128;
constexpr int kSweepThreads = 256;      // a level of many supernodes
constexpr int kWideSweepThreads = 1024; // a level of few (the top of the tree): large supernodes
constexpr int kPanel = 32; // columns a warp solves at a time in a supernode's diagonal block
constexpr unsigned kFullWarp = 0xffffffffu;

__device__ double WarpSum(double v) {
  for (int offset = 16; offset > 0; offset >>= 1)
    v += __shfl_down_sync(kFullWarp, v, offset);
  return v;
}

__device__ float WarpSum(float v) {
  for (int offset = 16; offset > 0; offset >>= 1)
    v += __shfl_down_sync(kFullWarp, v, offset);
  return v;
}

// Cell e's corners' nodes and shape-function gradients, and its deformation gradient
// F = I + sum_a d_a grad N_a at u, the corners' displacements d_a turned out of their nodes'
// frames.
__device__ __forceinline__ void CellDeformationGradient(const HyperelasticCellArrays& c,
                                                        const double* __restrict__ u,
                                                        std::int64_t e, int node[4], double g[4][3],
                                                        double F[3][3]) {
  double d[4][3];
  for (int a = 0; a < 4; ++a) {
    node[a] = c.corners[4 * e + a];
    const double* local = u + 3 * static_cast<std::int64_t>(node[a]);
    const double l0 = local[0], l1 = local[1], l2 = local[2];
    const int frame = c.frameOf[node[a]];
    if (frame < 0) {
      d[a][0] = l0;
      d[a][1] = l1;
      d[a][2] = l2;
    } else {
      const double* q = c.frames + 9 * static_cast<std::int64_t>(frame); // column-major
      for (int i = 0; i < 3; ++i)
        d[a][i] = q[i] * l0 + q[i + 3] * l1 + q[i + 6] * l2;
    }
    for (int j = 0; j < 3; ++j)
      g[a][j] = c.gradients[12 * e + 3 * a + j];
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      F[i][j] = (i == j ? 1.0 : 0.0) + d[0][i] * g[0][j] + d[1][i] * g[1][j] + d[2][i] * g[2][j] +
                d[3][i] * g[3][j];
}

// One thread per cell: NeoHookeanTetState / SmallStrainTetState (Core/Element/NeoHookeanTet.cpp)
// with the corners' displacements turned out of and the forces into the nodes' frames, the forces
// added to their nodes, the energies summed per block and then into `energy`.
__global__ void __launch_bounds__(kCellsPerBlock)
    HyperelasticForceKernel(HyperelasticCellArrays c, const double* __restrict__ u,
                            double* __restrict__ force, double* __restrict__ energy,
                            int* __restrict__ inadmissible) {
  __shared__ double partial[kCellsPerBlock / 32];
  const std::int64_t e = static_cast<std::int64_t>(blockIdx.x) * kCellsPerBlock + threadIdx.x;
  double cellEnergy = 0.0;
  if (e < c.cells) {
    int node[4];
    double g[4][3], F[3][3];
    CellDeformationGradient(c, u, e, node, g, F);
    // Cofactors: F^-T = cof(F) / J.
    double cof[3][3];
    cof[0][0] = F[1][1] * F[2][2] - F[1][2] * F[2][1];
    cof[0][1] = F[1][2] * F[2][0] - F[1][0] * F[2][2];
    cof[0][2] = F[1][0] * F[2][1] - F[1][1] * F[2][0];
    cof[1][0] = F[0][2] * F[2][1] - F[0][1] * F[2][2];
    cof[1][1] = F[0][0] * F[2][2] - F[0][2] * F[2][0];
    cof[1][2] = F[0][1] * F[2][0] - F[0][0] * F[2][1];
    cof[2][0] = F[0][1] * F[1][2] - F[0][2] * F[1][1];
    cof[2][1] = F[0][2] * F[1][0] - F[0][0] * F[1][2];
    cof[2][2] = F[0][0] * F[1][1] - F[0][1] * F[1][0];
    const double J = F[0][0] * cof[0][0] + F[0][1] * cof[0][1] + F[0][2] * cof[0][2];
    if (!(J > 0.0)) {
      atomicExch(inadmissible, 1);
    } else {
      const double V = c.volume[e], mu = c.mu[e], kappa = c.kappa[e];
      double P[3][3];
      if (c.smallStrain[e]) {
        const double lambda = kappa - 2.0 * mu / 3.0;
        const double trace = F[0][0] + F[1][1] + F[2][2] - 3.0;
        double epsSquared = 0.0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const double eps = 0.5 * (F[i][j] + F[j][i]) - (i == j ? 1.0 : 0.0);
            epsSquared += eps * eps;
            P[i][j] = 2.0 * mu * eps + (i == j ? lambda * trace : 0.0);
          }
        cellEnergy = V * (mu * epsSquared + 0.5 * lambda * trace * trace);
      } else {
        const double root = cbrt(J), a = 1.0 / (root * root);
        double i1 = 0.0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            i1 += F[i][j] * F[i][j];
        cellEnergy = V * (0.5 * mu * (a * i1 - 3.0) + 0.5 * kappa * (J - 1.0) * (J - 1.0));
        const double volumetric = kappa * (J - 1.0) * J;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const double inverseT = cof[i][j] / J;
            P[i][j] = mu * a * (F[i][j] - (i1 / 3.0) * inverseT) + volumetric * inverseT;
          }
      }
      for (int a = 0; a < 4; ++a) {
        double f[3];
        for (int i = 0; i < 3; ++i)
          f[i] = V * (P[i][0] * g[a][0] + P[i][1] * g[a][1] + P[i][2] * g[a][2]);
        const int frame = c.frameOf[node[a]];
        double* out = force + 3 * static_cast<std::int64_t>(node[a]);
        if (frame < 0) {
          for (int i = 0; i < 3; ++i)
            atomicAdd(out + i, f[i]);
        } else {
          const double* q = c.frames + 9 * static_cast<std::int64_t>(frame);
          for (int i = 0; i < 3; ++i) // Q^T f: column i of Q dotted with f
            atomicAdd(out + i, q[3 * i] * f[0] + q[3 * i + 1] * f[1] + q[3 * i + 2] * f[2]);
        }
      }
    }
  }
  const double warpEnergy = WarpSum(cellEnergy);
  if ((threadIdx.x & 31) == 0)
    partial[threadIdx.x >> 5] = warpEnergy;
  __syncthreads();
  if (threadIdx.x == 0) {
    double sum = 0.0;
    for (int w = 0; w < kCellsPerBlock / 32; ++w)
      sum += partial[w];
    atomicAdd(energy, sum);
  }
}

// Per block of cells: the smallest det F, the largest absolute principal Green strain and the
// first cell of the block that has it (-1 where every strain is 0), as MeasureDeformation's
// serial scan; the host merges the blocks in order.
__global__ void __launch_bounds__(kCellsPerBlock)
    DeformationMeasureKernel(HyperelasticCellArrays c, const double* __restrict__ u,
                             double* __restrict__ smallestDet, double* __restrict__ largestStrain,
                             long long* __restrict__ largestCell) {
  __shared__ double dets[kCellsPerBlock], strains[kCellsPerBlock];
  __shared__ long long cells[kCellsPerBlock];
  const std::int64_t e = static_cast<std::int64_t>(blockIdx.x) * kCellsPerBlock + threadIdx.x;
  double det = CUDART_INF, largest = 0.0;
  long long cell = -1;
  if (e < c.cells) {
    int node[4];
    double g[4][3], F[3][3];
    CellDeformationGradient(c, u, e, node, g, F);
    det = F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) -
          F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
          F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
    double E[3][3]; // Green strain (F^T F - I) / 2
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        E[i][j] = 0.5 * (F[0][i] * F[0][j] + F[1][i] * F[1][j] + F[2][i] * F[2][j] -
                         (i == j ? 1.0 : 0.0));
    // Eigenvalues of the symmetric 3 x 3 in closed form (trigonometric, on E - tr(E)/3 I).
    const double m = (E[0][0] + E[1][1] + E[2][2]) / 3.0;
    const double k00 = E[0][0] - m, k11 = E[1][1] - m, k22 = E[2][2] - m;
    const double p = (k00 * k00 + k11 * k11 + k22 * k22 +
                      2.0 * (E[0][1] * E[0][1] + E[0][2] * E[0][2] + E[1][2] * E[1][2])) /
                     6.0;
    double l1 = m, l2 = m, l3 = m;
    if (p > 0.0) {
      const double q = 0.5 * (k00 * (k11 * k22 - E[1][2] * E[1][2]) -
                              E[0][1] * (E[0][1] * k22 - E[1][2] * E[0][2]) +
                              E[0][2] * (E[0][1] * E[1][2] - k11 * E[0][2]));
      const double r = fmin(1.0, fmax(-1.0, q / (p * sqrt(p))));
      const double phi = acos(r) / 3.0, s = 2.0 * sqrt(p);
      l1 = m + s * cos(phi);
      l3 = m + s * cos(phi + 2.0943951023931957); // 2 pi / 3
      l2 = 3.0 * m - l1 - l3;
    }
    largest = fmax(fabs(l1), fmax(fabs(l2), fabs(l3)));
    cell = largest > 0.0 ? e : -1;
  }
  dets[threadIdx.x] = det;
  strains[threadIdx.x] = largest;
  cells[threadIdx.x] = cell;
  __syncthreads();
  if (threadIdx.x == 0) {
    double bestDet = CUDART_INF, best = 0.0;
    long long bestCell = -1;
    for (int t = 0; t < kCellsPerBlock; ++t) {
      bestDet = fmin(bestDet, dets[t]);
      if (strains[t] > best) {
        best = strains[t];
        bestCell = cells[t];
      }
    }
    smallestDet[blockIdx.x] = bestDet;
    largestStrain[blockIdx.x] = best;
    largestCell[blockIdx.x] = bestCell;
  }
}

__global__ void SymmetricUpperProductKernel(const int* __restrict__ rows,
                                            const int* __restrict__ cols,
                                            const double* __restrict__ values, std::int64_t nnz,
                                            const double* __restrict__ v,
                                            double* __restrict__ out) {
  const std::int64_t k = static_cast<std::int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k >= nnz)
    return;
  const int i = rows[k], j = cols[k];
  const double a = values[k];
  atomicAdd(out + i, a * v[j]);
  if (i != j)
    atomicAdd(out + j, a * v[i]);
}

__global__ void GatherScaledKernel(const double* __restrict__ b, const int* __restrict__ perm,
                                   int n, const double* __restrict__ scale, float* __restrict__ y) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n)
    y[k] = static_cast<float>(b[perm[k]] / *scale);
}

__global__ void ScatterScaledKernel(const float* __restrict__ y, const int* __restrict__ perm,
                                    int n, const double* __restrict__ scale,
                                    double* __restrict__ x) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n)
    x[perm[k]] = static_cast<double>(y[k]) * *scale;
}

// One block per supernode of a level: y[its columns] = L11^-1 y[...] (a warp solves 32 columns at
// a time, the block updates the rows below), then its off-diagonal rows' updates are added to the
// ancestors' entries (atomically: supernodes of one level may share an ancestor row).
__global__ void __launch_bounds__(kWideSweepThreads)
    SupernodalForwardKernel(SupernodalSweepArrays f, const int* __restrict__ order,
                            float* __restrict__ y) {
  extern __shared__ float z[];
  const int k = order[blockIdx.x];
  const int c0 = f.super[k], nc = f.super[k + 1] - c0;
  const int p0 = f.pi[k], nr = f.pi[k + 1] - p0;
  const float* __restrict__ L = f.values + f.px[k];
  const int t = threadIdx.x, lane = t & 31, warp = t >> 5;
  for (int i = t; i < nr; i += blockDim.x)
    z[i] = i < nc ? y[c0 + i] : 0.0f;
  __syncthreads();
  for (int j0 = 0; j0 < nc; j0 += kPanel) {
    const int w = min(kPanel, nc - j0);
    if (warp == 0) {
      // Lane r holds row r of the panel's triangle, loaded before the dependent steps, which then
      // wait on no memory.
      float row[kPanel];
#pragma unroll
      for (int jj = 0; jj < kPanel; ++jj)
        row[jj] = (jj <= lane && lane < w) ? L[static_cast<std::int64_t>(j0 + jj) * nr + j0 + lane]
                                           : 1.0f;
      float v = lane < w ? z[j0 + lane] : 0.0f;
#pragma unroll
      for (int jj = 0; jj < kPanel; ++jj) {
        if (jj < w) { // the same for the whole warp
          const float xj = __shfl_sync(kFullWarp, v, jj) / __shfl_sync(kFullWarp, row[jj], jj);
          if (lane == jj)
            v = xj;
          else if (lane > jj)
            v -= row[jj] * xj;
        }
      }
      if (lane < w)
        z[j0 + lane] = v;
    }
    __syncthreads();
    for (int i = j0 + w + t; i < nr; i += blockDim.x) {
      float sum = 0.0f;
      for (int jj = 0; jj < w; ++jj)
        sum += L[static_cast<std::int64_t>(j0 + jj) * nr + i] * z[j0 + jj];
      z[i] -= sum;
    }
    __syncthreads();
  }
  for (int i = t; i < nr; i += blockDim.x) {
    if (i < nc)
      y[c0 + i] = z[i];
    else if (z[i] != 0.0f)
      atomicAdd(y + f.s[p0 + i], z[i]);
  }
}

// One block per supernode of a level: y[its columns] -= L21^T y[rows below] (a warp per column),
// then L11^-T, 32 columns at a time from the last.
__global__ void __launch_bounds__(kWideSweepThreads)
    SupernodalBackwardKernel(SupernodalSweepArrays f, const int* __restrict__ order,
                             float* __restrict__ y) {
  extern __shared__ float z[];
  const int k = order[blockIdx.x];
  const int c0 = f.super[k], nc = f.super[k + 1] - c0;
  const int p0 = f.pi[k], nr = f.pi[k + 1] - p0;
  const float* __restrict__ L = f.values + f.px[k];
  const int t = threadIdx.x, lane = t & 31, warp = t >> 5, warps = blockDim.x >> 5;
  for (int i = t; i < nr; i += blockDim.x)
    z[i] = i < nc ? y[c0 + i] : y[f.s[p0 + i]];
  __syncthreads();
  for (int j0 = ((nc - 1) / kPanel) * kPanel; j0 >= 0; j0 -= kPanel) {
    const int w = min(kPanel, nc - j0);
    for (int jj = warp; jj < w; jj += warps) {
      const float* column = L + static_cast<std::int64_t>(j0 + jj) * nr;
      float sum = 0.0f;
      for (int i = j0 + w + lane; i < nr; i += 32)
        sum += column[i] * z[i];
      sum = WarpSum(sum);
      if (lane == 0)
        z[j0 + jj] -= sum;
    }
    __syncthreads();
    if (warp == 0) {
      // Lane r holds column r of the panel's triangle (row r of L^T), loaded first.
      float column[kPanel];
#pragma unroll
      for (int jj = 0; jj < kPanel; ++jj)
        column[jj] =
            (jj >= lane && jj < w) ? L[static_cast<std::int64_t>(j0 + lane) * nr + j0 + jj] : 1.0f;
      float v = lane < w ? z[j0 + lane] : 0.0f;
#pragma unroll
      for (int jj = kPanel - 1; jj >= 0; --jj) {
        if (jj < w) {
          const float xj = __shfl_sync(kFullWarp, v, jj) / __shfl_sync(kFullWarp, column[jj], jj);
          if (lane == jj)
            v = xj;
          else if (lane < jj)
            v -= column[jj] * xj;
        }
      }
      if (lane < w)
        z[j0 + lane] = v;
    }
    __syncthreads();
  }
  for (int i = t; i < nc; i += blockDim.x)
    y[c0 + i] = z[i];
}

__global__ void SubtractAtRowsKernel(const float* __restrict__ t, const int* __restrict__ rows,
                                     int count, float* __restrict__ y) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < count)
    y[rows[i]] -= t[i];
}

__global__ void GatherAtRowsKernel(const float* __restrict__ y, const int* __restrict__ rows,
                                   int count, float* __restrict__ t) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < count)
    t[i] = y[rows[i]];
}

__global__ void SetDiagonalKernel(float* __restrict__ a, int n, float value) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n)
    a[static_cast<std::int64_t>(i) * n + i] = value;
}

unsigned Blocks(std::int64_t count, int perBlock) {
  return static_cast<unsigned>((count + perBlock - 1) / perBlock);
}

} // namespace

cudaError_t LaunchHyperelasticForces(const HyperelasticCellArrays& cells, const double* u,
                                     double* force, double* energy, int* inadmissible,
                                     cudaStream_t stream) {
  if (cells.cells > 0)
    HyperelasticForceKernel<<<Blocks(cells.cells, kCellsPerBlock), kCellsPerBlock, 0, stream>>>(
        cells, u, force, energy, inadmissible);
  return cudaGetLastError();
}

int DeformationMeasureBlocks(std::int64_t cells) {
  return static_cast<int>(Blocks(cells, kCellsPerBlock));
}

cudaError_t LaunchDeformationMeasures(const HyperelasticCellArrays& cells, const double* u,
                                      double* smallestDet, double* largestStrain,
                                      long long* largestCell, cudaStream_t stream) {
  if (cells.cells > 0)
    DeformationMeasureKernel<<<Blocks(cells.cells, kCellsPerBlock), kCellsPerBlock, 0, stream>>>(
        cells, u, smallestDet, largestStrain, largestCell);
  return cudaGetLastError();
}

cudaError_t LaunchSymmetricUpperProduct(const int* rows, const int* cols, const double* values,
                                        std::int64_t nnz, const double* v, double* out,
                                        cudaStream_t stream) {
  if (nnz > 0)
    SymmetricUpperProductKernel<<<Blocks(nnz, 256), 256, 0, stream>>>(rows, cols, values, nnz, v,
                                                                      out);
  return cudaGetLastError();
}

cudaError_t LaunchGatherScaled(const double* b, const int* perm, int n, const double* scale,
                               float* y, cudaStream_t stream) {
  if (n > 0)
    GatherScaledKernel<<<Blocks(n, 256), 256, 0, stream>>>(b, perm, n, scale, y);
  return cudaGetLastError();
}

cudaError_t LaunchScatterScaled(const float* y, const int* perm, int n, const double* scale,
                                double* x, cudaStream_t stream) {
  if (n > 0)
    ScatterScaledKernel<<<Blocks(n, 256), 256, 0, stream>>>(y, perm, n, scale, x);
  return cudaGetLastError();
}

cudaError_t LaunchSubtractAtRows(const float* t, const int* rows, int count, float* y,
                                 cudaStream_t stream) {
  if (count > 0)
    SubtractAtRowsKernel<<<Blocks(count, 256), 256, 0, stream>>>(t, rows, count, y);
  return cudaGetLastError();
}

cudaError_t LaunchGatherAtRows(const float* y, const int* rows, int count, float* t,
                               cudaStream_t stream) {
  if (count > 0)
    GatherAtRowsKernel<<<Blocks(count, 256), 256, 0, stream>>>(y, rows, count, t);
  return cudaGetLastError();
}

cudaError_t LaunchSetDiagonal(float* a, int n, float value, cudaStream_t stream) {
  if (n > 0)
    SetDiagonalKernel<<<Blocks(n, 256), 256, 0, stream>>>(a, n, value);
  return cudaGetLastError();
}

cudaError_t AllowSweepSharedMemory(int bytes) {
  cudaError_t e = cudaFuncSetAttribute(SupernodalForwardKernel,
                                       cudaFuncAttributeMaxDynamicSharedMemorySize, bytes);
  if (e == cudaSuccess)
    e = cudaFuncSetAttribute(SupernodalBackwardKernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                             bytes);
  return e;
}

cudaError_t LaunchSupernodalSweep(const SupernodalSweepArrays& factor, const int* order,
                                  int supernodes, int maxRows, bool forward, float* y,
                                  cudaStream_t stream) {
  if (supernodes <= 0)
    return cudaSuccess;
  const size_t shared = sizeof(float) * static_cast<size_t>(maxRows);
  // A level of fewer supernodes than the GPU has multiprocessors leaves most of them idle: its
  // blocks get more threads, which read their large blocks' rows in parallel.
  const int threads = supernodes < 128 && maxRows > 256 ? kWideSweepThreads : kSweepThreads;
  if (forward)
    SupernodalForwardKernel<<<supernodes, threads, shared, stream>>>(factor, order, y);
  else
    SupernodalBackwardKernel<<<supernodes, threads, shared, stream>>>(factor, order, y);
  return cudaGetLastError();
}

} // namespace faceplan::cuda::detail
