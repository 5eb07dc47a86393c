// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Osteotomy operation presets: the cut planes of a standard operation placed from the bone's
// geometry, and the standard surgical approach marked on the split bone (Released: the degloved
// bone, whose soft tissue the surgeon detached; Sliding: the teeth, on which the lips slide).
//
// The bone is read in its anatomical frame: `anterior` points out of the face, `superior` up. The
// rules use landmarks of the bone's midline (the band within 5 % of the bone's width of its
// lateral centre) and proportions of the jaw, not lengths, so they hold for any size and unit:
//  - maxilla: the alveolar crest (its lowest midline point, prosthion) and the anterior nasal
//    spine (the highest midline point of its front quarter);
//  - mandible: the alveolar crest (its highest midline point, infradentale), menton (its lowest
//    midline point), pogonion (its most anterior midline point), the symphysis height H (crest to
//    menton) and the ramus's anterior border (the most anterior bone 0.2 H to 0.4 H above the
//    crest).
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"
#include "Osteotomy/CutPlanes.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace faceplan {

enum class Operation : int { Custom = 0, LeFortI = 1, BSSO = 2, Genioplasty = 3 };

// "Custom", "LeFortI", "BSSO", "Genioplasty"; "" for a value out of range.
std::string OperationName(Operation operation);

struct AnatomicalAxes {
  Eigen::Vector3d anterior = -Eigen::Vector3d::UnitX(); // out of the face
  Eigen::Vector3d superior = Eigen::Vector3d::UnitZ();  // up
};

// Checks that both axes are finite and non-zero and not parallel (within 10 degrees of it), makes
// them unit length and `superior` orthogonal to `anterior`.
Status NormalizeAxes(AnatomicalAxes& axes);

// What a preset found on the bone (frame coordinates: a = anterior, s = superior), kept for the
// approach's marks.
struct OperationGeometry {
  Operation operation = Operation::Custom;
  AnatomicalAxes axes;
  double crestS = 0.0;       // the alveolar crest's height
  double jawHeight = 0.0;    // maxilla: crest to ANS; mandible: crest to menton (H)
  double frontA = 0.0;       // the bone's most anterior coordinate
  double backA = 0.0;        // the bone's most posterior coordinate
  double cutS = 0.0;         // LeFortI, Genioplasty: the horizontal cut's height
  double cutA = 0.0;         // BSSO: the coronal cut's position; Genioplasty: the chin's back
  double ramusBorderA = 0.0; // mandible: the ramus's anterior border
  std::vector<CutPlane> planes;
};

// The cut planes of `operation` on the bone `points` (the segment is on the positive side of
// every plane, InsideOut off):
//  - LeFortI: one horizontal plane 0.1 of the crest-ANS height above ANS (through the piriform
//    rim, above the nasal floor); the segment is the maxilla below it.
//  - BSSO: one coronal plane 0.25 H in front of the ramus's anterior border (the buccal cut at the
//    second molar of the sagittal split); the segment is the body in front of it.
//  - Genioplasty: a horizontal plane 0.35 H above menton (below the mental foramina and the canine
//    roots) and a coronal plane 0.5 H behind pogonion; the segment is the chin below and in front.
// Fails for Custom, too few points, a non-finite point, axes that NormalizeAxes rejects, or a bone
// whose midline is empty or flat.
Status PlaceOperationCut(Operation operation, const RowVectors3d& points,
                         const AnatomicalAxes& axes, OperationGeometry& geometry);

// The standard approach on the split bone (`points` before the move, `segment` 1 on the moving
// side), one value per point:
//  - released: LeFortI, the maxilla from the vestibular incision (the top of the teeth band) up to
//    the infraorbital foramina (0.3 of the crest-to-cut height above the cut), both sides of the
//    cut (the nasal base is freed from the segment as well; the nasal dorsum stays attached); BSSO,
//    the bone within 0.3 H either side of the cut, both sides (the ramus and body exposed along the
//    external oblique ridge); Genioplasty, the fixed anterior mandible above the cut, up to the
//    canine roots (0.25 H below the crest) and back to 0.2 H behind the chin's back plane.
//  - sliding: the teeth, where the lips and cheeks rest on the jaw: maxilla, within 0.4 of the
//    crest-ANS height above the crest and in the front half; mandible, within 0.25 H below the
//    crest and in front of the BSSO cut's position.
void MarkOperationApproach(const OperationGeometry& geometry, const RowVectors3d& points,
                           const std::vector<std::uint8_t>& segment,
                           std::vector<std::uint8_t>& released, std::vector<std::uint8_t>& sliding);

} // namespace faceplan
