// SPDX-License-Identifier: BSD-3-Clause
// The probe of a backend's response operator against the double response.
#include "CondensedFEM/ResponseProbe.h"

#include "Common/ParallelFor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace faceplan {

// Row blocks the probe compares: all of them up to fullBytes of response, else every k-th
// (the last always), so that each probe reads about that much: reading all of a response of
// several GB twice would add a visible part to the precompute. What the probe is for, an operator
// held in lower precision, shows in every block; an error confined to unsampled blocks would pass
// it (the GPU checks its own response's residual before this, and the host copy is a plain chunked
// memcpy).
constexpr Eigen::Index kProbeBlockRows = 4096;

// Relative deviation of a backend's response operator from the double response, on random ROI
// vectors (a float operator shows ~1e-7; a double one ~1e-16), over the sampled row blocks.
double ProbeResponseOperator(const Eigen::MatrixXd& response, ResponseOperator& op,
                             double fullBytes, double& rowFraction, std::string& error) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Eigen::Index rows = response.rows();
  const Eigen::Index blocks = (rows + kProbeBlockRows - 1) / kProbeBlockRows;
  const double bytes = 8.0 * double(response.size());
  const Eigen::Index stride =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::ceil(bytes / fullBytes)));
  std::vector<Eigen::Index> sampled;
  for (Eigen::Index b = 0; b < blocks; b += stride)
    sampled.push_back(b);
  if (!sampled.empty() && sampled.back() != blocks - 1)
    sampled.push_back(blocks - 1);
  Eigen::Index sampledRows = 0;
  for (Eigen::Index b : sampled)
    sampledRows += std::min(kProbeBlockRows, rows - b * kProbeBlockRows);
  rowFraction = rows > 0 ? double(sampledRows) / double(rows) : 1.0;
  double worst = 0.0;
  for (int probe = 0; probe < 2; ++probe) {
    Eigen::VectorXd roi(response.cols());
    for (Eigen::Index k = 0; k < roi.size(); ++k)
      roi[k] = uniform(rng);
    Eigen::VectorXd approx;
    const Status applied = op.apply(roi, approx);
    if (!applied) {
      error = applied.message;
      return std::numeric_limits<double>::infinity();
    }
    if (approx.size() != rows) {
      error = "operator returned the wrong size";
      return std::numeric_limits<double>::infinity();
    }
    // The host product over the sampled row blocks, on every core.
    std::vector<double> exactSquared(sampled.size()), deviationSquared(sampled.size());
    ParallelFor(static_cast<std::int64_t>(sampled.size()), 1,
                [&](std::int64_t i0, std::int64_t i1) {
                  for (std::int64_t i = i0; i < i1; ++i) {
                    const Eigen::Index r0 = sampled[i] * kProbeBlockRows;
                    const Eigen::Index count = std::min(kProbeBlockRows, rows - r0);
                    const Eigen::VectorXd exact = response.middleRows(r0, count) * roi;
                    exactSquared[i] = exact.squaredNorm();
                    deviationSquared[i] = (approx.segment(r0, count) - exact).squaredNorm();
                  }
                });
    double norm = 0.0, dev = 0.0;
    for (size_t i = 0; i < sampled.size(); ++i) {
      norm += exactSquared[i];
      dev += deviationSquared[i];
    }
    norm = std::sqrt(norm);
    dev = std::sqrt(dev);
    worst = std::max(worst, norm > 0.0 ? dev / norm : dev);
  }
  return worst;
}

} // namespace faceplan
