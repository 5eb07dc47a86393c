// SPDX-License-Identifier: BSD-3-Clause
#include "SparseSolver/SinglePrecisionFactor.h"

#include "Common/BlasThreads.h"
#include "Common/HelperThreads.h"
#include "Common/ParallelFor.h"
#include "Common/UninitializedVector.h"
#include "Common/WorkerThreads.h"
#include "SparseSolver/Blas.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/MultifrontalCholesky.h"
#include "SparseSolver/SupernodalTree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

namespace faceplan {

namespace {

// Below this many entries a supernode's block is done with plain loops: a BLAS call's overhead
// would be most of its time.
constexpr int kBlasEntries = 512;
// The columns of a supernode's block in the substitutions' blocked triangular solves.
constexpr int kBlock = 32;
// Right-hand sides substituted together: a supernode's values are read once for all of them.
constexpr int kRightHandSides = 32;

} // namespace

struct FactorValueBin::Impl {
  mutable std::mutex mutex;
  std::vector<UninitializedVector<float>> kept;

  UninitializedVector<float> take(size_t size) {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = kept.begin(); it != kept.end(); ++it)
      if (it->size() == size) {
        UninitializedVector<float> out = std::move(*it);
        kept.erase(it);
        return out;
      }
    return {};
  }
  void give(UninitializedVector<float>&& values) {
    if (values.empty())
      return;
    std::lock_guard<std::mutex> lock(mutex);
    constexpr size_t kMost = 2;
    if (kept.size() == kMost)
      kept.erase(kept.begin()); // the oldest
    kept.push_back(std::move(values));
  }
};

FactorValueBin::FactorValueBin() : impl(std::make_unique<Impl>()) {}
FactorValueBin::~FactorValueBin() = default;

double FactorValueBin::keptBytes() const {
  std::lock_guard<std::mutex> lock(impl->mutex);
  double bytes = 0.0;
  for (const auto& v : impl->kept)
    bytes += 4.0 * double(v.size());
  return bytes;
}

struct SinglePrecisionFactor::Impl {
  ~Impl() {
    if (const std::shared_ptr<FactorValueBin> to = bin.lock())
      to->impl->give(std::move(values));
  }
  std::weak_ptr<FactorValueBin> bin; // where the values go when this factor is gone
  int n = 0;
  std::vector<int> super, pi, s, perm;
  std::vector<std::int64_t> px;
  UninitializedVector<float> values; // filled whole by assign()
  double factoredShare = 1.0;        // SinglePrecisionFactor::factoredShare
  // The split for two threads: top supernodes (ascending), each side's supernodes (ascending), and
  // per column its index among the top part's columns (-1 elsewhere).
  std::vector<int> top, side[2];
  std::vector<int> topIndex;
  int topColumns = 0;
  bool split = false;

  // The analysis's supernodes, row lists, value starts and ordering; values sized, not filled.
  void adoptStructure(const cholmod_factor& L, const SupernodalStructure& tree);

  int columns(int k) const { return super[k + 1] - super[k]; }
  int rowsOf(int k) const { return pi[k + 1] - pi[k]; }

