// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/MultifrontalCholesky.h"
#include "Common/BlasThreads.h"
#include "Common/HelperThreads.h"
#include "Common/InversePermutation.h"
#include "Common/ParallelFor.h"
#include "SparseSolver/Blas.h"
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace faceplan {

namespace {

// The BLAS calls of one supernode, for either precision.
template <class Scalar>
void GemmNT(int m, int n, int k, Scalar alpha, const Scalar* a, int lda, const Scalar* b, int ldb,
            Scalar beta, Scalar* c, int ldc) {
  if constexpr (std::is_same_v<Scalar, double>)
    dgemm_("N", "T", &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
  else
    sgemm_("N", "T", &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}

// The most columns of a panel factored by plain loops (PanelFactor's leaves): of 4, 8, 16, 32 and
// 64, 8 was the fastest on fronts of 32 to 864 columns.
constexpr int kPanelLeaf = 8;

// Factors the panel of a supernode's front in place: the `width` x `width` diagonal block A11 =
// L11 L11^T (lower) and the rows below it, A21 := A21 L11^-T, with `height` rows in all (column-
// major, leading dimension lda). Returns 0, or the panel's column (from 1) whose pivot is not
// positive, as LAPACK's info.
//
// Why not potrf and trsm: on the fronts of a tet mesh's tangent (tens to hundreds of columns over
// a few hundred rows) OpenBLAS's triangular solve runs at a tenth to a third of its matrix
// product's rate, and its potrf little better. Recursively halving the columns puts nearly all the
// flops in products with an inner dimension of half the panel; the leaves of at most kPanelLeaf
// columns factor their diagonal block by plain loops, invert it (as blocked triangular solves on
// GPUs do with their small diagonal blocks) and apply the inverse by one product. The strictly
// upper triangle of A11, which the products also write, is cleared at the end, as potrf leaves it.
template <class Scalar> class PanelFactor {
public:
  int operator()(int width, int height, Scalar* a, int lda) {
    const int failed = factor(width, height, a, lda);
    for (int j = 1; j < width; ++j)
      std::fill(a + size_t(j) * lda, a + size_t(j) * lda + j, Scalar(0));
    return failed;
  }

private:
  int factor(int width, int height, Scalar* a, int lda) {
    if (width <= kPanelLeaf)
      return leaf(width, height, a, lda);
    const int left = ((width / 2 + kPanelLeaf - 1) / kPanelLeaf) * kPanelLeaf;
    if (const int failed = factor(left, height, a, lda))
      return failed;
    const int right = width - left, below = height - left;
    Scalar* rest = a + size_t(left) * lda + left;
    GemmNT<Scalar>(below, right, left, Scalar(-1), a + left, lda, a + left, lda, Scalar(1), rest,
                   lda);
    if (const int failed = factor(right, below, rest, lda))
      return left + failed;
    return 0;
  }

  int leaf(int b, int height, Scalar* a, int lda) {
    for (int j = 0; j < b; ++j) { // right-looking, column by column
      Scalar* cj = a + size_t(j) * lda;
      if (!(cj[j] > Scalar(0)))
        return j + 1;
      const Scalar d = std::sqrt(cj[j]);
      cj[j] = d;
      for (int i = j + 1; i < b; ++i)
        cj[i] /= d;
      for (int k = j + 1; k < b; ++k) {
        Scalar* ck = a + size_t(k) * lda;
        const Scalar f = cj[k];
        for (int i = k; i < b; ++i)
          ck[i] -= cj[i] * f;
      }
    }
    const int below = height - b;
    if (below == 0)
      return 0;
    // inverse_ = L11^-1 (lower, b x b, leading dimension kPanelLeaf), column by column.
    std::fill(inverse_, inverse_ + kPanelLeaf * kPanelLeaf, Scalar(0));
    for (int j = 0; j < b; ++j) {
      Scalar* xj = inverse_ + j * kPanelLeaf;
      xj[j] = Scalar(1) / a[size_t(j) * lda + j];
      for (int i = j + 1; i < b; ++i) {
        Scalar sum = 0;
        for (int k = j; k < i; ++k)
          sum += a[size_t(k) * lda + i] * xj[k];
        xj[i] = -sum / a[size_t(i) * lda + i];
      }
    }
    // A21 := A21 L11^-T, through a copy (a product cannot write its own input).
    Scalar* rows = a + b;
    scratch_.resize(size_t(below) * b);
    GemmNT<Scalar>(below, b, b, Scalar(1), rows, lda, inverse_, kPanelLeaf, Scalar(0),
                   scratch_.data(), below);
    for (int j = 0; j < b; ++j)
      std::copy_n(scratch_.data() + size_t(j) * below, below, rows + size_t(j) * lda);
    return 0;
  }

  Scalar inverse_[kPanelLeaf * kPanelLeaf];
  std::vector<Scalar> scratch_;
};

template <class Scalar>
void SyrkLowerMinus(int n, int k, const Scalar* a, int lda, Scalar beta, Scalar* c, int ldc) {
  const Scalar minusOne = -1;
  if constexpr (std::is_same_v<Scalar, double>)
    dsyrk_("L", "N", &n, &k, &minusOne, a, &lda, &beta, c, &ldc);
  else
    ssyrk_("L", "N", &n, &k, &minusOne, a, &lda, &beta, c, &ldc);
}

// The factor's supernodal structure and tree, and the matrix's entries grouped by the
// elimination-order column they land in (the lower triangle of P A P^T): each entry's row there and
// its index in the matrix's values, which `values` points to for the factorization at hand.
struct Plan {
  int n = 0, nsuper = 0;
  const int *super = nullptr, *pi = nullptr, *px = nullptr, *s = nullptr;
  std::vector<int> parent, childStart, children;      // children in ascending order
  std::vector<double> flops;                          // of each supernode's own factorization
  std::vector<int> entryStart, entryRow, entrySource; // permuted lower triangle, by column
  const double* values = nullptr;

  int columns(int t) const { return super[t + 1] - super[t]; }
  int rows(int t) const { return pi[t + 1] - pi[t]; }
};

Status MakePlan(const SparseMatrix& upper, const cholmod_factor& L, Plan& p) {
  p.n = static_cast<int>(L.n);
  p.nsuper = static_cast<int>(L.nsuper);
  p.super = static_cast<const int*>(L.super);
  p.pi = static_cast<const int*>(L.pi);
  p.px = static_cast<const int*>(L.px);
  p.s = static_cast<const int*>(L.s);
  const int* perm = static_cast<const int*>(L.Perm);
  if (!p.super || !p.pi || !p.px || !p.s || !perm)
    return Status::Error("internal: the factor has no supernodal analysis");
  const std::vector<int> pinv = InversePermutation(perm, p.n);
  const SupernodalStructure tree{p.n, p.nsuper, p.super, p.pi, p.s};
  p.parent = SupernodeParents(tree, SupernodeOfColumns(tree));
  p.flops.resize(p.nsuper);
  std::vector<int> childCount(p.nsuper + 1, 0);
  for (int t = 0; t < p.nsuper; ++t) {
    const double w = p.columns(t), off = p.rows(t) - p.columns(t);
    p.flops[t] = w * w * w / 3.0 + w * w * off + w * off * off;
    if (p.parent[t] >= 0) {
      if (p.parent[t] <= t)
        return Status::Error("internal: the supernodal tree is not postordered");
      ++childCount[p.parent[t]];
    }
  }
  p.childStart.assign(p.nsuper + 1, 0);
  for (int t = 0; t < p.nsuper; ++t)
    p.childStart[t + 1] = p.childStart[t] + childCount[t];
  p.children.resize(p.childStart[p.nsuper]);
  std::vector<int> fill(p.childStart.begin(), p.childStart.end() - 1);
  for (int t = 0; t < p.nsuper; ++t)
    if (p.parent[t] >= 0)
      p.children[fill[p.parent[t]]++] = t;

  // Entries of the upper triangle, each moved to (max, min) of its permuted row and column.
  const int* start = upper.outerIndexPtr();
  const int* row = upper.innerIndexPtr();
  p.entryStart.assign(p.n + 1, 0);
  for (int j = 0; j < p.n; ++j)
    for (int q = start[j]; q < start[j + 1]; ++q)
      ++p.entryStart[std::min(pinv[row[q]], pinv[j]) + 1];
  for (int c = 0; c < p.n; ++c)
    p.entryStart[c + 1] += p.entryStart[c];
  p.entryRow.resize(p.entryStart[p.n]);
  p.entrySource.resize(p.entryStart[p.n]);
  std::vector<int> next(p.entryStart.begin(), p.entryStart.end() - 1);
  for (int j = 0; j < p.n; ++j)
    for (int q = start[j]; q < start[j + 1]; ++q) {
      const int a = pinv[row[q]], b = pinv[j];
      const int at = next[std::min(a, b)]++;
      p.entryRow[at] = std::max(a, b);
      p.entrySource[at] = q;
    }
  return Status::Ok();
}

// Checks that `upper` can be factored with the supernodal analysis L.
Status CheckMatch(const SparseMatrix& upper, const cholmod_factor& L) {
  if (!L.is_super || L.itype != CHOLMOD_INT)
    return Status::Error("internal: multifrontal factorization needs a supernodal analysis");
  if (!upper.isCompressed() || upper.rows() != upper.cols() ||
      static_cast<size_t>(upper.rows()) != L.n)
    return Status::Error("internal: the matrix does not match the factor's analysis");
  return Status::Ok();
}

// Whether every value of `upper` is within a float's range (false for NaN).
bool FitsSingle(const SparseMatrix& upper) {
  const double* v = upper.valuePtr();
  bool fits = true;
  for (Eigen::Index k = 0; k < upper.nonZeros(); ++k)
    fits &= std::abs(v[k]) <= std::numeric_limits<float>::max();
  return fits;
}

// A supernode's update matrix (off x off, column-major, lower triangle meaningful).
template <class Scalar> struct Update {
  std::unique_ptr<Scalar[]> values;
  size_t capacity = 0;
};

// How a factorization reuses a reference, or keeps one (MultifrontalReference).
template <class Scalar> struct Reuse {
  const std::vector<char>* active = nullptr; // the supernodes to factor (null: every one)
  std::vector<const Scalar*> borrowed;       // per supernode: its kept update matrix, or null
  // Where the update matrices of the supernodes keepMask marks are copied (null: none kept).
  std::vector<std::unique_ptr<Scalar[]>>* keep = nullptr;
  const std::vector<char>* keepMask = nullptr;
};

// Buffers for the update matrices, reused: over one factorization they add up to several times
// the factor, most in blocks large enough for malloc to map fresh pages for each, which the kernel
// zero-fills on first touch (a visible part of a precompute's CPU time). A released buffer serves
// a later request of between half its size and its size. A pool kept across factorizations
// (MultifrontalWorkspace) is trimmed after each to the most it lent at once.
template <class Scalar> class UpdatePool {
public:
  Update<Scalar> take(size_t size) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = free_.lower_bound(size);
      if (it != free_.end() && it->first <= 2 * size + 512) {
        Update<Scalar> u{std::move(it->second), it->first};
        free_.erase(it);
        lent(u.capacity);
        return u;
      }
    }
    Update<Scalar> u{std::unique_ptr<Scalar[]>(new Scalar[std::max<size_t>(size, 1)]), size};
    std::lock_guard<std::mutex> lock(mutex_);
    lent(u.capacity);
    return u;
  }
  void give(Update<Scalar>& u) {
    if (!u.values)
      return;
    std::lock_guard<std::mutex> lock(mutex_);
    lentNow_ -= u.capacity;
    free_.emplace(u.capacity, std::move(u.values));
    u.capacity = 0;
  }
  // Frees the smallest kept buffers until those kept hold no more than the most lent at once since
  // the last trim (all are back after a factorization).
  void trim() {
    std::lock_guard<std::mutex> lock(mutex_);
    size_t kept = 0;
    for (const auto& entry : free_)
      kept += entry.first;
    while (kept > mostLent_ && !free_.empty()) {
      kept -= free_.begin()->first;
      free_.erase(free_.begin());
    }
    mostLent_ = lentNow_;
  }
  double keptBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    double bytes = 0.0;
    for (const auto& entry : free_)
      bytes += double(entry.first) * sizeof(Scalar);
    return bytes;
  }

private:
  void lent(size_t capacity) {
    lentNow_ += capacity;
    mostLent_ = std::max(mostLent_, lentNow_);
  }
  mutable std::mutex mutex_;
  std::multimap<size_t, std::unique_ptr<Scalar[]>> free_;
  size_t lentNow_ = 0, mostLent_ = 0;
};

// Adds a child's update columns [b0, b1) into supernode t's front: columns that land in t's own
// columns go into its block of L (`block`), the others into its update matrix. A child's update
// rows are a subset of t's rows, and distinct update columns land in distinct front columns, so
// column ranges may run in parallel.
template <class Scalar>
void ExtendAdd(const Plan& p, int t, int child, const Scalar* childUpdate,
               const std::vector<int>& position, Scalar* block, Scalar* update, int b0, int b1) {
  const int width = p.columns(t), height = p.rows(t), off = height - width;
  const int childOff = p.rows(child) - p.columns(child);
  const int* childRows = p.s + p.pi[child] + p.columns(child);
  for (int b = b0; b < b1; ++b) {
    const int pb = position[childRows[b]];
    const Scalar* source = childUpdate + size_t(b) * childOff;
    Scalar* target =
        pb < width ? block + size_t(pb) * height : update + size_t(pb - width) * off - width;
    for (int a = b; a < childOff; ++a)
      target[position[childRows[a]]] += source[a];
  }
}

// Splits the columns of a lower triangle of `size` columns into `parts` ranges of about equal
// entries and runs work(begin, end) on each, on threads when parts > 1.
template <class Work> void OverTriangleColumns(int size, int parts, Work&& work) {
  if (parts <= 1 || size < 2) {
    work(0, size);
    return;
  }
  std::vector<std::thread> pool;
  int begin = 0;
  const double total = 0.5 * double(size) * (size + 1);
  double entries = 0.0;
  for (int part = 0, b = 0; part < parts; ++part) {
    const double goal = total * (part + 1) / parts;
    while (b < size && entries < goal)
      entries += size - b++;
    const int end = part + 1 == parts ? size : b;
    if (begin < end) {
      try {
        pool.emplace_back([&work, begin, end] { work(begin, end); });
      } catch (...) { // no thread to be had: this range here
        work(begin, end);
      }
    }
    begin = end;
  }
  for (std::thread& th : pool)
    th.join();
}

// Factors supernode t: its columns of L (the matrix's entries plus its children's update
// columns that land there), then its own update matrix for its parent (-L_off L_off^T plus the
// children's other update columns). `threads` > 1 splits the assembly over threads (the top's
// large fronts, where it is memory-bound work the size of the front). Returns the failing
// elimination-order column, or -1.
template <class Scalar>
int FactorSupernode(const Plan& p, int t, Scalar* x, std::vector<Update<Scalar>>& updates,
                    UpdatePool<Scalar>& pool, std::vector<int>& position, int threads,
                    const Reuse<Scalar>* reuse) {
  const int width = p.columns(t), height = p.rows(t), off = height - width;
  const int* rows = p.s + p.pi[t];
  for (int k = 0; k < height; ++k)
    position[rows[k]] = k;
  Scalar* block = x + p.px[t];
  constexpr double kParallelFrom = 1 << 20; // entries of the front
  const int parts = double(height) * height >= kParallelFrom ? threads : 1;
  OverTriangleColumns(width, parts, [&](int c0, int c1) {
    for (int c = c0; c < c1; ++c) {
      Scalar* column = block + size_t(c) * height;
      std::memset(column, 0, sizeof(Scalar) * height);
      const int k = p.super[t] + c;
      for (int q = p.entryStart[k]; q < p.entryStart[k + 1]; ++q)
        column[position[p.entryRow[q]]] += static_cast<Scalar>(p.values[p.entrySource[q]]);
    }
  });
  // A child's update columns landing in t's own columns come first (its rows are sorted).
  auto childSplit = [&](int child) {
    const int childOff = p.rows(child) - p.columns(child);
    const int* childRows = p.s + p.pi[child] + p.columns(child);
    return int(std::lower_bound(childRows, childRows + childOff, p.super[t + 1]) - childRows);
  };
  auto extendAdd = [&](int child, int b0, int b1, Scalar* update) {
    const int childOff = p.rows(child) - p.columns(child);
    // A child not factored here has its update matrix in the reference.
    const Scalar* childUpdate =
        updates[child].values || !reuse ? updates[child].values.get() : reuse->borrowed[child];
    const int ranges = double(childOff) * (b1 - b0) >= kParallelFrom ? parts : 1;
    OverTriangleColumns(b1 - b0, ranges, [&](int c0, int c1) {
      ExtendAdd(p, t, child, childUpdate, position, block, update, b0 + c0, b0 + c1);
    });
  };
  for (int q = p.childStart[t]; q < p.childStart[t + 1]; ++q)
    extendAdd(p.children[q], 0, childSplit(p.children[q]), nullptr);
  thread_local PanelFactor<Scalar> panel; // its scratch kept from supernode to supernode
  if (const int failed = panel(width, height, block, height))
    return p.super[t] + failed - 1;
  if (off > 0) {
    updates[t] = pool.take(size_t(off) * off);
    Scalar* update = updates[t].values.get();
    // Single-threaded BLAS clears the update itself (beta = 0). With threaded BLAS (the top) it is
    // cleared here, on the same threads as the assembly: OpenBLAS's own threads would clear it
    // behind synchronisation that ThreadSanitizer cannot see, and it then reports every entry
    // the extend-add reads (suppressed as OpenBLAS's, but slowly enough to stall the TSan run).
    Scalar beta = 0;
    if (threads > 1) {
      OverTriangleColumns(off, parts, [&](int c0, int c1) {
        std::memset(update + size_t(c0) * off, 0, sizeof(Scalar) * size_t(c1 - c0) * off);
      });
      beta = 1;
    }
    SyrkLowerMinus<Scalar>(off, width, block + width, height, beta, update, off);
    for (int q = p.childStart[t]; q < p.childStart[t + 1]; ++q) {
      const int child = p.children[q];
      extendAdd(child, childSplit(child), p.rows(child) - p.columns(child), update);
    }
    if (reuse && reuse->keep && (*reuse->keepMask)[t]) {
      (*reuse->keep)[t].reset(new Scalar[size_t(off) * off]);
      std::copy_n(update, size_t(off) * off, (*reuse->keep)[t].get());
    }
  }
  for (int q = p.childStart[t]; q < p.childStart[t + 1]; ++q)
    pool.give(updates[p.children[q]]);
  return -1;
}

// The top: supernodes run last with threaded BLAS. A supernode is in it when its own
// factorization is a large share of the work (a dense block big enough for threaded BLAS), and
// so is every ancestor of one; the rest, independent subtrees and the cheap supernodes between
// them, runs as tasks.
std::vector<char> MarkTop(const Plan& p, int threads) {
  double total = 0.0;
  for (double f : p.flops)
    total += f;
  std::vector<char> top(p.nsuper, 0);
  if (threads <= 1)
    return top;
  const double large = total / (2.0 * threads);
  for (int t = 0; t < p.nsuper; ++t)
    if (p.flops[t] >= large)
      top[t] = 1;
  for (int t = 0; t < p.nsuper; ++t) // postorder: a parent comes after its children
    if (top[t] && p.parent[t] >= 0)
      top[p.parent[t]] = 1;
  return top;
}

// The numeric factorization into x (the plan's value layout), in Scalar precision: an error when
// memory ran out in a task, else failedColumn is the elimination-order column where a pivot failed
// or -1.
template <class Scalar>
Status FactorizeNumeric(const Plan& p, Scalar* x, int threads, int& failedColumnOut,
                        MultifrontalReport* report, UpdatePool<Scalar>& pool,
                        const Reuse<Scalar>* reuse) {
  threads = std::max(1, threads);
  const std::vector<char> top = MarkTop(p, threads);
  auto factored = [&](int t) { return !reuse || !reuse->active || (*reuse->active)[t]; };

  std::vector<Update<Scalar>> updates(p.nsuper);
  std::atomic<int> failedColumn{-1};
  bool outOfMemory = false; // under the tasks' mutex while they run
  auto noteFailure = [&](int column) {
    int expected = -1;
    failedColumn.compare_exchange_strong(expected, column);
  };

  // Tasks: every supernode outside the top, ready once its children are done. Last in, first
  // out, so a thread follows a subtree upwards while its update matrices are warm.
  {
    ScopedBlasThreads singleThreadedBlas(1);
    std::vector<int> pending(p.nsuper);
    std::vector<int> ready;
    int remaining = 0;
    for (int t = 0; t < p.nsuper; ++t) {
      pending[t] = 0; // the children factored here (an ancestor of one is factored too)
      for (int q = p.childStart[t]; q < p.childStart[t + 1]; ++q)
        pending[t] += factored(p.children[q]) ? 1 : 0;
      if (!top[t] && factored(t)) {
        ++remaining;
        if (pending[t] == 0)
          ready.push_back(t);
      }
    }
    std::reverse(ready.begin(), ready.end()); // lowest-numbered leaves first
    std::mutex mutex;
    std::condition_variable wake;
    // A failed allocation in a task stops every worker (an exception must not leave a thread);
    // the caller then gets an error and CholmodFactor tries CHOLMOD.
    auto worker = [&] {
      try {
        std::vector<int> position(p.n, 0); // each row's place in the supernode being factored
        std::unique_lock<std::mutex> lock(mutex);
        while (true) {
          wake.wait(lock, [&] {
            return !ready.empty() || remaining == 0 || failedColumn >= 0 || outOfMemory;
          });
          if (remaining == 0 || failedColumn >= 0 || outOfMemory)
            return;
          const int t = ready.back();
          ready.pop_back();
          lock.unlock();
          const int failed = FactorSupernode(p, t, x, updates, pool, position, 1, reuse);
          if (failed >= 0)
            noteFailure(failed);
          lock.lock();
          --remaining;
          const int parent = p.parent[t];
          if (parent >= 0 && --pending[parent] == 0 && !top[parent])
            ready.push_back(parent);
          wake.notify_all();
        }
      } catch (...) {
        std::lock_guard<std::mutex> guard(mutex);
        outOfMemory = true;
        wake.notify_all();
      }
    };
    // On the calling thread's helpers (HelperThreads), which the steps before a refactorization
    // (the tangent's cells, its assembly) leave awake: threads started here would share the cores
    // with them while they wait.
    try {
      RunOnHelpers(threads, [&worker](int) { worker(); });
    } catch (...) { // no helper to be had: this thread alone
      worker();
    }
  }
  if (outOfMemory)
    return Status::Error("out of memory in the multifrontal factorization");
  // At most 8 BLAS threads for the top, as CholmodFactor::factorize has for CHOLMOD: OpenBLAS
  // with 16 threads was many times slower on these blocks. One on a background thread
  // (BlasThreads.h).
  const int topBlasThreads = ThreadIsBackground() ? 1 : std::min(threads, 8);
  if (failedColumn < 0) {
    ScopedBlasThreads threadedBlas(topBlasThreads);
    std::vector<int> position(p.n, 0);
    for (int t = 0; t < p.nsuper && failedColumn < 0; ++t)
      if (top[t] && factored(t))
        if (const int failed = FactorSupernode(p, t, x, updates, pool, position, threads, reuse);
            failed >= 0)
          noteFailure(failed);
  }
  if (report) {
    double total = 0.0, topFlops = 0.0, factoredFlops = 0.0;
    report->topSupernodes = 0;
    report->supernodesFactored = 0;
    for (int t = 0; t < p.nsuper; ++t) {
      total += p.flops[t];
      if (factored(t)) {
        factoredFlops += p.flops[t];
        ++report->supernodesFactored;
      }
      if (top[t]) {
        topFlops += p.flops[t];
        ++report->topSupernodes;
      }
    }
    report->supernodes = p.nsuper;
    report->topFlopsShare = total > 0.0 ? topFlops / total : 0.0;
    report->factoredFlopsShare = total > 0.0 ? factoredFlops / total : 1.0;
    report->threads = threads;
    report->topBlasThreads = topBlasThreads;
  }
  for (Update<Scalar>& u : updates) // those a failure left unread
    pool.give(u);
  failedColumnOut = failedColumn.load();
  return Status::Ok();
}

Status NotPositiveDefinite(int column) {
  return Status::Error("stiffness matrix is not positive definite (pivot failed at column " +
                       std::to_string(column) + ")");
}

// What a plan or a reference was made for: the analysis's structure (its arrays' addresses) and
// the matrix's pattern.
struct MadeFor {
  const void *super = nullptr, *s = nullptr, *perm = nullptr;
  std::vector<int> outer, inner;

  void record(const SparseMatrix& upper, const cholmod_factor& L) {
    super = L.super;
    s = L.s;
    perm = L.Perm;
    outer.assign(upper.outerIndexPtr(), upper.outerIndexPtr() + upper.cols() + 1);
    inner.assign(upper.innerIndexPtr(), upper.innerIndexPtr() + upper.nonZeros());
  }
  bool matches(const SparseMatrix& upper, const cholmod_factor& L) const {
    return super == L.super && s == L.s && perm == L.Perm &&
           static_cast<Eigen::Index>(outer.size()) == upper.cols() + 1 &&
           static_cast<Eigen::Index>(inner.size()) == upper.nonZeros() &&
           std::equal(outer.begin(), outer.end(), upper.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), upper.innerIndexPtr());
  }
};

} // namespace

