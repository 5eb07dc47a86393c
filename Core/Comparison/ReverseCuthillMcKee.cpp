// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/ReverseCuthillMcKee.h"
#include "Common/InversePermutation.h"

#include <algorithm>
#include <cstdlib>

namespace faceplan {

namespace {

// Breadth-first level structure from `root` over unvisited-in-component vertices; returns the
// vertices of the last level and the number of levels.
int LevelStructure(int root, const std::vector<int>& start, const std::vector<int>& adjacent,
                   std::vector<int>& level, std::vector<int>& lastLevel) {
  std::vector<int> frontier{root}, touched{root};
  level[root] = 0;
  int depth = 0;
  while (true) {
    std::vector<int> next;
    for (int v : frontier)
      for (int k = start[v]; k < start[v + 1]; ++k) {
        const int w = adjacent[k];
        if (level[w] < 0) {
          level[w] = depth + 1;
          next.push_back(w);
          touched.push_back(w);
        }
      }
    if (next.empty())
      break;
    frontier.swap(next);
    ++depth;
  }
  lastLevel = frontier;
  for (int v : touched)
    level[v] = -1; // leave the scratch array clean
  return depth + 1;
}

} // namespace

std::vector<int> ReverseCuthillMcKee(const std::vector<int>& start,
                                     const std::vector<int>& adjacent) {
  const int n = static_cast<int>(start.size()) - 1;
  std::vector<int> degree(n), order, level(n, -1);
  for (int v = 0; v < n; ++v)
    degree[v] = start[v + 1] - start[v];
  std::vector<char> placed(n, 0);
  order.reserve(n);
  std::vector<int> byDegree(n);
  for (int v = 0; v < n; ++v)
    byDegree[v] = v;
  std::stable_sort(byDegree.begin(), byDegree.end(),
                   [&](int a, int b) { return degree[a] < degree[b]; });
  std::vector<int> neighbours;
  for (int seed : byDegree) {
    if (placed[seed])
      continue;
    // Pseudo-peripheral node: move to a smallest-degree vertex of the last level while the
    // eccentricity grows.
    int root = seed;
    std::vector<int> last;
    int depth = LevelStructure(root, start, adjacent, level, last);
    for (int pass = 0; pass < 8; ++pass) {
      const int candidate = *std::min_element(last.begin(), last.end(),
                                              [&](int a, int b) { return degree[a] < degree[b]; });
      std::vector<int> candidateLast;
      const int candidateDepth = LevelStructure(candidate, start, adjacent, level, candidateLast);
      if (candidateDepth <= depth)
        break;
      root = candidate;
      depth = candidateDepth;
      last.swap(candidateLast);
    }
    // Cuthill-McKee breadth-first numbering.
    size_t head = order.size();
    order.push_back(root);
    placed[root] = 1;
    while (head < order.size()) {
      const int v = order[head++];
      neighbours.clear();
      for (int k = start[v]; k < start[v + 1]; ++k) {
        const int w = adjacent[k];
        if (w != v && !placed[w]) {
          placed[w] = 1;
          neighbours.push_back(w);
        }
      }
      std::sort(neighbours.begin(), neighbours.end(), [&](int a, int b) {
        return degree[a] != degree[b] ? degree[a] < degree[b] : a < b;
      });
      order.insert(order.end(), neighbours.begin(), neighbours.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

int GraphBandwidth(const std::vector<int>& start, const std::vector<int>& adjacent,
                   const std::vector<int>& order) {
  const int n = static_cast<int>(start.size()) - 1;
  const std::vector<int> position = InversePermutation(order.data(), n);
  int band = 0;
  for (int v = 0; v < n; ++v)
    for (int k = start[v]; k < start[v + 1]; ++k)
      band = std::max(band, std::abs(position[v] - position[adjacent[k]]));
  return band;
}

} // namespace faceplan
