// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LipSeal: the tissue's facing surfaces (the lips across a closed oral fissure) tied to each other.
//
// A tetrahedral tissue model keeps the two lips as separate surfaces a little apart, so nothing
// but the commissures passes force between them. Closed lips at rest hold each other: the upper
// lip, carried by its own jaw, restrains the lower one. AddLipSeal ties every boundary face to the
// nearest boundary node facing it across at most `gap`: each tie is one bridging tetrahedron (the
// face and that node) whose material is `stiffnessFactor` times as stiff as the tissue behind the
// face, a penalty weld that both the linear and the large-deformation solvers take as ordinary
// cells; the bridges are flagged small-strain (Materials::smallStrain), so the large-deformation
// model keeps them linear elastic and their tangent constant. No node is added or moved, so results
// map to the input's nodes one to one; the input's cells keep their numbers and the bridges follow
// them.
#include "Common/Status.h"
#include "Mesh/TetMesh.h"

namespace faceplan {

struct LipSealOptions {
  double gap = 0.0; // largest face-to-node distance tied, in mesh units; 0 ties nothing
  // How much stiffer a bridge is than the tissue it joins: large enough that the tied surfaces
  // move together (the weld's limit), small enough to keep the system well conditioned.
  double stiffnessFactor = 1000.0;
  // Facing: the node lies within this angle's cosine of the face's outward normal (seen from the
  // face's centroid), and its own outward normal points back against the face's.
  double facingCosine = 0.7;
  double opposedCosine = 0.5;
  // Bridges below this mean-ratio quality (1 = regular) are left out: a near-flat bridge is where
  // the surfaces already touch and would only make a sliver.
  double minimumQuality = 0.1;
};

struct LipSealInfo {
  long long bridges = 0;   // tetrahedra added
  long long tiedNodes = 0; // distinct nodes of the bridges (the tied surfaces' nodes)
};

// `sealed` is `mesh` with the bridges appended; `sealedMaterials` has one entry per cell of
// `sealed` (the tissue's for the input cells; density zero for the bridges, which carry no weight).
// An error for a negative or non-finite gap, or a factor that is not positive and finite.
Status AddLipSeal(const TetMesh& mesh, const Materials& materials, const LipSealOptions& options,
                  TetMesh& sealed, Materials& sealedMaterials, LipSealInfo& info);

} // namespace faceplan
