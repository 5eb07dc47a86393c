// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Whether two precompute requests would produce the same system, compared field by field over the
// whole request (mesh, materials, node sets, every option), so that a cache keyed on it can never
// reuse a factor built for different inputs. Adding a field to any of these structs trips a
// static_assert in RequestIdentity.cpp until the comparison covers it.
#include "CondensedFEM/CondensedFEM.h"

namespace faceplan {

bool SameOptions(const PrecomputeOptions& a, const PrecomputeOptions& b);
// Mesh, materials and node sets (everything but the options).
bool SameInputs(const PrecomputeRequest& a, const PrecomputeRequest& b);
bool SameRequest(const PrecomputeRequest& a, const PrecomputeRequest& b);

} // namespace faceplan
