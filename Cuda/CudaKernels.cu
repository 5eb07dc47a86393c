// SPDX-License-Identifier: BSD-3-Clause
#include "CudaKernels.h"

#include <algorithm>

namespace faceplan::cuda::detail {

namespace {

constexpr int kPacked = 78;       // entries of a packed 12x12 upper triangle
constexpr int kTetsPerBlock = 64; // one thread per tetrahedron
constexpr int kStageStride = 79;  // odd stride in doubles: no shared-memory bank conflicts

// One thread computes one tetrahedron's 78 entries into shared memory; the block then writes its
// 64 x 78 contiguous doubles with coalesced stores (a direct write would stride by 624 bytes).
__global__ void __launch_bounds__(kTetsPerBlock)
    ElementStiffnessKernel(const double* __restrict__ points, const int* __restrict__ tets,
                           std::int64_t numTets, const double* __restrict__ youngs,
                           int youngsStride, const double* __restrict__ poisson, int poissonStride,
                           double* __restrict__ packed) {
  __shared__ double stage[kTetsPerBlock * kStageStride];
  const std::int64_t first = static_cast<std::int64_t>(blockIdx.x) * kTetsPerBlock;
  const std::int64_t e = first + threadIdx.x;

  if (e < numTets) {
    const int4 t = reinterpret_cast<const int4*>(tets)[e];
    const double* p0 = points + 3 * static_cast<std::int64_t>(t.x);
    const double* p1 = points + 3 * static_cast<std::int64_t>(t.y);
    const double* p2 = points + 3 * static_cast<std::int64_t>(t.z);
    const double* p3 = points + 3 * static_cast<std::int64_t>(t.w);
    const double x0 = __ldg(p0), y0 = __ldg(p0 + 1), z0 = __ldg(p0 + 2);
    // M(i, j) = component i of edge j (edge j = corner j+1 - corner 0).
    const double m00 = __ldg(p1) - x0, m10 = __ldg(p1 + 1) - y0, m20 = __ldg(p1 + 2) - z0;
    const double m01 = __ldg(p2) - x0, m11 = __ldg(p2 + 1) - y0, m21 = __ldg(p2 + 2) - z0;
    const double m02 = __ldg(p3) - x0, m12 = __ldg(p3 + 1) - y0, m22 = __ldg(p3 + 2) - z0;
    // Cofactors C(i, j); inverse(r, c) = C(c, r) / det.
    const double c00 = m11 * m22 - m12 * m21, c01 = m12 * m20 - m10 * m22,
                 c02 = m10 * m21 - m11 * m20;
    const double c10 = m02 * m21 - m01 * m22, c11 = m00 * m22 - m02 * m20,
                 c12 = m01 * m20 - m00 * m21;
    const double c20 = m01 * m12 - m02 * m11, c21 = m02 * m10 - m00 * m12,
                 c22 = m00 * m11 - m01 * m10;
    const double det = m00 * c00 + m01 * c01 + m02 * c02;
    const double volume = det / 6.0;
    const double invDet = 1.0 / det;
    // Shape-function gradients: g[a][c]; rows 1..3 are the rows of the inverse.
    double g[4][3];
    g[1][0] = c00 * invDet;
    g[1][1] = c10 * invDet;
    g[1][2] = c20 * invDet;
    g[2][0] = c01 * invDet;
    g[2][1] = c11 * invDet;
    g[2][2] = c21 * invDet;
    g[3][0] = c02 * invDet;
    g[3][1] = c12 * invDet;
    g[3][2] = c22 * invDet;
#pragma unroll
    for (int c = 0; c < 3; ++c)
      g[0][c] = -(g[1][c] + g[2][c] + g[3][c]);

    const double E = youngs[youngsStride * e];
    const double nu = poisson[poissonStride * e];
    const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    const double mu = E / (2.0 * (1.0 + nu));

    double* out = stage + threadIdx.x * kStageStride;
    int k = 0;
#pragma unroll
    for (int p = 0; p < 12; ++p) {
#pragma unroll
      for (int q = p; q < 12; ++q) {
        const int a = p / 3, i = p % 3, b = q / 3, j = q % 3;
        double v = lambda * g[a][i] * g[b][j] + mu * g[b][i] * g[a][j];
        if (i == j)
          v += mu * (g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2]);
        out[k++] = volume * v;
      }
    }
  }
  __syncthreads();