  // Forward sweep through supernode k: y[k's columns] = L11^-1 y[...], then the rows below get
  // L21 y subtracted, into `accumulate` (indexed by topIndex) for top rows when it is given.
  void forward(int k, float* y, float* accumulate, std::vector<float>& t) const {
    const int nc = columns(k), nr = rowsOf(k), m = nr - nc;
    const float* L = values.data() + px[k];
    float* y1 = y + super[k];
    const int* rows = s.data() + pi[k] + nc;
    if (nc * nr >= kBlasEntries) {
      // By blocks of columns: the block's triangle with plain loops, then one product for every
      // row below it, in the triangle and in L21 alike (BLAS's triangular solve does its
      // diagonal blocks a column at a time and costs several times a product's time per entry).
      t.resize(nr);
      std::copy(y1, y1 + nc, t.begin());
      std::fill(t.begin() + nc, t.end(), 0.0f);
      float* w = t.data();
      const int one = 1;
      const float alpha = -1.0f, beta = 1.0f;
      for (int j0 = 0; j0 < nc; j0 += kBlock) {
        const int b = std::min(kBlock, nc - j0);
        for (int j = j0; j < j0 + b; ++j) {
          const float* col = L + std::int64_t(j) * nr;
          const float v = (w[j] /= col[j]);
          for (int i = j + 1; i < j0 + b; ++i)
            w[i] -= col[i] * v;
        }
        const int below = nr - j0 - b;
        if (below > 0)
          sgemv_("N", &below, &b, &alpha, L + std::int64_t(j0) * nr + j0 + b, &nr, w + j0, &one,
                 &beta, w + j0 + b, &one);
      }
      std::copy(w, w + nc, y1);
      for (int i = 0; i < m; ++i)
        w[i] = -w[nc + i]; // L21 y1, as the loops below leave it
    } else {
      for (int j = 0; j < nc; ++j) {
        const float* col = L + std::int64_t(j) * nr;
        const float v = (y1[j] /= col[j]);
        for (int i = j + 1; i < nc; ++i)
          y1[i] -= col[i] * v;
      }
      t.assign(m, 0.0f);
      for (int j = 0; j < nc; ++j) {
        const float* col = L + std::int64_t(j) * nr + nc;
        const float v = y1[j];
        for (int i = 0; i < m; ++i)
          t[i] += col[i] * v;
      }
    }
    for (int i = 0; i < m; ++i) {
      const int r = rows[i];
      if (accumulate && topIndex[r] >= 0)
        accumulate[topIndex[r]] += t[i];
      else
        y[r] -= t[i];
    }
  }

  // Backward sweep through supernode k: y[k's columns] -= L21^T y[rows below], then L11^-T.
  void backward(int k, float* y, std::vector<float>& t) const {
    const int nc = columns(k), nr = rowsOf(k), m = nr - nc;
    const float* L = values.data() + px[k];
    float* y1 = y + super[k];
    const int* rows = s.data() + pi[k] + nc;
    if (nc * nr >= kBlasEntries) {
      // By blocks of columns, from the last: one product with every row below the block, then
      // the block's triangle with plain loops (as forward).
      t.resize(nr);
      std::copy(y1, y1 + nc, t.begin());
      for (int i = 0; i < m; ++i)
        t[nc + i] = y[rows[i]];
      float* w = t.data();
      const int one = 1;
      const float alpha = -1.0f, beta = 1.0f;
      for (int j0 = ((nc - 1) / kBlock) * kBlock; j0 >= 0; j0 -= kBlock) {
        const int b = std::min(kBlock, nc - j0);
        const int below = nr - j0 - b;
        if (below > 0)
          sgemv_("T", &below, &b, &alpha, L + std::int64_t(j0) * nr + j0 + b, &nr, w + j0 + b, &one,
                 &beta, w + j0, &one);
        for (int j = j0 + b - 1; j >= j0; --j) {
          const float* col = L + std::int64_t(j) * nr;
          float sum = 0.0f;
          for (int i = j + 1; i < j0 + b; ++i)
            sum += col[i] * w[i];
          w[j] = (w[j] - sum) / col[j];
        }
      }
      std::copy(w, w + nc, y1);
      return;
    }
    t.resize(m);
    for (int i = 0; i < m; ++i)
      t[i] = y[rows[i]];
    for (int j = 0; j < nc; ++j) {
      const float* col = L + std::int64_t(j) * nr + nc;
      float sum = 0.0f;
      for (int i = 0; i < m; ++i)
        sum += col[i] * t[i];
      y1[j] -= sum;
    }
    for (int j = nc - 1; j >= 0; --j) {
      const float* col = L + std::int64_t(j) * nr;
      float sum = 0.0f;
      for (int i = j + 1; i < nc; ++i)
        sum += col[i] * y1[i];
      y1[j] = (y1[j] - sum) / col[j];
    }
  }

