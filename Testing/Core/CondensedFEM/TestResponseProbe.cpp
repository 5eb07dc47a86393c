// SPDX-License-Identifier: BSD-3-Clause
// The probe of a backend's response operator (Core/CondensedFEM/ResponseProbe): the rows it
// compares, in full and sampled, and that it sees a wrong block or a lower precision there.
#include "CondensedFEM/ResponseProbe.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace faceplan;

namespace {

// response * roi, then `damage` applied to the product.
class DamagedOperator : public ResponseOperator {
public:
  DamagedOperator(const Eigen::MatrixXd& r, std::function<void(Eigen::VectorXd&)> d)
      : response_(r), damage_(std::move(d)) {}
  Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) override {
    kept = response_ * roi;
    damage_(kept);
    return Status::Ok();
  }

private:
  const Eigen::MatrixXd& response_;
  std::function<void(Eigen::VectorXd&)> damage_;
};

// 10,000 rows: blocks of 4096 rows 0, 1 and 2 (1,808 rows).
const Eigen::MatrixXd& Response() {
  static const Eigen::MatrixXd r = Eigen::MatrixXd::Random(10000, 3);
  return r;
}
const double kBytes = 8.0 * 10000 * 3;

} // namespace

TEST(ResponseProbe, ComparesEveryRowOfASmallResponse) {
  DamagedOperator exact(Response(), [](Eigen::VectorXd&) {});
  double fraction = 0.0;
  std::string error;
  EXPECT_LT(ProbeResponseOperator(Response(), exact, kBytes, fraction, error), 1e-15);
  EXPECT_EQ(fraction, 1.0);
  DamagedOperator lastRow(Response(), [](Eigen::VectorXd& v) { v[9999] += 1.0; });
  EXPECT_GT(ProbeResponseOperator(Response(), lastRow, kBytes, fraction, error), 1e-3);
}

TEST(ResponseProbe, SamplesBlocksOfALargeOneAndSeesThem) {
  // Twice the full size: every second block and the last, blocks 0 and 2.
  const double fullBytes = kBytes / 2;
  double fraction = 0.0;
  std::string error;
  DamagedOperator exact(Response(), [](Eigen::VectorXd&) {});
  EXPECT_LT(ProbeResponseOperator(Response(), exact, fullBytes, fraction, error), 1e-15);
  EXPECT_DOUBLE_EQ(fraction, (4096.0 + 1808.0) / 10000.0);
  // Single precision everywhere shows in the sampled blocks.
  DamagedOperator single(Response(), [](Eigen::VectorXd& v) {
    for (Eigen::Index i = 0; i < v.size(); ++i)
      v[i] = double(float(v[i]));
  });
  const double deviation = ProbeResponseOperator(Response(), single, fullBytes, fraction, error);
  EXPECT_GT(deviation, 1e-9);
  EXPECT_LT(deviation, 1e-6);
  DamagedOperator firstBlock(Response(), [](Eigen::VectorXd& v) { v[17] += 1.0; });
  EXPECT_GT(ProbeResponseOperator(Response(), firstBlock, fullBytes, fraction, error), 1e-3);
  DamagedOperator lastBlock(Response(), [](Eigen::VectorXd& v) { v[9000] += 1.0; });
  EXPECT_GT(ProbeResponseOperator(Response(), lastBlock, fullBytes, fraction, error), 1e-3);
  // Block 1 is not compared: the sample's documented limit.
  DamagedOperator middleBlock(Response(), [](Eigen::VectorXd& v) { v[5000] += 1.0; });
  EXPECT_LT(ProbeResponseOperator(Response(), middleBlock, fullBytes, fraction, error), 1e-15);
}

TEST(ResponseProbe, WrongSizeIsInfiniteWithAMessage) {
  DamagedOperator shorter(Response(), [](Eigen::VectorXd& v) { v.conservativeResize(10); });
  double fraction = 0.0;
  std::string error;
  EXPECT_TRUE(std::isinf(ProbeResponseOperator(Response(), shorter, kBytes, fraction, error)));
  EXPECT_NE(error.find("wrong size"), std::string::npos);
}