  const std::int64_t remaining = numTets - first;
  const int count =
      static_cast<int>(remaining < kTetsPerBlock ? remaining : kTetsPerBlock) * kPacked;
  double* dst = packed + first * kPacked;
  for (int idx = threadIdx.x; idx < count; idx += kTetsPerBlock) {
    const int tet = idx / kPacked, entry = idx - tet * kPacked;
    dst[idx] = stage[tet * kStageStride + entry];
  }
}

__global__ void GatherKernel(const int* __restrict__ gatherStart,
                             const int* __restrict__ packedIndex, const double* __restrict__ packed,
                             int nnz, double* __restrict__ values) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= nnz)
    return;
  const int begin = gatherStart[k], end = gatherStart[k + 1];
  double sum = 0.0;
  for (int g = begin; g < end; ++g)
    sum += __ldg(packed + __ldg(packedIndex + g));
  values[k] = sum;
}

__global__ void ScatterCscKernel(const int* __restrict__ colStart, const int* __restrict__ rowIndex,
                                 const double* __restrict__ values, const int* __restrict__ pinv,
                                 int c0, int nb, double sign, double* __restrict__ Y) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= nb)
    return;
  for (int p = colStart[c0 + c]; p < colStart[c0 + c + 1]; ++p)
    Y[static_cast<std::int64_t>(pinv[rowIndex[p]]) * nb + c] += sign * values[p];
}

// One block row per blockIdx.y (grid-stride in y), threads across the nb columns.
__global__ void ScatterSubtractRowsKernel(double* __restrict__ Y, const double* __restrict__ T,
                                          const int* __restrict__ rows, int count, int nb) {
  for (int i = blockIdx.y; i < count; i += gridDim.y) {
    double* dst = Y + static_cast<std::int64_t>(rows[i]) * nb;
    const double* src = T + static_cast<std::int64_t>(i) * nb;
    for (int c = blockIdx.x * blockDim.x + threadIdx.x; c < nb; c += gridDim.x * blockDim.x)
      dst[c] -= src[c];
  }
}

__global__ void GatherRowsKernel(const double* __restrict__ Y, double* __restrict__ T,
                                 const int* __restrict__ rows, int count, int nb) {
  for (int i = blockIdx.y; i < count; i += gridDim.y) {
    const double* src = Y + static_cast<std::int64_t>(rows[i]) * nb;
    double* dst = T + static_cast<std::int64_t>(i) * nb;
    for (int c = blockIdx.x * blockDim.x + threadIdx.x; c < nb; c += gridDim.x * blockDim.x)
      dst[c] = src[c];
  }
}

// 32 x 32 tiles through shared memory: reads along c (contiguous in Y), writes along i.
__global__ void ExtractResponseKernel(const double* __restrict__ Y, const int* __restrict__ pinv,
                                      int keptRows, int nb, int c0, double* __restrict__ out,
                                      std::int64_t ldOut) {
  __shared__ double tile[32][33];
  const int cBase = blockIdx.x * 32, iBase = blockIdx.y * 32;
  for (int k = threadIdx.y; k < 32; k += blockDim.y) {
    const int i = iBase + k, c = cBase + threadIdx.x;
    if (i < keptRows && c < nb)
      tile[k][threadIdx.x] = Y[static_cast<std::int64_t>(pinv[i]) * nb + c];
  }
  __syncthreads();
  for (int k = threadIdx.y; k < 32; k += blockDim.y) {
    const int c = cBase + k, i = iBase + threadIdx.x;
    if (i < keptRows && c < nb)
      out[static_cast<std::int64_t>(c0 + c) * ldOut + i] = -tile[threadIdx.x][k];
  }
}