  // Forward and backward sweeps through supernode k for `width` right-hand sides at once: y holds
  // them row by row (width values per column of the factor), so a supernode's rows are one
  // row-major block, which BLAS reads as the transposed column-major block.
  void forwardMany(int k, int width, float* y, float* accumulate, std::vector<float>& t) const {
    const int nc = columns(k), nr = rowsOf(k), m = nr - nc;
    const float* L = values.data() + px[k];
    float* y1 = y + std::int64_t(super[k]) * width;
    const float one = 1.0f, zero = 0.0f;
    // Y1 <- L11^-1 Y1, as Y1^T <- Y1^T L11^-T.
    strsm_("R", "L", "T", "N", &width, &nc, &one, L, &nr, y1, &width);
    if (m == 0)
      return;
    // T = L21 Y1, as T^T = Y1^T L21^T.
    t.resize(std::size_t(m) * width);
    sgemm_("N", "T", &width, &m, &nc, &one, y1, &width, L + nc, &nr, &zero, t.data(), &width);
    const int* rows = s.data() + pi[k] + nc;
    for (int i = 0; i < m; ++i) {
      const int r = rows[i];
      const float* ti = t.data() + std::int64_t(i) * width;
      if (accumulate && topIndex[r] >= 0) {
        float* a = accumulate + std::int64_t(topIndex[r]) * width;
        for (int q = 0; q < width; ++q)
          a[q] += ti[q];
      } else {
        float* yr = y + std::int64_t(r) * width;
        for (int q = 0; q < width; ++q)
          yr[q] -= ti[q];
      }
    }
  }

  void backwardMany(int k, int width, float* y, std::vector<float>& t) const {
    const int nc = columns(k), nr = rowsOf(k), m = nr - nc;
    const float* L = values.data() + px[k];
    float* y1 = y + std::int64_t(super[k]) * width;
    const float one = 1.0f, minusOne = -1.0f;
    t.resize(std::size_t(m) * width);
    const int* rows = s.data() + pi[k] + nc;
    for (int i = 0; i < m; ++i)
      std::copy_n(y + std::int64_t(rows[i]) * width, width, t.data() + std::int64_t(i) * width);
    // Y1 -= L21^T T with T the rows below, as Y1^T -= T^T L21; then Y1 <- L11^-T Y1, as
    // Y1^T <- Y1^T L11^-1.
    if (m > 0)
      sgemm_("N", "N", &width, &nc, &m, &minusOne, t.data(), &width, L + nc, &nr, &one, y1, &width);
    strsm_("R", "L", "N", "N", &width, &nc, &one, L, &nr, y1, &width);
  }

  // The forward sweep then the backward sweep over every supernode, `width` values per column of
  // y: with the two sides of the split on two threads where there is one.
  template <class Forward, class Backward>
  void sweeps(int width, float* y, const Forward& forward, const Backward& backward) const {
    const int ns = static_cast<int>(super.size()) - 1;
    if (!split) {
      std::vector<float> t;
      for (int k = 0; k < ns; ++k)
        forward(k, y, nullptr, t);
      for (int k = ns - 1; k >= 0; --k)
        backward(k, y, t);
      return;
    }
    std::vector<float> accumulate[2] = {std::vector<float>(std::size_t(topColumns) * width, 0.0f),
                                        std::vector<float>(std::size_t(topColumns) * width, 0.0f)};
    RunOnHelpers(2, [&](int side) {
      std::vector<float> t;
      for (int k : this->side[side])
        forward(k, y, accumulate[side].data(), t);
    });
    for (int k : top)
      for (int c = super[k]; c < super[k + 1]; ++c) {
        const std::int64_t a = std::int64_t(topIndex[c]) * width;
        for (int q = 0; q < width; ++q)
          y[std::int64_t(c) * width + q] -= accumulate[0][a + q] + accumulate[1][a + q];
      }
    std::vector<float> t;
    for (int k : top)
      forward(k, y, nullptr, t);
    for (auto it = top.rbegin(); it != top.rend(); ++it)
      backward(*it, y, t);
    RunOnHelpers(2, [&](int side) {
      std::vector<float> t;
      for (auto it = this->side[side].rbegin(); it != this->side[side].rend(); ++it)
        backward(*it, y, t);
    });
  }

