// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Fill-reducing ordering of a stiffness matrix with a chosen set of nodes placed last.
//
// Why last: the right-hand sides of the dense response (and of a load-free edit) are the columns
// of K_FR, which are non-zero only on the free nodes that share a cell with an ROI node. With those
// nodes at the end of the elimination order, L^-1 b is non-zero only in the trailing dense block,
// so the forward substitution shrinks to a small dense triangular solve and only the backward
// substitution runs over the whole factor (half the flops of a full solve).
//
// The rest is ordered by METIS nested dissection of the node graph (each node's DOFs stay
// together): with the same trailing nodes, its factor on the face-like shells is smaller than
// constrained AMD's on the DOF graph, the more so the larger the mesh, and AMD on the node graph
// gives a much costlier factorization; the node graph also has 9x fewer edges than the DOF graph
// to partition. Falls back to AMD if METIS is unavailable.
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"

#include <mutex>
#include <vector>

namespace faceplan {

// Held around every METIS call where MetisRandomIsPerThread() is false. METIS keeps its random
// generator in global state: two orderings at once (two threads, or two precomputes) would draw
// from it in turn, so the same graph would get a different ordering from run to run, and
// round-off-different results. Where each thread has its own generator (MetisRandom.h), METIS
// calls run at once: the top levels of the nested dissection are split over threads.
std::mutex& MetisMutex();

struct FillReducingOrdering {
  std::vector<int> permutation; // position -> DOF (CHOLMOD's Perm convention)
  int trailingDofs = 0;         // the last trailingDofs positions hold the requested nodes' DOFs
  const char* method = "";      // "METIS" or "AMD"
  int leaves = 1; // graphs ordered whole: > 1 when the dissection's top was split here
};

// `upper`: the free block's upper triangle, `dofsPerNode` consecutive DOFs per node;
// `trailingNode[node]` marks the nodes to order last (may be empty: none). `leaves`: the parts the
// nested dissection's top is split into, each ordered on its own thread (1, 2, 4, ... 64); 0 lets
// the ordering choose (no split below 50,000 nodes, else as many as there are cores, up to 8).
Status OrderNodesWithTrailing(const SparseMatrix& upper, int dofsPerNode,
                              const std::vector<char>& trailingNode, FillReducingOrdering& ordering,
                              int leaves = 0);

// The same from the node graph itself: `lower` as LowerNodeNeighbours gives it
// (Element/StiffnessAssembly.h), of which the first `nodes` are ordered. Gives the ordering
// OrderNodesWithTrailing gives for the upper triangle UpperPatternOfNodes builds from `lower`.
Status OrderNodeGraphWithTrailing(const NodeNeighbours& lower, int nodes, int dofsPerNode,
                                  const std::vector<char>& trailingNode,
                                  FillReducingOrdering& ordering, int leaves = 0);

// The first `nodes` nodes of `lower` that share a cell with a later node: with the free nodes
// first and the ROI nodes after them, the rows of K_FR by node (NodesCoupledTo of K_FR).
std::vector<char> NodesCoupledToLaterNodes(const NodeNeighbours& lower, int nodes);

// Nodes (of `dofsPerNode` DOFs) with a non-zero in some column of `coupling` (free x ROI), as a
// per-node mark for OrderNodesWithTrailing.
std::vector<char> NodesCoupledTo(const SparseMatrix& coupling, int freeNodes, int dofsPerNode);

} // namespace faceplan
