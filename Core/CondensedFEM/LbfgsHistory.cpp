// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/LbfgsHistory.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace faceplan {

namespace {

// The passes' blocks: a block of the pairs' rows and the vectors it is combined with stays in the
// core's cache while every pair is done with it.
constexpr Eigen::Index kBlock = 4096;

// Runs body(block, first, end) for every block in order, on the calling thread: a pass is tens of
// microseconds, and helper threads that slept while the GPU substituted take longer than that to
// wake on a virtual machine.
template <class Body> void ForBlocks(Eigen::Index n, const Body& body) {
  const Eigen::Index blocks = (n + kBlock - 1) / kBlock;
  for (Eigen::Index b = 0; b < blocks; ++b)
    body(b, b * kBlock, std::min(n, (b + 1) * kBlock));
}

// Sums per block (rows: blocks, columns: the sums), added in block order.
Eigen::VectorXd SumBlocks(const Eigen::MatrixXd& partial) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(partial.cols());
  for (Eigen::Index b = 0; b < partial.rows(); ++b)
    sum += partial.row(b).transpose();
  return sum;
}

Eigen::Index Blocks(Eigen::Index n) {
  return (n + kBlock - 1) / kBlock;
}

} // namespace

void LbfgsHistory::clear() {
  s_.clear();
  y_.clear();
  rho_.clear();
  gram_.clear();
}

bool LbfgsHistory::add(const Eigen::VectorXd& x1, const Eigen::VectorXd& x0,
                       const Eigen::VectorXd& r1, const Eigen::VectorXd& r0) {
  const Eigen::Index n = x1.size();
  if (capacity_ <= 0 || x0.size() != n || r1.size() != n || r0.size() != n)
    return false;
  const int k = size();
  Eigen::VectorXd& s = spareS_;
  Eigen::VectorXd& y = spareY_;
  s.resize(n);
  y.resize(n);
  // One pass: s, y, s.y, s.s, y.y and every kept s_i.y.
  Eigen::MatrixXd partial(Blocks(n), k + 3);
  ForBlocks(n, [&](Eigen::Index b, Eigen::Index first, Eigen::Index end) {
    const Eigen::Index len = end - first;
    auto sb = s.segment(first, len);
    auto yb = y.segment(first, len);
    sb = x1.segment(first, len) - x0.segment(first, len);
    yb = r1.segment(first, len) - r0.segment(first, len);
    partial(b, 0) = sb.dot(yb);
    partial(b, 1) = sb.squaredNorm();
    partial(b, 2) = yb.squaredNorm();
    for (int i = 0; i < k; ++i)
      partial(b, 3 + i) = s_[i].segment(first, len).dot(yb);
  });
  const Eigen::VectorXd sums = SumBlocks(partial);
  const double sy = sums[0], ss = sums[1], yy = sums[2];
  if (!(sy > 1e-14 * std::sqrt(ss) * std::sqrt(yy)))
    return false;
  Eigen::VectorXd oldS, oldY;
  int dropped = 0;
  if (k == capacity_) {
    oldS = std::move(s_.front());
    oldY = std::move(y_.front());
    s_.pop_front();
    y_.pop_front();
    rho_.pop_front();
    gram_.pop_front();
    for (auto& row : gram_)
      row.pop_front();
    dropped = 1;
  }
  // The new column (s_i.y for each pair i kept), and the new pair's row (only j > i is read).
  for (int i = 0; i < static_cast<int>(gram_.size()); ++i)
    gram_[i].push_back(sums[3 + i + dropped]);
  gram_.emplace_back(s_.size() + 1, 0.0);
  s_.push_back(std::move(s));
  y_.push_back(std::move(y));
  rho_.push_back(1.0 / sy);
  spareS_ = std::move(oldS);
  spareY_ = std::move(oldY);
  return true;
}

void LbfgsHistory::direction(
    const Eigen::VectorXd& r,
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& applyInitial,
    Eigen::VectorXd& out) {
  const Eigen::Index n = r.size();
  const int k = size();
  if (k == 0) {
    out = applyInitial(r);
    if (out.size() != 0)
      out = -out;
    return;
  }
  // The first loop's scalars: a_i = rho_i (s_i.r - sum over j > i of a_j s_i.y_j), newest first.
  Eigen::MatrixXd partial(Blocks(n), k);
  ForBlocks(n, [&](Eigen::Index b, Eigen::Index first, Eigen::Index end) {
    const auto rb = r.segment(first, end - first);
    for (int i = 0; i < k; ++i)
      partial(b, i) = s_[i].segment(first, end - first).dot(rb);
  });
  const Eigen::VectorXd sr = SumBlocks(partial);
  std::vector<double> a(k), c(k);
  for (int i = k - 1; i >= 0; --i) {
    double v = sr[i];
    for (int j = i + 1; j < k; ++j)
      v -= a[j] * gram_[i][j];
    a[i] = rho_[i] * v;
  }
  // q = r - sum a_j y_j, then H0 q.
  q_.resize(n);
  ForBlocks(n, [&](Eigen::Index, Eigen::Index first, Eigen::Index end) {
    auto qb = q_.segment(first, end - first);
    qb = r.segment(first, end - first);
    for (int j = k - 1; j >= 0; --j)
      qb -= a[j] * y_[j].segment(first, end - first);
  });
  out = applyInitial(q_);
  if (out.size() == 0)
    return;
  // The second loop's scalars: b_i = rho_i (y_i.z + sum over j < i of (a_j - b_j) s_j.y_i),
  // oldest first; then z += sum (a_i - b_i) s_i, negated.
  ForBlocks(n, [&](Eigen::Index b, Eigen::Index first, Eigen::Index end) {
    const auto zb = out.segment(first, end - first);
    for (int i = 0; i < k; ++i)
      partial(b, i) = y_[i].segment(first, end - first).dot(zb);
  });
  const Eigen::VectorXd yz = SumBlocks(partial);
  for (int i = 0; i < k; ++i) {
    double v = yz[i];
    for (int j = 0; j < i; ++j)
      v += c[j] * gram_[j][i];
    c[i] = a[i] - rho_[i] * v;
  }
  ForBlocks(n, [&](Eigen::Index, Eigen::Index first, Eigen::Index end) {
    auto zb = out.segment(first, end - first);
    for (int i = 0; i < k; ++i)
      zb += c[i] * s_[i].segment(first, end - first);
    zb = -zb;
  });
}

Eigen::VectorXd TwoLoopDirection(const std::deque<Eigen::VectorXd>& s,
                                 const std::deque<Eigen::VectorXd>& y, const Eigen::VectorXd& r,
                                 const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& h0) {
  const int k = static_cast<int>(s.size());
  Eigen::VectorXd q = r;
  std::vector<double> a(k), rho(k);
  for (int i = k - 1; i >= 0; --i) {
    rho[i] = 1.0 / s[i].dot(y[i]);
    a[i] = rho[i] * s[i].dot(q);
    q -= a[i] * y[i];
  }
  Eigen::VectorXd z = h0(q);
  for (int i = 0; i < k; ++i) {
    const double b = rho[i] * y[i].dot(z);
    z += (a[i] - b) * s[i];
  }
  return -z;
}

} // namespace faceplan
