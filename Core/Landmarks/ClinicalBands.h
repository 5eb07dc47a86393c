// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Published soft-to-hard tissue movement ratios: how far a soft-tissue landmark moves per unit of
// its paired bony landmark's movement, long-term, for a standard operation and direction of
// movement. Each band names its source; docs/CLINICAL.md gives the full references.
#include "Landmarks/FacialLandmarks.h"
#include "Osteotomy/OperationPresets.h"

#include <string>
#include <vector>

namespace faceplan {
namespace landmarks {

enum class Movement { Advancement, Setback, Impaction, Descent };
enum class Component { Horizontal, Vertical };

struct ClinicalBand {
  Operation operation;
  Movement movement;
  Landmark landmark;
  Component component; // which component of both movements the ratio divides
  double low, high;
  std::string source;
};

const std::vector<ClinicalBand>& ClinicalBands();

// The bony movement's kind from its horizontal and vertical components (in the frame): the larger
// one decides; forward is an advancement, backward a setback, up an impaction, down a descent.
Movement ClassifyMovement(double horizontal, double vertical);
std::string MovementName(Movement movement);

// The band for this operation, movement and landmark; nullptr when the literature gives none.
const ClinicalBand* FindBand(Operation operation, Movement movement, Landmark landmark);

} // namespace landmarks
} // namespace faceplan
