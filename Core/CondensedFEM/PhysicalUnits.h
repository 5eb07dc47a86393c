// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Converts SI material values into a mesh's length unit. Core solves in whatever consistent units
// it is given; a mesh in millimetres with forces in newtons needs E in N/mm^2 and density in
// kg/mm^3. Gravity stays in m/s^2: kg/mm^3 * m/s^2 = N/mm^3, a body force consistent with N and mm.
#include "Common/Status.h"
#include "Mesh/TetMesh.h"

namespace faceplan {

// `si`: Young's modulus in Pa, density in kg/m^3 (Poisson ratios are unitless). `metresPerUnit`:
// the mesh's length unit in metres (0.001 for millimetres); must be positive and finite.
Status MaterialsInMeshUnits(const Materials& si, double metresPerUnit, Materials& inMeshUnits);

} // namespace faceplan
