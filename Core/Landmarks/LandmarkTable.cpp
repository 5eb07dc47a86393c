// SPDX-License-Identifier: BSD-3-Clause
#include "Landmarks/LandmarkTable.h"

#include <cmath>

namespace faceplan {
namespace landmarks {

Status LandmarkRows(const Placement& placement,
                    const std::array<Eigen::Vector3d, kLandmarkCount>& displacement,
                    const Frame& frame, Operation operation, double still,
                    std::vector<LandmarkRow>& rows) {
  rows.assign(kLandmarkCount, LandmarkRow());
  for (int i = 0; i < kLandmarkCount; ++i) {
    const Landmark l = static_cast<Landmark>(i);
    if (placement.found[i] && !displacement[i].allFinite())
      return Status::Error("the displacement at " + LandmarkName(l) + " is not finite");
    LandmarkRow& r = rows[i];
    r.landmark = l;
    r.found = placement.found[i];
    r.note = placement.note[i];
    r.paired = PairedBone(l);
    if (!r.found) {
      r.check = IsSkinLandmark(l) ? "not found" : "";
      continue;
    }
    r.pre = placement.position[i];
    r.post = r.pre + displacement[i];
    r.horizontal = frame.anterior.dot(displacement[i]);
    r.vertical = frame.superior.dot(displacement[i]);
  }
  for (LandmarkRow& r : rows) {
    if (!IsSkinLandmark(r.landmark) || !r.found)
      continue;
    const LandmarkRow& bone = rows[static_cast<int>(r.paired)];
    r.pairedFound = bone.found;
    if (!bone.found) {
      r.check = "paired bone not found";
      continue;
    }
    r.boneHorizontal = bone.horizontal;
    r.boneVertical = bone.vertical;
    const Movement movement = ClassifyMovement(bone.horizontal, bone.vertical);
    r.band = FindBand(operation, movement, r.landmark);
    // The band's component; without a band, the movement's own (vertical for an impaction).
    const bool vertical = r.band
                              ? r.band->component == Component::Vertical
                              : (movement == Movement::Impaction || movement == Movement::Descent);
    const double hard = vertical ? bone.vertical : bone.horizontal;
    const double soft = vertical ? r.vertical : r.horizontal;
    if (!(std::abs(hard) > still)) {
      r.check = "paired bone does not move";
      continue;
    }
    r.ratioDefined = true;
    r.ratio = soft / hard;
    if (!r.band)
      r.check = "no band";
    else
      r.check = (r.ratio >= r.band->low && r.ratio <= r.band->high) ? "in" : "out";
  }
  return Status::Ok();
}

} // namespace landmarks
} // namespace faceplan
