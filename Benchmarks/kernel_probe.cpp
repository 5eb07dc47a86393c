// SPDX-License-Identifier: BSD-3-Clause
// The machine's ceilings behind the ~100k precompute: the BLAS's DGEMM and DTRSM rates on the
// shapes the response's substitutions use, and the cost of touching fresh memory (page faults)
// against populating it in one call.
//   kernel_probe [--threads N]   (BLAS threads for the rates; default 1, then 2)
#include "Common/BlasThreads.h"
#include "SparseSolver/Blas.h"

#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23 // Linux 5.14
#endif

namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <class Run> double Best(int repeats, Run&& run) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r)
    best = std::min(best, run());
  return best;
}

// C (m x n) = A (m x k) B (k x n), column-major, best of 5.
double GemmRate(int m, int k, int n) {
  std::vector<double> a(size_t(m) * k), b(size_t(k) * n), c(size_t(m) * n);
  for (size_t i = 0; i < a.size(); ++i)
    a[i] = 1.0 / double(i % 7 + 1);
  for (size_t i = 0; i < b.size(); ++i)
    b[i] = 1.0 / double(i % 5 + 1);
  const double one = 1.0, zero = 0.0;
  const double s = Best(5, [&] {
    const auto t = std::chrono::steady_clock::now();
    dgemm_("N", "N", &m, &n, &k, &one, a.data(), &m, b.data(), &k, &zero, c.data(), &m);
    return Seconds(t);
  });
  return 2.0 * m * k * n / s / 1e9;
}

// X (m x w) := X L^-1, L lower triangular (w x w), as the backward substitution calls it.
double TrsmRate(int m, int w) {
  std::vector<double> l(size_t(w) * w, 0.0), x0(size_t(m) * w), x(x0.size());
  for (int j = 0; j < w; ++j)
    for (int i = j; i < w; ++i)
      l[i + size_t(j) * w] = i == j ? double(w) : 1.0 / double(1 + i + j);
  for (size_t i = 0; i < x0.size(); ++i)
    x0[i] = 1.0 / double(1 + i % 13);
  const double one = 1.0;
  const double s = Best(5, [&] {
    x = x0;
    const auto t = std::chrono::steady_clock::now();
    dtrsm_("R", "L", "N", "N", &m, &w, &one, l.data(), &w, x.data(), &m);
    return Seconds(t);
  });
  return double(m) * w * w / s / 1e9;
}

// Milliseconds to fault in `bytes` of fresh anonymous memory page by page, and to populate it with
// one madvise call (then -1 where the kernel lacks MADV_POPULATE_WRITE).
void FaultCost(size_t bytes, double& touchMs, double& populateMs) {
  auto map = [bytes] {
    return static_cast<char*>(
        mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
  };
  char* p = map();
  auto t = std::chrono::steady_clock::now();
  for (size_t i = 0; i < bytes; i += 4096)
    p[i] = 1;
  touchMs = 1e3 * Seconds(t);
  munmap(p, bytes);
  p = map();
  t = std::chrono::steady_clock::now();
  populateMs = madvise(p, bytes, MADV_POPULATE_WRITE) == 0 ? 1e3 * Seconds(t) : -1.0;
  munmap(p, bytes);
}

} // namespace

int main(int argc, char** argv) {
  std::vector<int> threadCounts{1, 2};
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--threads")
      threadCounts = {std::max(1, std::atoi(argv[i + 1]))};
  for (int threads : threadCounts) {
    faceplan::ScopedBlasThreads blas(threads);
    std::printf("BLAS threads %d: DGEMM 3000x3000x3000 %.1f GFLOP/s, 2000x200x128 %.1f GFLOP/s; "
                "DTRSM (right, lower) 126 x 3222 %.1f, 126 x 1000 %.1f, 126 x 300 %.1f GFLOP/s\n",
                threads, GemmRate(3000, 3000, 3000), GemmRate(2000, 200, 128), TrsmRate(126, 3222),
                TrsmRate(126, 1000), TrsmRate(126, 300));
  }
  for (int r = 0; r < 3; ++r) {
    double touch = 0.0, populate = 0.0;
    FaultCost(size_t(200) << 20, touch, populate);
    std::printf(
        "fresh 200 MB: touching each page %.1f ms (%.2f us a page), MADV_POPULATE_WRITE %.1f ms\n",
        touch, touch * 1e3 / double((size_t(200) << 20) / 4096), populate);
  }
  return 0;
}