struct MultifrontalWorkspace::Impl {
  // The plan and what it was made for: the analysis (its address, null while there is no plan) and
  // madeFor.
  Plan plan;
  const cholmod_factor* analysis = nullptr;
  MadeFor madeFor;
  int plansReused = 0;
  UpdatePool<float> single;
  UpdatePool<double> twice;

  bool planFits(const SparseMatrix& upper, const cholmod_factor& L) const {
    return analysis == &L && madeFor.matches(upper, L);
  }
};

MultifrontalWorkspace::MultifrontalWorkspace() : impl(std::make_unique<Impl>()) {}
MultifrontalWorkspace::~MultifrontalWorkspace() = default;

double MultifrontalWorkspace::keptBytes() const {
  return impl->single.keptBytes() + impl->twice.keptBytes();
}

int MultifrontalWorkspace::plansReused() const {
  return impl->plansReused;
}

namespace {

// The plan for `upper` with L, from the workspace when it has the plan for both, else made (and
// kept there). `local` holds a plan made without a workspace.
Status PlanFor(const SparseMatrix& upper, const cholmod_factor& L, MultifrontalWorkspace* workspace,
               Plan& local, const Plan*& plan) {
  if (Status s = CheckMatch(upper, L); !s)
    return s;
  if (!workspace) {
    if (Status s = MakePlan(upper, L, local); !s)
      return s;
    local.values = upper.valuePtr();
    plan = &local;
    return Status::Ok();
  }
  MultifrontalWorkspace::Impl& w = *workspace->impl;
  if (w.planFits(upper, L)) {
    ++w.plansReused;
  } else {
    w.analysis = nullptr;
    if (Status s = MakePlan(upper, L, w.plan); !s)
      return s;
    w.madeFor.record(upper, L);
    w.analysis = &L; // last: the plan is whole
  }
  w.plan.values = upper.valuePtr();
  plan = &w.plan;
  return Status::Ok();
}

template <class Scalar>
Status Factorize(const Plan& p, Scalar* x, int threads, int& failedColumn,
                 MultifrontalReport* report, UpdatePool<Scalar>* kept,
                 const Reuse<Scalar>* reuse = nullptr) {
  if (kept) {
    const Status s = FactorizeNumeric(p, x, threads, failedColumn, report, *kept, reuse);
    kept->trim();
    return s;
  }
  UpdatePool<Scalar> pool;
  return FactorizeNumeric(p, x, threads, failedColumn, report, pool, reuse);
}

} // namespace

