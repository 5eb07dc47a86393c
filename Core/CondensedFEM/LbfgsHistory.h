// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// L-BFGS's pairs and its direction with a given initial inverse Hessian H0 (the precomputed large
// deformation's factor), in the compact form of the two-loop recursion: the recursion's scalars
// come from the products s_i.y_j of the kept pairs (kept as pairs are added), so that a direction
// is four passes, each over all the pairs at once, instead of two per pair. The same vector as the
// two-loop recursion, to round-off (the tests compare them), in the same time on the machines of
// BENCHMARKS.md: either reads every pair twice, and reading them is what a direction costs.
//
// The passes go over the DOFs by blocks, their sums added block by block in order.
#include <Eigen/Core>

#include <deque>
#include <functional>

namespace faceplan {

class LbfgsHistory {
public:
  explicit LbfgsHistory(int capacity = 8) : capacity_(capacity) {}

  int size() const { return static_cast<int>(s_.size()); }
  int capacity() const { return capacity_; }
  void clear();

  // Makes the pair s = x1 - x0, y = r1 - r0 (r: the energy's gradient) and keeps it (the oldest
  // goes when there are `capacity` already) when its curvature s.y is positive enough for the
  // inverse Hessian to stay positive definite. True when kept.
  bool add(const Eigen::VectorXd& x1, const Eigen::VectorXd& x0, const Eigen::VectorXd& r1,
           const Eigen::VectorXd& r0);

  // -H r, H the L-BFGS inverse Hessian from H0 (applyInitial(q) = H0 q; an empty result is
  // passed on as a failure). `out` keeps its memory from call to call.
  void direction(const Eigen::VectorXd& r,
                 const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& applyInitial,
                 Eigen::VectorXd& out);

private:
  int capacity_;
  std::deque<Eigen::VectorXd> s_, y_;
  std::deque<double> rho_;
  // gram_[i][j] = s_i.y_j for i < j (the pairs in order, oldest first).
  std::deque<std::deque<double>> gram_;
  Eigen::VectorXd q_;
  Eigen::VectorXd spareS_, spareY_; // a dropped pair's memory, for the next pair
};

// The plain two-loop recursion over the same pairs (for the tests).
Eigen::VectorXd TwoLoopDirection(const std::deque<Eigen::VectorXd>& s,
                                 const std::deque<Eigen::VectorXd>& y, const Eigen::VectorXd& r,
                                 const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& h0);

} // namespace faceplan
