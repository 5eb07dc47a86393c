// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CHOLMOD's supernodal symbolic analysis of a stiffness matrix in a given fill-reducing order,
// made faster than cholmod_analyze_p without changing its result. For .cpp files only (CHOLMOD is
// a private dependency; see CholmodViews.h).
//
// cholmod_analyze_p with CHOLMOD_GIVEN transposes the matrix through the permutation twice (for
// the column counts, then for the supernodal pattern) and works on every DOF, on the ordering
// thread, the precompute's longest CPU path on large meshes. Here:
//  - when the matrix is node-blocked (3 DOFs per node with full 3x3 blocks, as every stiffness
//    matrix from the node graph is) and the order keeps each node's DOFs together, the elimination
//    tree and column counts come from the node graph (9x fewer entries) and are expanded exactly:
//    DOF 3r+d has parent 3r+d+1 (d < 2) or 3 parent(r) (d = 2) and column count 3 count(r) - d,
//    since the factor's pattern is the node factor's pattern with full blocks;
//  - the DOF-level postorder, the permuted pattern and the supernodal pattern are then made as
//    CHOLMOD makes them (cholmod_postorder with the column counts as weights,
//    cholmod_super_symbolic), from a copy of the pattern permuted here in parallel;
//  - otherwise CHOLMOD analyses the pattern permuted here with its natural order.
// Either way the factor equals cholmod_analyze_p's array for array (TestCholmodAnalysis), and
// common.lnz / common.fl are set as CHOLMOD sets them.
#include "Element/StiffnessAssembly.h"
#include "SparseSolver/CholmodFactor.h"

#include <cholmod.h>
#include <vector>

namespace faceplan {

// Sets common's relaxed-supernode amalgamation (nrelax, zrelax) for `relaxation`.
void ApplySupernodeRelaxation(cholmod_common& common, SupernodeRelaxation relaxation);

// `upper`: a symmetric matrix's upper triangle; `perm`: position -> DOF. The factor's Perm is in
// `upper`'s numbering and its ordering CHOLMOD_GIVEN. `nodeBlocked` (optional) tells which path
// ran. Null when CHOLMOD fails (common.status says why).
cholmod_factor* AnalyzeInGivenOrder(const SparseMatrix& upper, const std::vector<int>& perm,
                                    cholmod_common& common, bool* nodeBlocked = nullptr);

} // namespace faceplan
