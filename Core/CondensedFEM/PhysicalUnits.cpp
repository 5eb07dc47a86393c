// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/PhysicalUnits.h"

#include <cmath>
#include <sstream>

namespace faceplan {

Status MaterialsInMeshUnits(const Materials& si, double metresPerUnit, Materials& inMeshUnits) {
  if (!(metresPerUnit > 0.0) || !std::isfinite(metresPerUnit)) {
    std::ostringstream msg;
    msg << "the length unit must be a positive number of metres (got " << metresPerUnit << ")";
    return Status::Error(msg.str());
  }
  const double s = metresPerUnit;
  inMeshUnits = si;
  inMeshUnits.youngsModulus *= s * s; // N/m^2 -> N/unit^2
  inMeshUnits.density *= s * s * s;   // kg/m^3 -> kg/unit^3
  return Status::Ok();
}

} // namespace faceplan
