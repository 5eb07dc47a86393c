// SPDX-License-Identifier: BSD-3-Clause
// How fast a large device-to-host copy can land in ordinary (pageable, already touched) host
// memory on this machine: through two 64 MB page-locked buffers and a parallel host copy (what
// DownloadLarge does), or straight into the destination after cudaHostRegister (timing the
// registration and its undoing too). The dense response of the 1M-cell scene is 4.6 GB.
//   host_transfer_probe [GB]
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

namespace {
double Ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
void Check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) {
    std::fprintf(stderr, "%s: %s\n", what, cudaGetErrorString(e));
    std::exit(1);
  }
}
void ParallelCopy(char* dst, const char* src, size_t bytes, int threads) {
  std::vector<std::thread> pool;
  const size_t part = (bytes + threads - 1) / threads;
  for (int t = 0; t < threads; ++t) {
    const size_t a = std::min(bytes, t * part), b = std::min(bytes, a + part);
    if (a < b)
      pool.emplace_back([=] { std::memcpy(dst + a, src + a, b - a); });
  }
  for (auto& th : pool)
    th.join();
}
} // namespace

int main(int argc, char** argv) {
  const double gb = argc > 1 ? std::atof(argv[1]) : 4.6;
  const size_t bytes = size_t(gb * 1e9) / 8 * 8;
  const int threads = std::max(1u, std::thread::hardware_concurrency());
  char* device = nullptr;
  Check(cudaMalloc(&device, bytes), "cudaMalloc");
  Check(cudaMemset(device, 1, bytes), "cudaMemset");
  cudaStream_t stream;
  Check(cudaStreamCreate(&stream), "stream");
  // Page-aligned, so that parts of it can be registered on their own.
  struct Buffer {
    char* p;
    explicit Buffer(size_t n)
        : p(static_cast<char*>(std::aligned_alloc(4096, (n + 4095) / 4096 * 4096))) {}
    ~Buffer() { std::free(p); }
    char* data() { return p; }
  } host(bytes), other(bytes);
  auto t0 = std::chrono::steady_clock::now();
  std::memset(host.data(), 0, bytes);
  std::printf("%.2f GB, %d host threads; first touch (memset) %.0f ms\n", bytes / 1e9, threads,
              Ms(t0));

  // Staged, as DownloadLarge.
  const size_t chunk = size_t(64) << 20;
  char* stage[2];
  t0 = std::chrono::steady_clock::now();
  for (auto& s : stage)
    Check(cudaHostAlloc(reinterpret_cast<void**>(&s), chunk, 0), "cudaHostAlloc");
  const double allocMs = Ms(t0);
  cudaEvent_t done[2];
  for (auto& e : done)
    Check(cudaEventCreateWithFlags(&e, cudaEventDisableTiming), "event");
  for (int rep = 0; rep < 2; ++rep) {
    t0 = std::chrono::steady_clock::now();
    const size_t chunks = (bytes + chunk - 1) / chunk;
    for (size_t k = 0; k <= chunks; ++k) {
      if (k < chunks) {
        const size_t off = k * chunk, len = std::min(chunk, bytes - off);
        Check(cudaMemcpyAsync(stage[k % 2], device + off, len, cudaMemcpyDeviceToHost, stream),
              "copy");
        Check(cudaEventRecord(done[k % 2], stream), "record");
      }
      if (k > 0) {
        const size_t off = (k - 1) * chunk, len = std::min(chunk, bytes - off);
        Check(cudaEventSynchronize(done[(k - 1) % 2]), "sync");
        ParallelCopy(host.data() + off, stage[(k - 1) % 2], len, threads);
      }
    }
    const double ms = Ms(t0);
    std::printf("staged (2 x 64 MB pinned, %.0f ms to allocate): %.0f ms = %.1f GB/s\n", allocMs,
                ms, bytes / 1e6 / ms);
  }
  // Host memcpy alone, pageable to pageable.
  std::memset(other.data(), 0, bytes);
  t0 = std::chrono::steady_clock::now();
  ParallelCopy(other.data(), host.data(), bytes, threads);
  std::printf("host parallel memcpy: %.0f ms = %.1f GB/s\n", Ms(t0), bytes / 1e6 / Ms(t0));

  // Registered destination.
  t0 = std::chrono::steady_clock::now();
  Check(cudaHostRegister(host.data(), bytes, cudaHostRegisterDefault), "cudaHostRegister");
  const double registerMs = Ms(t0);
  for (int rep = 0; rep < 2; ++rep) {
    t0 = std::chrono::steady_clock::now();
    Check(cudaMemcpyAsync(host.data(), device, bytes, cudaMemcpyDeviceToHost, stream), "copy");
    Check(cudaStreamSynchronize(stream), "sync");
    const double ms = Ms(t0);
    std::printf("registered: register %.0f ms, copy %.0f ms = %.1f GB/s\n", registerMs, ms,
                bytes / 1e6 / ms);
  }
  t0 = std::chrono::steady_clock::now();
  Check(cudaHostUnregister(host.data()), "cudaHostUnregister");
  std::printf("unregister %.0f ms\n", Ms(t0));
  // Registration split over threads (parts of the buffer at once).
  t0 = std::chrono::steady_clock::now();
  {
    std::vector<std::thread> pool;
    const int parts = 8;
    const size_t part = (bytes / parts) & ~size_t(4095);
    for (int p = 0; p < parts; ++p)
      pool.emplace_back([&, p] {
        const size_t a = p * part, len = p + 1 == parts ? bytes - a : part;
        Check(cudaHostRegister(host.data() + a, len, cudaHostRegisterDefault), "register part");
      });
    for (auto& th : pool)
      th.join();
  }
  std::printf("register in 8 parts on threads: %.0f ms\n", Ms(t0));
  return 0;
}
