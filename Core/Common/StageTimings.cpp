// SPDX-License-Identifier: BSD-3-Clause
#include "Common/StageTimings.h"

namespace faceplan {

const char* StageName(Stage stage) {
  switch (stage) {
  case Stage::Reordering:
    return "Reordering";
  case Stage::ElementStiffness:
    return "ElementStiffness";
  case Stage::Assembly:
    return "Assembly";
  case Stage::Separation:
    return "Separation";
  case Stage::Condensation:
    return "Condensation";
  case Stage::Factorization:
    return "Factorization";
  case Stage::BoundaryCondition:
    return "BoundaryCondition";
  case Stage::Load:
    return "Load";
  case Stage::Solve:
    return "Solve";
  case Stage::Total:
    return "Total";
  }
  return "?";
}

} // namespace faceplan