  // Chooses the top part and two sides that minimise the top's work plus the larger side's
  // (greedy: the heaviest subtree below the top joins it, and each step's split is tried).
  void chooseSplit(const SupernodalStructure& tree) {
    const int ns = tree.nsuper;
    const std::vector<int> parent = SupernodeParents(tree, SupernodeOfColumns(tree));
    std::vector<double> work(ns), subtree(ns);
    std::vector<std::vector<int>> children(ns);
    double total = 0.0;
    for (int k = 0; k < ns; ++k) {
      work[k] = double(columns(k)) * rowsOf(k);
      total += work[k];
    }
    for (int k = 0; k < ns; ++k) {
      subtree[k] += work[k];
      if (parent[k] >= 0) {
        subtree[parent[k]] += subtree[k];
        children[parent[k]].push_back(k);
      }
    }
    // The candidate roots in ascending order of their subtree's work (ties by index), the heaviest
    // last: kept sorted as the heaviest moves to the top and its children come in, rather than
    // sorted afresh at each step (a factor whose analysis leaves pinned DOFs uncoupled has a root
    // for each, a thousand on the face's scenes).
    auto lighter = [&](int a, int b) {
      return subtree[a] < subtree[b] || (subtree[a] == subtree[b] && a > b);
    };
    // Roots of at most `light` work are not placed one by one while the split is searched: their
    // sum goes to the lighter side, as placing them would about do.
    const double light = total / 65536.0;
    std::vector<char> inTop(ns, 0); // after the replay below: the best step's top
    std::vector<int> candidates;
    double lightWork = 0.0; // of the candidates of at most `light` work
    auto start = [&] {
      candidates.clear();
      lightWork = 0.0;
      for (int k = 0; k < ns; ++k)
        if (parent[k] < 0) {
          candidates.push_back(k);
          lightWork += subtree[k] <= light ? subtree[k] : 0.0;
        }
      std::sort(candidates.begin(), candidates.end(), lighter);
    };
    auto raise = [&] { // the heaviest candidate to the top
      const int heaviest = candidates.back();
      candidates.pop_back();
      inTop[heaviest] = 1;
      lightWork -= subtree[heaviest] <= light ? subtree[heaviest] : 0.0;
      for (int c : children[heaviest]) {
        candidates.insert(std::upper_bound(candidates.begin(), candidates.end(), c, lighter), c);
        lightWork += subtree[c] <= light ? subtree[c] : 0.0;
      }
      return heaviest;
    };
    // The roots to two sides, heaviest first, each to the lighter side; the larger side's work
    // (-1 where a side is empty). With `sideOf`, every root placed; else the light ones summed.
    auto sides = [&](std::vector<int>* sideOf) {
      double bin[2] = {0.0, 0.0};
      if (sideOf)
        sideOf->assign(candidates.size(), 0);
      size_t c = candidates.size();
      for (; c-- > 0;) {
        if (!sideOf && subtree[candidates[c]] <= light)
          break;
        const int b = bin[0] <= bin[1] ? 0 : 1;
        if (sideOf)
          (*sideOf)[c] = b;
        bin[b] += subtree[candidates[c]];
      }
      if (!sideOf && lightWork > 0.0) {
        const double gap = std::abs(bin[0] - bin[1]);
        bin[bin[0] <= bin[1] ? 0 : 1] += std::min(gap, lightWork);
        bin[0] += 0.5 * (lightWork - std::min(gap, lightWork));
        bin[1] += 0.5 * (lightWork - std::min(gap, lightWork));
      }
      return std::min(bin[0], bin[1]) > 0.0 ? std::max(bin[0], bin[1]) : -1.0;
    };
    // Each step's makespan, then the best step replayed.
    start();
    double best = total, topWork = 0.0;
    int bestStep = -1;
    for (int step = 0; step < 256 && !candidates.empty() && topWork < best; ++step) {
      const double larger = sides(nullptr);
      if (larger >= 0.0 && topWork + larger < best) {
        best = topWork + larger;
        bestStep = step;
      }
      topWork += work[raise()];
    }
    std::fill(inTop.begin(), inTop.end(), 0);
    std::vector<int> sideOf; // per candidate root of the best step: 0 or 1
    if (bestStep >= 0) {
      start();
      for (int step = 0; step < bestStep; ++step)
        raise();
      sides(&sideOf);
    }
    // Two threads only where they save a tenth of the work.
    split = bestStep >= 0 && best < 0.9 * total;
    if (!split)
      return;
    std::vector<int> owner(ns, -1); // -1: top
    for (size_t c = 0; c < candidates.size(); ++c)
      owner[candidates[c]] = sideOf[c];
    for (int k = ns - 1; k >= 0; --k)
      if (!inTop[k] && owner[k] < 0 && parent[k] >= 0)
        owner[k] = owner[parent[k]];
    topIndex.assign(n, -1);
    topColumns = 0;
    for (int k = 0; k < ns; ++k) {
      if (inTop[k]) {
        top.push_back(k);
        for (int c = super[k]; c < super[k + 1]; ++c)
          topIndex[c] = topColumns++;
      } else {
        side[owner[k]].push_back(k);
      }
    }
  }
};