Status MultifrontalFactorize(const SparseMatrix& upper, cholmod_factor* L, cholmod_common* common,
                             int threads, MultifrontalReport* report,
                             MultifrontalWorkspace* workspace) {
  if (!L || !common)
    return Status::Error("internal: multifrontal factorization needs a supernodal analysis");
  Plan local;
  const Plan* plan = nullptr;
  if (Status s = PlanFor(upper, *L, workspace, local, plan); !s)
    return s;
  const Plan& p = *plan;
  const size_t xsize = static_cast<size_t>(p.px[p.nsuper]);
  if (!cholmod_change_factor(CHOLMOD_REAL, 1, 1, 1, 1, L, common) || !L->x || L->xsize != xsize)
    return Status::Error("CHOLMOD could not allocate the numeric factor (out of memory?)");
  int failedColumn = -1;
  if (Status s = Factorize(p, static_cast<double*>(L->x), threads, failedColumn, report,
                           workspace ? &workspace->impl->twice : nullptr);
      !s)
    return s;
  if (failedColumn >= 0) {
    L->minor = static_cast<size_t>(failedColumn);
    return NotPositiveDefinite(failedColumn);
  }
  L->minor = L->n;
  return Status::Ok();
}

struct MultifrontalReference::Impl {
  MadeFor madeFor;
  std::vector<double> entries; // the matrix's, in the plan's order (Plan::entrySource)
  std::vector<double> scale;   // sqrt |a_kk| per elimination-order column
  std::vector<float> factor;   // L's values
  std::vector<std::unique_ptr<float[]>> updates; // per supernode, or null where not kept
  double bytes = 0.0;

