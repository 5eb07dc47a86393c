// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The probe of a backend's response operator (which may hold the response in lower precision, or
// on the GPU) against the double response on the host: two random ROI vectors through both.
#include "Backend/ComputeBackend.h"

#include <Eigen/Core>
#include <string>

namespace faceplan {

// The response read by each probe in full up to this size; beyond it, a sample of row blocks.
constexpr double kProbeFullBytes = 512.0e6;

// Relative deviation ||op(v) - response v|| / ||response v|| over the compared rows, the worse of
// two random v: all rows while the response holds at most fullBytes, else every k-th block of
// 4096 rows and the last one, about fullBytes per probe (rowFraction: the share compared).
// Infinity, with `error`, when the operator fails or returns the wrong size.
double ProbeResponseOperator(const Eigen::MatrixXd& response, ResponseOperator& op,
                             double fullBytes, double& rowFraction, std::string& error);

} // namespace faceplan