SinglePrecisionFactor::SinglePrecisionFactor() : impl_(std::make_unique<Impl>()) {}
SinglePrecisionFactor::~SinglePrecisionFactor() = default;

void SinglePrecisionFactor::Impl::adoptStructure(const cholmod_factor& L,
                                                 const SupernodalStructure& tree) {
  n = tree.n;
  super.assign(tree.super, tree.super + tree.nsuper + 1);
  pi.assign(tree.pi, tree.pi + tree.nsuper + 1);
  s.assign(tree.s, tree.s + pi.back());
  const int* starts = static_cast<const int*>(L.px);
  px.assign(starts, starts + tree.nsuper + 1);
  const int* order = static_cast<const int*>(L.Perm);
  if (order)
    perm.assign(order, order + n);
  else
    for (int k = 0; k < n; ++k)
      perm.push_back(k);
  values.resize(static_cast<size_t>(px.back()));
}

Status SinglePrecisionFactor::assign(const CholmodFactor& factor, int threads) {
  impl_ = std::make_unique<Impl>();
  const cholmod_factor_struct* L = factor.numericFactor();
  if (!L)
    return Status::Error("internal: a single-precision copy needs a numeric factor");
  SupernodalStructure tree;
  Status status = NumericSupernodalStructure(*L, tree);
  if (!status)
    return status;
  Impl& d = *impl_;
  d.adoptStructure(*L, tree);
  const double* x = static_cast<const double*>(L->x);
  // Rounded and checked in one pass, on the cores that first touch the new values' pages.
  std::atomic<bool> fits{true};
  ParallelFor(static_cast<std::int64_t>(d.values.size()), 1 << 16,
              [&](std::int64_t begin, std::int64_t end) {
                float* out = d.values.data();
                bool finite = true;
                for (std::int64_t k = begin; k < end; ++k) {
                  const float v = static_cast<float>(x[k]);
                  out[k] = v;
                  finite &= std::abs(v) <= std::numeric_limits<float>::max(); // false for NaN
                }
                if (!finite)
                  fits = false;
              });
  if (!fits) {
    impl_ = std::make_unique<Impl>();
    return Status::Error("the factor does not fit single precision");
  }
  if (threads > 1 && WorkerThreads(2) > 1)
    d.chooseSplit(tree);
  return Status::Ok();
}

Status SinglePrecisionFactor::factorize(const CholmodFactor& analysed, const SparseMatrix& upper,
                                        int threads, MultifrontalWorkspace* workspace,
                                        const std::shared_ptr<FactorValueBin>& bin,
                                        const FactorReuse& reuse) {
  impl_ = std::make_unique<Impl>(); // the previous values, if any, go to their bin
  const cholmod_factor_struct* L = analysed.analysis();
  if (!L || !L->is_super || L->itype != CHOLMOD_INT)
    return Status::Error("internal: a single-precision factorization needs a supernodal analysis");
  if (upper.rows() != static_cast<Eigen::Index>(L->n) || upper.cols() != upper.rows())
    return Status::Error("internal: the matrix does not match the analysis");
  const SupernodalStructure tree{static_cast<int>(L->n), static_cast<int>(L->nsuper),
                                 static_cast<const int*>(L->super), static_cast<const int*>(L->pi),
                                 static_cast<const int*>(L->s)};
  if (!tree.super || !tree.pi || !tree.s || !L->px)
    return Status::Error("internal: the analysis has no supernodal structure");
  Impl& d = *impl_;
  if (bin) {
    d.values = bin->impl->take(static_cast<size_t>(static_cast<const int*>(L->px)[L->nsuper]));
    d.bin = bin;
  }
  d.adoptStructure(*L, tree);
  // Each supernode's columns are written whole by the factorization, on the thread that factors
  // it (which so first touches those pages, where they are fresh).
  MultifrontalReport report;
  const Status status =
      reuse.from ? MultifrontalRefactorizeSingle(upper, *L, d.values.data(), WorkerThreads(16),
                                                 *reuse.from, reuse.tolerance, &report, workspace)
                 : MultifrontalFactorizeSingle(upper, *L, d.values.data(), WorkerThreads(16),
                                               &report, workspace, reuse.keep);
  if (!status) {
    impl_ = std::make_unique<Impl>();
    return status;
  }
  d.factoredShare = report.factoredFlopsShare;
  if (threads > 1 && WorkerThreads(2) > 1)
    d.chooseSplit(tree);
  return Status::Ok();
}

