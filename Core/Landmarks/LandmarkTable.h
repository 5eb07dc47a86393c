// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The landmark table: per landmark its pre- and post-operative position, its movement in the
// reference frame, its paired bony landmark's movement, the soft:hard ratio and the published band.
#include "Landmarks/ClinicalBands.h"
#include "Landmarks/FacialLandmarks.h"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace faceplan {
namespace landmarks {

struct LandmarkRow {
  Landmark landmark = Landmark::Pronasale;
  bool found = false;
  std::string note; // why it was not found
  Eigen::Vector3d pre = Eigen::Vector3d::Zero(), post = Eigen::Vector3d::Zero();
  double horizontal = 0.0, vertical = 0.0; // post - pre: + anterior, + superior
  Landmark paired = Landmark::Pronasale;
  bool pairedFound = false;
  double boneHorizontal = 0.0, boneVertical = 0.0;
  bool ratioDefined = false;
  double ratio = 0.0; // soft / hard along the band's component (without a band: the bone's
                      // main component, vertical for an impaction or descent)
  const ClinicalBand* band = nullptr;
  std::string check; // "in", "out", "no band", "paired bone not found", "paired bone does not
                     // move", "not found"; "" for a bony landmark
};

// `displacement` holds each found landmark's displacement (the field interpolated at it). A ratio
// is defined where the paired bone moves more than `still` along the ratio's component. Fails on a
// non-finite displacement of a found landmark.
Status LandmarkRows(const Placement& placement,
                    const std::array<Eigen::Vector3d, kLandmarkCount>& displacement,
                    const Frame& frame, Operation operation, double still,
                    std::vector<LandmarkRow>& rows);

} // namespace landmarks
} // namespace faceplan