  bool fits(const SparseMatrix& upper, const cholmod_factor& L) const {
    return !factor.empty() && madeFor.matches(upper, L);
  }
};

MultifrontalReference::MultifrontalReference() : impl(std::make_unique<Impl>()) {}
MultifrontalReference::~MultifrontalReference() = default;

bool MultifrontalReference::made() const {
  return !impl->factor.empty();
}

double MultifrontalReference::keptBytes() const {
  return impl->bytes;
}

namespace {

// The supernodes whose update matrices a reference keeps: those whose subtree's flops are at least
// kKeepFlopsPerEntry per entry of the update (a reuse then saves far more than it reads), with the
// ratio raised fourfold until they hold no more entries than the factor. Roots have no update.
constexpr double kKeepFlopsPerEntry = 256.0;
std::vector<char> UpdatesToKeep(const Plan& p) {
  std::vector<double> subtree(p.flops);
  for (int t = 0; t < p.nsuper; ++t) // postorder: children first
    if (p.parent[t] >= 0)
      subtree[p.parent[t]] += subtree[t];
  const double budget = double(p.px[p.nsuper]);
  std::vector<char> keep(p.nsuper, 0);
  for (double ratio = kKeepFlopsPerEntry;; ratio *= 4.0) {
    double entries = 0.0;
    for (int t = 0; t < p.nsuper; ++t) {
      const double off = p.rows(t) - p.columns(t);
      keep[t] = p.parent[t] >= 0 && off > 0 && subtree[t] >= ratio * off * off;
      entries += keep[t] ? off * off : 0.0;
    }
    if (entries <= budget)
      return keep;
  }
}

// The supernodes to factor against reference r: those with a column whose entries differ from
// r's beyond the tolerance, their ancestors, and the children these need whose update matrices r
// does not keep (and so on down).
std::vector<char> SupernodesToFactor(const Plan& p, const MultifrontalReference::Impl& r,
                                     double tolerance) {
  std::vector<char> changed(p.n, 0); // per column, on every core (it reads the whole matrix)
  ParallelFor(p.n, 4096, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k)
      for (int q = p.entryStart[k]; q < p.entryStart[k + 1]; ++q) {
        const double bound = tolerance * r.scale[k] * r.scale[p.entryRow[q]];
        if (!(std::abs(p.values[p.entrySource[q]] - r.entries[q]) <= bound)) { // NaN differs
          changed[k] = 1;
          break;
        }
      }
  });
  std::vector<char> factor(p.nsuper, 0);
  for (int t = 0; t < p.nsuper; ++t)
    factor[t] = std::any_of(changed.begin() + p.super[t], changed.begin() + p.super[t + 1],
                            [](char c) { return c != 0; });
  for (int t = 0; t < p.nsuper; ++t)
    if (factor[t] && p.parent[t] >= 0)
      factor[p.parent[t]] = 1;
  for (int t = p.nsuper - 1; t >= 0; --t) // parents first
    if (factor[t])
      for (int q = p.childStart[t]; q < p.childStart[t + 1]; ++q)
        if (!r.updates[p.children[q]])
          factor[p.children[q]] = 1;
  return factor;
}

