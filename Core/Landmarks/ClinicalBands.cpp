// SPDX-License-Identifier: BSD-3-Clause
#include "Landmarks/ClinicalBands.h"

#include <cmath>

namespace faceplan {
namespace landmarks {

const std::vector<ClinicalBand>& ClinicalBands() {
  using L = Landmark;
  const Movement adv = Movement::Advancement;
  const Component h = Component::Horizontal;
  static const std::vector<ClinicalBand> bands = {
      {Operation::BSSO, adv, L::SoftTissuePogonion, h, 0.8, 1.2,
       "Mobarak et al. 2001 (about 1:1); San Miguel Moragas et al., systematic review: 90-100 %"},
      {Operation::BSSO, adv, L::SoftTissueB, h, 0.8, 1.2,
       "San Miguel Moragas et al., systematic review: 100 % (6 studies); Mobarak et al. 2001: 1:1"},
      {Operation::BSSO, adv, L::LabraleInferius, h, 0.4, 0.85,
       "study means 0.43-0.76 (Eur J Orthod 2017: 0.76, n = 109; Kim et al. 2018: 0.66)"},
      {Operation::Genioplasty, adv, L::SoftTissuePogonion, h, 0.7, 1.1,
       "systematic review 2021: 0.77-0.91; Shaughnessy et al. 2006: 0.9"},
      {Operation::LeFortI, adv, L::Subnasale, h, 0.4, 1.0,
       "San Miguel Moragas et al., systematic review: 60-90 % (5 studies)"},
      {Operation::LeFortI, adv, L::Pronasale, h, 0.1, 0.45,
       "Khamashta-Ledezma & Naini 2014: 0.24-0.35"},
      {Operation::LeFortI, adv, L::LabraleSuperius, h, 0.3, 1.1,
       "Khamashta-Ledezma & Naini 2014: 0.36-1.43; San Miguel Moragas et al.: 60-100 %"},
  };
  return bands;
}

Movement ClassifyMovement(double horizontal, double vertical) {
  if (std::abs(horizontal) >= std::abs(vertical))
    return horizontal >= 0.0 ? Movement::Advancement : Movement::Setback;
  return vertical >= 0.0 ? Movement::Impaction : Movement::Descent;
}

std::string MovementName(Movement movement) {
  switch (movement) {
  case Movement::Advancement:
    return "advancement";
  case Movement::Setback:
    return "setback";
  case Movement::Impaction:
    return "impaction";
  case Movement::Descent:
    return "descent";
  }
  return "";
}

const ClinicalBand* FindBand(Operation operation, Movement movement, Landmark landmark) {
  for (const ClinicalBand& b : ClinicalBands())
    if (b.operation == operation && b.movement == movement && b.landmark == landmark)
      return &b;
  return nullptr;
}

} // namespace landmarks
} // namespace faceplan