double SinglePrecisionFactor::factoredShare() const {
  return impl_->factoredShare;
}

Status SinglePrecisionFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const Impl& d = *impl_;
  if (d.values.empty() || b.size() != d.n)
    return Status::Error("internal: single-precision solve before assign, or a wrong size");
  const double scale = b.cwiseAbs().maxCoeff();
  x.setZero(d.n);
  if (!(scale > 0.0))
    return std::isfinite(scale) ? Status::Ok() : Status::Error("the right-hand side is not finite");
  std::vector<float> y(d.n);
  for (int k = 0; k < d.n; ++k)
    y[k] = static_cast<float>(b[d.perm[k]] / scale);
  // One BLAS thread: these triangular solves and products are too small for threaded BLAS.
  ScopedBlasThreads serial(1, BlasScope::Pinned);
  d.sweeps(
      1, y.data(),
      [&d](int k, float* y, float* accumulate, std::vector<float>& t) {
        d.forward(k, y, accumulate, t);
      },
      [&d](int k, float* y, std::vector<float>& t) { d.backward(k, y, t); });
  for (int k = 0; k < d.n; ++k)
    x[d.perm[k]] = static_cast<double>(y[k]) * scale;
  if (!x.allFinite())
    return Status::Error("the single-precision substitution overflowed");
  return Status::Ok();
}

Status SinglePrecisionFactor::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
  const Impl& d = *impl_;
  if (d.values.empty() || b.rows() != d.n)
    return Status::Error("internal: single-precision solve before assign, or a wrong size");
  if (!b.allFinite())
    return Status::Error("the right-hand side is not finite");
  x.setZero(d.n, b.cols());
  ScopedBlasThreads serial(1, BlasScope::Pinned);
  std::vector<float> y;
  for (Eigen::Index first = 0; first < b.cols(); first += kRightHandSides) {
    const int width = static_cast<int>(std::min<Eigen::Index>(kRightHandSides, b.cols() - first));
    // Each column scaled to unit largest entry (a zero column stays zero).
    Eigen::VectorXd scale(width);
    for (int q = 0; q < width; ++q) {
      const double largest = b.col(first + q).cwiseAbs().maxCoeff();
      scale[q] = largest > 0.0 ? largest : 1.0;
    }
    y.resize(std::size_t(d.n) * width);
    for (int k = 0; k < d.n; ++k)
      for (int q = 0; q < width; ++q)
        y[std::size_t(k) * width + q] = static_cast<float>(b(d.perm[k], first + q) / scale[q]);
    d.sweeps(
        width, y.data(),
        [&d, width](int k, float* y, float* accumulate, std::vector<float>& t) {
          d.forwardMany(k, width, y, accumulate, t);
        },
        [&d, width](int k, float* y, std::vector<float>& t) { d.backwardMany(k, width, y, t); });
    for (int k = 0; k < d.n; ++k)
      for (int q = 0; q < width; ++q)
        x(d.perm[k], first + q) = static_cast<double>(y[std::size_t(k) * width + q]) * scale[q];
  }
  if (!x.allFinite())
    return Status::Error("the single-precision substitution overflowed");
  return Status::Ok();
}

Eigen::Index SinglePrecisionFactor::rows() const {
  return impl_->n;
}

double SinglePrecisionFactor::valueBytes() const {
  return 4.0 * double(impl_->values.size());
}

SinglePrecisionFactor::Layout SinglePrecisionFactor::layout() const {
  const Impl& d = *impl_;
  Layout out;
  if (d.super.empty())
    return out;
  out.n = d.n;
  out.nsuper = static_cast<int>(d.super.size()) - 1;
  out.super = d.super.data();
  out.pi = d.pi.data();
  out.px = d.px.data();
  out.s = d.s.data();
  out.values = d.values.data();
  out.perm = d.perm.data();
  return out;
}

} // namespace faceplan
