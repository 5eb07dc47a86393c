// SPDX-License-Identifier: BSD-3-Clause
// LbfgsHistory's compact recursion against the plain two-loop recursion over the same pairs.
#include "CondensedFEM/LbfgsHistory.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <deque>
#include <random>

using namespace faceplan;

namespace {

struct Quadratic {
  Eigen::MatrixXd a; // symmetric positive definite
  Eigen::VectorXd gradient(const Eigen::VectorXd& x) const { return a * x; }
};

Quadratic MakeQuadratic(int n, std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd m(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      m(i, j) = normal(random);
  return {m * m.transpose() / n + Eigen::MatrixXd::Identity(n, n)};
}

Eigen::VectorXd Random(int n, std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i)
    v[i] = normal(random);
  return v;
}

double RelativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

} // namespace

// Pairs of a quadratic, more than the history keeps (the oldest go), on a size whose passes run
// on several blocks and threads: each direction equals the two-loop recursion's over the pairs
// kept, with a non-trivial H0 (a diagonal scaling), and the same inputs give the same bits.
TEST(LbfgsHistory, EqualsTheTwoLoopRecursion) {
  for (int n : {7, 40000}) {
    std::mt19937 random(3);
    const int dense = std::min(n, 60);
    const Quadratic q = MakeQuadratic(dense, random);
    // The energy's Hessian: q.a on the first `dense` DOFs, 2 on the others.
    auto gradient = [&](const Eigen::VectorXd& x) {
      Eigen::VectorXd g = 2.0 * x;
      g.head(dense) = q.gradient(x.head(dense));
      return g;
    };
    const Eigen::VectorXd scale = Random(n, random).cwiseAbs().array() + 0.5;
    auto h0 = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return scale.cwiseProduct(v); };
    LbfgsHistory history(5);
    std::deque<Eigen::VectorXd> s, y;
    Eigen::VectorXd x = Random(n, random), d;
    for (int step = 0; step < 9; ++step) {
      const Eigen::VectorXd r = gradient(x);
      history.direction(r, h0, d);
      const Eigen::VectorXd reference = TwoLoopDirection(s, y, r, h0);
      ASSERT_EQ(d.size(), n);
      EXPECT_LT(RelativeDifference(d, reference), 1e-12) << "n " << n << " step " << step;
      Eigen::VectorXd again;
      history.direction(r, h0, again);
      EXPECT_EQ((again - d).cwiseAbs().maxCoeff(), 0.0);
      const Eigen::VectorXd x1 = x + 0.7 * d;
      ASSERT_TRUE(history.add(x1, x, gradient(x1), r));
      s.push_back(x1 - x);
      y.push_back(gradient(x1) - r);
      if (static_cast<int>(s.size()) > 5) {
        s.pop_front();
        y.pop_front();
      }
      EXPECT_EQ(history.size(), static_cast<int>(s.size()));
      x = x1;
    }
  }
}

// A pair without positive curvature is not kept; a failed H0 is passed on as an empty direction.
TEST(LbfgsHistory, RefusesAPairWithoutCurvatureAndPassesOnAFailedInitialHessian) {
  LbfgsHistory history(4);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(3), x1 = Eigen::VectorXd::Ones(3);
  EXPECT_FALSE(history.add(x1, x0, -x1, x0)); // s.y < 0
  EXPECT_EQ(history.size(), 0);
  EXPECT_TRUE(history.add(x1, x0, x1, x0));
  Eigen::VectorXd d;
  history.direction(
      x1, [](const Eigen::VectorXd&) { return Eigen::VectorXd(); }, d);
  EXPECT_EQ(d.size(), 0);
  history.clear();
  EXPECT_EQ(history.size(), 0);
  LbfgsHistory none(0);
  EXPECT_FALSE(none.add(x1, x0, x1, x0));
}