__global__ void ColumnSquaredNormsKernel(const double* __restrict__ R, std::int64_t rows, int nb,
                                         int rowsPerBlock, double* __restrict__ sums) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= nb)
    return;
  const std::int64_t r0 = static_cast<std::int64_t>(blockIdx.y) * rowsPerBlock;
  const std::int64_t r1 = r0 + rowsPerBlock < rows ? r0 + rowsPerBlock : rows;
  double sum = 0.0;
  for (std::int64_t r = r0; r < r1; ++r) {
    const double v = R[r * nb + c];
    sum += v * v;
  }
  atomicAdd(sums + c, sum);
}

// Position of `row` in supernode t's sorted row list (it is there by construction).
__device__ __forceinline__ int RowPosition(const SupernodalStructure& st, int t, int row) {
  int lo = st.pi[t], hi = st.pi[t + 1] - 1;
  while (lo < hi) {
    const int mid = (lo + hi) >> 1;
    if (st.s[mid] < row)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo - st.pi[t];
}

__global__ void AssembleSupernodalKernel(const int* __restrict__ colStart,
                                         const int* __restrict__ rowIndex,
                                         const double* __restrict__ values, int n,
                                         const int* __restrict__ pinv, SupernodalStructure st,
                                         double* __restrict__ Lx) {
  const int j = blockIdx.x * blockDim.x + threadIdx.x;
  if (j >= n)
    return;
  const int pj = pinv[j];
  for (int p = colStart[j]; p < colStart[j + 1]; ++p) {
    const int pi = pinv[rowIndex[p]];
    const int row = pi > pj ? pi : pj, col = pi > pj ? pj : pi;
    const int t = st.colSuper[col];
    const int nsrow = st.pi[t + 1] - st.pi[t];
    Lx[st.px[t] + RowPosition(st, t, row) + static_cast<std::int64_t>(col - st.super[t]) * nsrow] =
        values[p];
  }
}

// blockIdx.y (grid-stride) picks the update's column jj; threads run over its rows ii >= jj.
__global__ void ScatterUpdateKernel(const double* __restrict__ C, int count,
                                    const int* __restrict__ rows, SupernodalStructure st,
                                    double* __restrict__ Lx) {
  for (int jj = blockIdx.y; jj < count; jj += gridDim.y) {
    const int gc = rows[jj];
    const int t = st.colSuper[gc];
    const int nsrow = st.pi[t + 1] - st.pi[t];
    double* column = Lx + st.px[t] + static_cast<std::int64_t>(gc - st.super[t]) * nsrow;
    const double* src = C + static_cast<std::int64_t>(jj) * count;
    for (int ii = jj + blockIdx.x * blockDim.x + threadIdx.x; ii < count;
         ii += gridDim.x * blockDim.x)
      column[RowPosition(st, t, rows[ii])] -= src[ii];
  }
}

unsigned RowGrid(int count) {
  return static_cast<unsigned>(count < 65535 ? count : 65535);
}

} // namespace

cudaError_t LaunchScatterCsc(const int* colStart, const int* rowIndex, const double* values,
                             const int* pinv, int c0, int nb, double sign, double* Y,
                             cudaStream_t stream) {
  if (nb <= 0)
    return cudaSuccess;
  ScatterCscKernel<<<(nb + 127) / 128, 128, 0, stream>>>(colStart, rowIndex, values, pinv, c0, nb,
                                                         sign, Y);
  return cudaGetLastError();
}

cudaError_t LaunchScatterSubtractRows(double* Y, const double* T, const int* rows, int count,
                                      int nb, cudaStream_t stream) {
  if (count <= 0 || nb <= 0)
    return cudaSuccess;
  const int threads = nb >= 256 ? 256 : 128;
  const dim3 grid(static_cast<unsigned>(std::min((nb + threads - 1) / threads, 64)),
                  RowGrid(count));
  ScatterSubtractRowsKernel<<<grid, threads, 0, stream>>>(Y, T, rows, count, nb);
  return cudaGetLastError();
}

cudaError_t LaunchGatherRows(const double* Y, double* T, const int* rows, int count, int nb,
                             cudaStream_t stream) {
  if (count <= 0 || nb <= 0)
    return cudaSuccess;
  const int threads = nb >= 256 ? 256 : 128;
  const dim3 grid(static_cast<unsigned>(std::min((nb + threads - 1) / threads, 64)),
                  RowGrid(count));
  GatherRowsKernel<<<grid, threads, 0, stream>>>(Y, T, rows, count, nb);
  return cudaGetLastError();
}

