// SPDX-License-Identifier: BSD-3-Clause
// SparseSolver/SinglePrecisionFactor: the single-precision substitutions with a copy of a
// supernodal factor solve the factored matrix to single precision's accuracy (relative to the
// double substitution), on one thread and split over two, the same either way; a factor that is
// not numeric, or whose values a float cannot hold, is refused. Factored directly in single
// precision, it solves as the copy does; where single precision breaks down it is refused. Values
// recycled through a bin are all overwritten.
#include "CondensedFEM/CondensedSystem.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/MultifrontalWorkspace.h"
#include "SparseSolver/SinglePrecisionFactor.h"
#include "Support/FEMTestScenes.h"

#include <gtest/gtest.h>

using namespace faceplan;
using namespace faceplan::testing;

namespace {

struct Factored {
  std::shared_ptr<const CondensedSystem> system;
  CholmodFactor factor;
};

void Factor(Factored& f) {
  ASSERT_TRUE(Precompute(ShellRequest(12, 4), f.system).ok);
  ASSERT_TRUE(f.factor.analyze(f.system->kff).ok);
  ASSERT_TRUE(f.factor.factorize(f.system->kff).ok);
}

} // namespace

TEST(SinglePrecisionFactor, SolvesTheFactoredMatrixToSinglePrecision) {
  Factored f;
  Factor(f);
  const SparseMatrix& k = f.system->kff;
  Eigen::VectorXd b = Eigen::VectorXd::Random(k.rows());
  Eigen::MatrixXd exact;
  ASSERT_TRUE(f.factor.solve(b, exact).ok);
  for (int threads : {1, 2}) {
    SinglePrecisionFactor single;
    ASSERT_TRUE(single.assign(f.factor, threads).ok);
    EXPECT_EQ(single.rows(), k.rows());
    Eigen::VectorXd x;
    ASSERT_TRUE(single.solve(b, x).ok);
    const double error = (x - exact.col(0)).norm() / exact.col(0).norm();
    EXPECT_LT(error, 1e-4) << threads << " thread(s)";
    EXPECT_GT(error, 1e-12) << "a double-precision solve, not a single-precision one";
    const Eigen::VectorXd residual = k.selfadjointView<Eigen::Upper>() * x - b;
    EXPECT_LT(residual.norm() / b.norm(), 1e-4);
    // A scaled right-hand side gives the scaled solution (b is scaled before it is rounded).
    Eigen::VectorXd scaled;
    ASSERT_TRUE(single.solve(1e-200 * b, scaled).ok);
    EXPECT_LT((scaled - 1e-200 * x).norm(), 1e-6 * 1e-200 * x.norm());
  }
  // One thread and two threads: the same sums in a different order only.
  SinglePrecisionFactor one, two;
  ASSERT_TRUE(one.assign(f.factor, 1).ok);
  ASSERT_TRUE(two.assign(f.factor, 2).ok);
  Eigen::VectorXd x1, x2;
  ASSERT_TRUE(one.solve(b, x1).ok);
  ASSERT_TRUE(two.solve(b, x2).ok);
  EXPECT_LT((x1 - x2).norm() / x1.norm(), 1e-5);
  EXPECT_EQ(one.valueBytes(), two.valueBytes());
  EXPECT_GT(one.valueBytes(), 0.0);
}

TEST(SinglePrecisionFactor, SeveralRightHandSidesAtOnceEqualOneByOne) {
  Factored f;
  Factor(f);
  const Eigen::Index n = f.system->kff.rows();
  // More columns than one pass takes, with a zero column and columns of very different scales.
  Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 41);
  b.col(3).setZero();
  b.col(7) *= 1e-150;
  b.col(40) *= 1e150;
  for (int threads : {1, 2}) {
    SinglePrecisionFactor single;
    ASSERT_TRUE(single.assign(f.factor, threads).ok);
    Eigen::MatrixXd x;
    ASSERT_TRUE(single.solve(b, x).ok);
    ASSERT_EQ(x.rows(), n);
    ASSERT_EQ(x.cols(), b.cols());
    EXPECT_EQ(x.col(3).norm(), 0.0);
    for (Eigen::Index c = 0; c < b.cols(); ++c) {
      if (c == 3)
        continue;
      Eigen::VectorXd one;
      ASSERT_TRUE(single.solve(Eigen::VectorXd(b.col(c)), one).ok);
      EXPECT_LT((x.col(c) - one).norm(), 1e-5 * one.norm())
          << "column " << c << ", " << threads << " thread(s)";
    }
  }
  SinglePrecisionFactor single;
  ASSERT_TRUE(single.assign(f.factor).ok);
  Eigen::MatrixXd x;
  EXPECT_FALSE(single.solve(Eigen::MatrixXd::Ones(3, 2), x).ok) << "a wrong size";
  b(5, 9) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(single.solve(b, x).ok);
}

