// SPDX-License-Identifier: BSD-3-Clause
#include "Backend/ComputeBackend.h"

#include "Common/StageTimings.h"
#include "Element/ElementStiffness.h"

#include <vector>

namespace faceplan {

namespace {

class CpuResponse final : public ResponseOperator {
public:
  explicit CpuResponse(const Eigen::MatrixXd& response) : response_(response) {}
  Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) override {
    if (response_.cols() != roi.size())
      return Status::Error("ROI vector does not match the response");
    // An edit often moves only part of the ROI (the bone under a cut, one segment): the product
    // is memory-bound, so reading only the columns of non-zero values saves in proportion.
    std::vector<Eigen::Index> nonZero; // local: concurrent solves share this operator
    for (Eigen::Index j = 0; j < roi.size(); ++j)
      if (roi[j] != 0.0)
        nonZero.push_back(j);
    if (4 * nonZero.size() >= 3 * static_cast<size_t>(roi.size())) {
      kept.noalias() = response_ * roi;
      return Status::Ok();
    }
    kept.setZero(response_.rows());
    for (Eigen::Index j : nonZero)
      kept.noalias() += roi[j] * response_.col(j);
    return Status::Ok();
  }

private:
  const Eigen::MatrixXd& response_; // owned by the CondensedSystem, which owns this operator too
};

class CpuBackend final : public ComputeBackend {
public:
  std::string name() const override { return "CPU"; }

  Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                           AssemblyPattern& pattern, AssemblyTimings& timings) override {
    StageClock clock;
    PackedElementMatrices packed;
    ComputePackedElementStiffness(mesh, materials, packed);
    timings.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed.data(), pattern);
    timings.assemblyMs = clock.lapMs();
    return Status::Ok();
  }

  Status makeResponseOperator(const Eigen::MatrixXd& response,
                              std::unique_ptr<ResponseOperator>& op) override {
    op = std::make_unique<CpuResponse>(response);
    return Status::Ok();
  }
};

} // namespace

std::shared_ptr<ComputeBackend> MakeCpuBackend() {
  return std::make_shared<CpuBackend>();
}

} // namespace faceplan