cudaError_t LaunchExtractResponse(const double* Y, const int* pinv, int keptRows, int nb, int c0,
                                  double* out, std::int64_t ldOut, cudaStream_t stream) {
  if (keptRows <= 0 || nb <= 0)
    return cudaSuccess;
  const dim3 grid(static_cast<unsigned>((nb + 31) / 32),
                  static_cast<unsigned>((keptRows + 31) / 32));
  ExtractResponseKernel<<<grid, dim3(32, 8), 0, stream>>>(Y, pinv, keptRows, nb, c0, out, ldOut);
  return cudaGetLastError();
}

cudaError_t LaunchColumnSquaredNorms(const double* R, std::int64_t rows, int nb, double* sums,
                                     cudaStream_t stream) {
  if (rows <= 0 || nb <= 0)
    return cudaSuccess;
  const std::int64_t perBlock = std::max<std::int64_t>(2048, (rows + 65534) / 65535);
  if (perBlock > 0x7fffffff)
    return cudaErrorInvalidValue;
  const int rowsPerBlock = static_cast<int>(perBlock);
  const std::int64_t rowBlocks = (rows + rowsPerBlock - 1) / rowsPerBlock;
  const dim3 grid(static_cast<unsigned>((nb + 127) / 128), static_cast<unsigned>(rowBlocks));
  ColumnSquaredNormsKernel<<<grid, 128, 0, stream>>>(R, rows, nb, rowsPerBlock, sums);
  return cudaGetLastError();
}

cudaError_t LaunchAssembleSupernodal(const int* colStart, const int* rowIndex, const double* values,
                                     int n, const int* pinv, SupernodalStructure st, double* Lx,
                                     cudaStream_t stream) {
  if (n <= 0)
    return cudaSuccess;
  AssembleSupernodalKernel<<<(n + 127) / 128, 128, 0, stream>>>(colStart, rowIndex, values, n, pinv,
                                                                st, Lx);
  return cudaGetLastError();
}

cudaError_t LaunchScatterUpdate(const double* C, int count, const int* rows, SupernodalStructure st,
                                double* Lx, cudaStream_t stream) {
  if (count <= 0)
    return cudaSuccess;
  const int threads = count >= 256 ? 256 : (count >= 64 ? 64 : 32);
  const dim3 grid(static_cast<unsigned>(std::min((count + threads - 1) / threads, 32)),
                  RowGrid(count));
  ScatterUpdateKernel<<<grid, threads, 0, stream>>>(C, count, rows, st, Lx);
  return cudaGetLastError();
}

cudaError_t LaunchElementStiffness(const double* points, const int* tets, std::int64_t numTets,
                                   const double* youngs, int youngsStride, const double* poisson,
                                   int poissonStride, double* packed, cudaStream_t stream) {
  if (numTets <= 0)
    return cudaSuccess;
  const std::int64_t blocks = (numTets + kTetsPerBlock - 1) / kTetsPerBlock;
  if (blocks > 0x7fffffff)
    return cudaErrorInvalidValue;
  ElementStiffnessKernel<<<static_cast<unsigned>(blocks), kTetsPerBlock, 0, stream>>>(
      points, tets, numTets, youngs, youngsStride, poisson, poissonStride, packed);
  return cudaGetLastError();
}

cudaError_t LaunchGather(const int* gatherStart, const int* packedIndex, const double* packed,
                         int nnz, double* values, cudaStream_t stream) {
  if (nnz <= 0)
    return cudaSuccess;
  constexpr int threads = 256;
  const int blocks = (nnz + threads - 1) / threads;
  GatherKernel<<<blocks, threads, 0, stream>>>(gatherStart, packedIndex, packed, nnz, values);
  return cudaGetLastError();
}

cudaError_t CheckKernelImage() {
  cudaFuncAttributes attributes;
  cudaError_t status = cudaFuncGetAttributes(&attributes, ElementStiffnessKernel);
  if (status != cudaSuccess)
    return status;
  return cudaFuncGetAttributes(&attributes, GatherKernel);
}

} // namespace faceplan::cuda::detail