TEST(SinglePrecisionFactor, ZeroAndBadInput) {
  Factored f;
  Factor(f);
  SinglePrecisionFactor single;
  Eigen::VectorXd x;
  EXPECT_FALSE(single.solve(Eigen::VectorXd::Ones(f.system->kff.rows()), x).ok)
      << "a solve before assign";
  ASSERT_TRUE(single.assign(f.factor).ok);
  ASSERT_TRUE(single.solve(Eigen::VectorXd::Zero(f.system->kff.rows()), x).ok);
  EXPECT_EQ(x.norm(), 0.0);
  EXPECT_FALSE(single.solve(Eigen::VectorXd::Ones(3), x).ok) << "a wrong size";
  Eigen::VectorXd nan = Eigen::VectorXd::Ones(f.system->kff.rows());
  nan[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(single.solve(nan, x).ok);
  CholmodFactor unfactored;
  EXPECT_FALSE(single.assign(unfactored).ok);
}

TEST(SinglePrecisionFactor, AFactorBeyondSinglePrecisionIsRefused) {
  // The factor of diag(1, 1e80, 1) holds 1e40, beyond a float's range; of diag(1, 1e60, 1), 1e30.
  for (double big : {1e80, 1e60}) {
    SparseMatrix upper(3, 3);
    upper.insert(0, 0) = 1.0;
    upper.insert(1, 1) = big;
    upper.insert(2, 2) = 1.0;
    upper.makeCompressed();
    CholmodFactor factor;
    ASSERT_TRUE(factor.analyze(upper).ok);
    ASSERT_TRUE(factor.factorize(upper).ok);
    SinglePrecisionFactor single;
    const Status assigned = single.assign(factor);
    if (big > 1e76) {
      EXPECT_FALSE(assigned.ok);
      EXPECT_NE(assigned.message.find("single precision"), std::string::npos) << assigned.message;
      EXPECT_EQ(single.valueBytes(), 0.0) << "nothing kept";
    } else {
      EXPECT_TRUE(assigned.ok) << assigned.message;
    }
  }
}

TEST(SinglePrecisionFactor, FactoredDirectlyEqualsTheCopyOfTheDoubleFactor) {
  Factored f;
  Factor(f);
  const SparseMatrix& k = f.system->kff;
  CholmodFactor analysed; // analysed only: the single-precision factorization reads its structure
  ASSERT_TRUE(analysed.analyze(k).ok);
  ASSERT_FALSE(analysed.isFactorized());
  Eigen::VectorXd b = Eigen::VectorXd::Random(k.rows());
  Eigen::MatrixXd exact;
  ASSERT_TRUE(f.factor.solve(b, exact).ok);
  SinglePrecisionFactor copied;
  ASSERT_TRUE(copied.assign(f.factor).ok);
  Eigen::VectorXd fromCopy;
  ASSERT_TRUE(copied.solve(b, fromCopy).ok);
  for (int threads : {1, 2}) {
    SinglePrecisionFactor direct;
    const Status factored = direct.factorize(analysed, k, threads);
    ASSERT_TRUE(factored.ok) << factored.message;
    EXPECT_EQ(direct.valueBytes(), copied.valueBytes());
    Eigen::VectorXd x;
    ASSERT_TRUE(direct.solve(b, x).ok);
    const double error = (x - exact.col(0)).norm() / exact.col(0).norm();
    EXPECT_LT(error, 1e-4) << threads << " thread(s)";
    EXPECT_GT(error, 1e-12) << "a double-precision solve, not a single-precision one";
    EXPECT_LT((x - fromCopy).norm() / fromCopy.norm(), 1e-4);
    const Eigen::VectorXd residual = k.selfadjointView<Eigen::Upper>() * x - b;
    EXPECT_LT(residual.norm() / b.norm(), 1e-4);
  }
}

TEST(SinglePrecisionFactor, ADirectFactorizationThatBreaksDownIsRefused) {
  // [[1, 1 - 1e-9], [1 - 1e-9, 1]] is positive definite, but its off-diagonal rounds to 1 in single
  // precision, where the matrix is singular.
  SparseMatrix nearlySingular(2, 2);
  nearlySingular.insert(0, 0) = 1.0;
  nearlySingular.insert(0, 1) = 1.0 - 1e-9;
  nearlySingular.insert(1, 1) = 1.0;
  nearlySingular.makeCompressed();
  CholmodFactor analysed;
  ASSERT_TRUE(analysed.analyze(nearlySingular).ok);
  SinglePrecisionFactor single;
  Status factored = single.factorize(analysed, nearlySingular);
  EXPECT_FALSE(factored.ok);
  EXPECT_NE(factored.message.find("not positive definite"), std::string::npos) << factored.message;
  EXPECT_EQ(single.valueBytes(), 0.0) << "nothing kept";
  Eigen::VectorXd x;
  EXPECT_FALSE(single.solve(Eigen::VectorXd::Ones(2), x).ok);
  CholmodFactor inDouble;
  ASSERT_TRUE(inDouble.analyze(nearlySingular).ok);
  EXPECT_TRUE(inDouble.factorize(nearlySingular).ok) << "positive definite in double precision";

  // Entries beyond a float's range, a matrix of another size, and no analysis.
  SparseMatrix huge = nearlySingular;
  huge.coeffRef(1, 1) = 1e80;
  factored = single.factorize(analysed, huge);
  EXPECT_FALSE(factored.ok);
  EXPECT_NE(factored.message.find("single precision"), std::string::npos) << factored.message;
  SparseMatrix other(3, 3);
  other.setIdentity();
  other.makeCompressed();
  EXPECT_FALSE(single.factorize(analysed, other).ok);
  CholmodFactor none;
  EXPECT_FALSE(single.factorize(none, nearlySingular).ok);
}

// Factors made with a bin give their values back when they are gone, and the next factorization
// of that size takes them. The recycled values held another matrix's factor: every one of them must
// be overwritten, so the factor solves exactly as a fresh one does. A factor may outlive its bin.
TEST(SinglePrecisionFactor, ABinPassesTheValuesOfAFactorThatIsGoneToTheNext) {
  Factored f;
  Factor(f);
  const SparseMatrix& k = f.system->kff;
  CholmodFactor analysed;
  ASSERT_TRUE(analysed.analyze(k).ok);
  const SparseMatrix other = 3.0 * k; // the same pattern, other values
  const Eigen::VectorXd b = Eigen::VectorXd::Random(k.rows());
  Eigen::VectorXd fresh;
  {
    SinglePrecisionFactor plain;
    ASSERT_TRUE(plain.factorize(analysed, k).ok);
    ASSERT_TRUE(plain.solve(b, fresh).ok);
  }
  auto bin = std::make_shared<FactorValueBin>();
  MultifrontalWorkspace workspace;
  double bytes = 0.0;
  {
    SinglePrecisionFactor first;
    ASSERT_TRUE(first.factorize(analysed, other, 2, &workspace, bin).ok);
    bytes = first.valueBytes();
    EXPECT_EQ(bin->keptBytes(), 0.0);
  }
  EXPECT_EQ(bin->keptBytes(), bytes) << "the values of the factor that is gone";
  SinglePrecisionFactor second;
  ASSERT_TRUE(second.factorize(analysed, k, 2, &workspace, bin).ok);
  EXPECT_EQ(bin->keptBytes(), 0.0) << "taken by the next factorization";
  EXPECT_EQ(workspace.plansReused(), 1);
  Eigen::VectorXd x;
  ASSERT_TRUE(second.solve(b, x).ok);
  EXPECT_TRUE(x == fresh) << "differs from a fresh factor's solution by "
                          << (x - fresh).norm() / fresh.norm();
  // Factored again, it gives its values back first and takes them again.
  ASSERT_TRUE(second.factorize(analysed, other, 2, &workspace, bin).ok);
  ASSERT_TRUE(second.factorize(analysed, k, 2, &workspace, bin).ok);
  EXPECT_EQ(bin->keptBytes(), 0.0);
  ASSERT_TRUE(second.solve(b, x).ok);
  EXPECT_TRUE(x == fresh);
  // A factor that outlives its bin frees its values itself.
  SinglePrecisionFactor last;
  ASSERT_TRUE(last.factorize(analysed, k, 2, &workspace, bin).ok);
  bin.reset();
}
