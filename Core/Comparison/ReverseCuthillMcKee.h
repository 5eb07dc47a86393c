// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Reverse Cuthill-McKee ordering of an undirected graph (bandwidth reduction, the reordering stage
// of the paper's traditional band-Cholesky route). Each connected component starts from a
// pseudo-peripheral node (George-Liu); neighbours are visited by increasing degree.
#include <vector>

namespace faceplan {

// adjacency: CSR (start has n + 1 entries); self loops are ignored.
// Returns order[k] = the vertex placed at position k.
std::vector<int> ReverseCuthillMcKee(const std::vector<int>& start,
                                     const std::vector<int>& adjacent);

// Largest |position(u) - position(v)| over the graph's edges for a given order.
int GraphBandwidth(const std::vector<int>& start, const std::vector<int>& adjacent,
                   const std::vector<int>& order);

} // namespace faceplan
