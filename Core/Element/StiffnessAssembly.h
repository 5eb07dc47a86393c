// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Sparse symmetric assembly: the pattern and a gather map are built once per mesh and DOF
// numbering; assembling new element values into it is then a pure gather (no atomics, no search),
// which both the CPU and the CUDA backend run.
#include "Common/GroupByKey.h"
#include "Common/Status.h"
#include "Mesh/TetMesh.h"

#include <Eigen/SparseCore>
#include <vector>

namespace faceplan {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct AssemblyPattern {
  // Upper triangle of the global stiffness in the numbering dofOfNode gave (3 DOFs per node),
  // column-compressed, rows sorted; values are zero until Assemble fills them.
  SparseMatrix upper;
  // For nonzero k of `upper`, its contributions are packedIndex[gatherStart[k] .. gatherStart[k+1])
  // where each packed index is cell * 78 + (position in the packed upper triangle of Ke).
  std::vector<int> gatherStart;
  std::vector<int> packedIndex; // int: up to 27M tetrahedra (checked when built)
};

// Each DOF node's neighbours of lower or equal index (itself included), sorted: the node graph
// from which both the assembly pattern and the fill-reducing ordering start (the Precompute
// orders the free nodes from it while the pattern's gather map is still being built).
using NodeNeighbours = std::vector<std::vector<int>>;
NodeNeighbours LowerNodeNeighbours(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                   const std::vector<int>& dofNode, int numDofNodes);

// The cells' corners (cell * nodesPerCell + place) grouped by DOF node, each group in increasing
// order: the node-to-cell index both the node graph and the gather map walk.
Groups CornersByNode(const int* cells, Eigen::Index numCells, int nodesPerCell,
                     const std::vector<int>& dofNode, int numDofNodes);
// LowerNodeNeighbours from that index, already built.
NodeNeighbours LowerNodeNeighbours(const int* cells, int nodesPerCell,
                                   const std::vector<int>& dofNode, const Groups& cornersOf);

// The upper-triangle structure (3 DOFs per node, rows sorted) of the first `nodes` DOF nodes of
// `lower`; values are zero when zeroValues, else left uninitialised (a structure to analyse).
// Fails when the matrix would overflow 32-bit indices.
Status UpperPatternOfNodes(const NodeNeighbours& lower, int nodes, bool zeroValues,
                           SparseMatrix& upper);

// The pattern of cells with any node count: `cells` holds numCells x nodesPerCell node ids row by
// row; each packed element matrix is the row-by-row upper triangle of its (3 k) x (3 k) matrix,
// (3 k)(3 k + 1) / 2 entries. dofNode[i] is the new index of node i (its DOFs are
// 3*dofNode[i] + c); -1 drops the node. Pass an identity to keep the mesh's own numbering.
// Fails when the packed indices or the matrix would overflow 32-bit ints.
Status BuildCellAssemblyPattern(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                const std::vector<int>& dofNode, int numDofNodes,
                                AssemblyPattern& pattern);
// The same from the cells' CornersByNode and LowerNodeNeighbours, already built.
Status BuildCellAssemblyPattern(const int* cells, Eigen::Index numCells, int nodesPerCell,
                                const std::vector<int>& dofNode, const Groups& cornersOf,
                                const NodeNeighbours& lower, AssemblyPattern& pattern);

// The same for the 4-node cells of `mesh`.
Status BuildAssemblyPattern(const TetMesh& mesh, const std::vector<int>& dofNode, int numDofNodes,
                            AssemblyPattern& pattern);

// upper.valuePtr()[k] = sum of packed[packedIndex[...]] over its gather range.
void AssembleFromPacked(const double* packed, AssemblyPattern& pattern);

// Per packed cell entry (packedSize of them), the nonzero of pattern.upper it is summed into: the
// gather map turned around. Empty when an entry has no place in the pattern (a dropped node's).
std::vector<int> PackedEntries(const AssemblyPattern& pattern, size_t packedSize);

// pattern.upper's values for cells of which only some left their rest values: `restValues` (the
// assembly of `restPacked`, one value per entry of pattern.upper) plus, for each cell c without
// atRest[c], its entries in `packed` minus those in `restPacked` (entries: PackedEntries); a cell
// with atRest[c] must hold its rest values in `packed`. Entries that only cells at rest reach keep
// their rest values exactly; the others equal AssembleFromPacked's to round-off. Each thread owns a
// range of entries and adds in cell order: the same sums on any number of threads. A changed cell
// costs about twice its share of the whole assembly, so this pays where few cells changed.
void AssembleChangedCells(const double* restValues, const std::vector<double>& restPacked,
                          const double* packed, const std::vector<char>& atRest,
                          const std::vector<int>& entries, AssemblyPattern& pattern);

} // namespace faceplan