// Keeps a successful factorization (its matrix p.values, its factor x and the updates copied
// during it) as reference r.
void KeepReference(const Plan& p, const SparseMatrix& upper, const cholmod_factor& L,
                   const float* x, std::vector<std::unique_ptr<float[]>>& updates,
                   MultifrontalReference::Impl& r) {
  r.madeFor.record(upper, L);
  const int entries = p.entryStart[p.n];
  r.entries.resize(entries);
  for (int q = 0; q < entries; ++q)
    r.entries[q] = p.values[p.entrySource[q]];
  r.scale.assign(p.n, 0.0);
  for (int k = 0; k < p.n; ++k)
    for (int q = p.entryStart[k]; q < p.entryStart[k + 1]; ++q)
      if (p.entryRow[q] == k)
        r.scale[k] += r.entries[q];
  for (double& d : r.scale)
    d = std::sqrt(std::abs(d));
  r.factor.assign(x, x + p.px[p.nsuper]);
  r.updates = std::move(updates);
  r.bytes = 8.0 * (r.entries.size() + r.scale.size()) +
            4.0 * (r.factor.size() + r.madeFor.outer.size() + r.madeFor.inner.size());
  for (int t = 0; t < p.nsuper; ++t)
    if (r.updates[t]) {
      const double off = p.rows(t) - p.columns(t);
      r.bytes += 4.0 * off * off;
    }
}

} // namespace

Status MultifrontalFactorizeSingle(const SparseMatrix& upper, const cholmod_factor& analysis,
                                   float* values, int threads, MultifrontalReport* report,
                                   MultifrontalWorkspace* workspace, MultifrontalReference* keep) {
  if (keep)
    keep->impl = std::make_unique<MultifrontalReference::Impl>();
  if (!values)
    return Status::Error("internal: no values to factor into");
  Plan local;
  const Plan* plan = nullptr;
  if (Status s = PlanFor(upper, analysis, workspace, local, plan); !s)
    return s;
  if (!FitsSingle(upper))
    return Status::Error("the matrix does not fit single precision");
  Reuse<float> reuse;
  std::vector<char> keepMask;
  std::vector<std::unique_ptr<float[]>> kept;
  if (keep) {
    keepMask = UpdatesToKeep(*plan);
    kept.resize(plan->nsuper);
    reuse.keep = &kept;
    reuse.keepMask = &keepMask;
  }
  int failedColumn = -1;
  if (Status s = Factorize(*plan, values, threads, failedColumn, report,
                           workspace ? &workspace->impl->single : nullptr, keep ? &reuse : nullptr);
      !s)
    return s;
  if (failedColumn >= 0)
    return NotPositiveDefinite(failedColumn);
  if (keep)
    KeepReference(*plan, upper, analysis, values, kept, *keep->impl);
  return Status::Ok();
}

Status MultifrontalRefactorizeSingle(const SparseMatrix& upper, const cholmod_factor& analysis,
                                     float* values, int threads,
                                     const MultifrontalReference& reference, double tolerance,
                                     MultifrontalReport* report, MultifrontalWorkspace* workspace) {
  const MultifrontalReference::Impl& r = *reference.impl;
  if (!(tolerance >= 0.0))
    return Status::Error("internal: the reuse tolerance must be zero or positive");
  if (!values)
    return Status::Error("internal: no values to factor into");
  Plan local;
  const Plan* plan = nullptr;
  if (Status s = PlanFor(upper, analysis, workspace, local, plan); !s)
    return s;
  if (!FitsSingle(upper))
    return Status::Error("the matrix does not fit single precision");
  const Plan& p = *plan;
  UpdatePool<float>* pool = workspace ? &workspace->impl->single : nullptr;
  int failedColumn = -1;
  if (!r.fits(upper, analysis)) {
    if (Status s = Factorize(p, values, threads, failedColumn, report, pool); !s)
      return s;
  } else {
    const std::vector<char> factor = SupernodesToFactor(p, r, tolerance);
    // The supernodes reused take the reference's columns: runs of them, copied on every core.
    std::vector<std::pair<std::int64_t, std::int64_t>> runs;
    for (int t = 0; t < p.nsuper; ++t)
      if (!factor[t]) {
        if (!runs.empty() && runs.back().second == p.px[t])
          runs.back().second = p.px[t + 1];
        else
          runs.emplace_back(p.px[t], p.px[t + 1]);
      }
    ParallelFor(p.px[p.nsuper], 1 << 16, [&](std::int64_t begin, std::int64_t end) {
      for (const auto& [from, to] : runs) {
        const std::int64_t b = std::max(from, begin), e = std::min(to, end);
        if (b < e)
          std::copy(r.factor.begin() + b, r.factor.begin() + e, values + b);
      }
    });
    Reuse<float> reuse;
    reuse.active = &factor;
    reuse.borrowed.resize(p.nsuper);
    for (int t = 0; t < p.nsuper; ++t)
      reuse.borrowed[t] = r.updates[t].get();
    if (Status s = Factorize(p, values, threads, failedColumn, report, pool, &reuse); !s)
      return s;
  }
  return failedColumn >= 0 ? NotPositiveDefinite(failedColumn) : Status::Ok();
}

} // namespace faceplan
