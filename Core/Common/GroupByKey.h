// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Items 0 .. count-1 grouped by an integer key, by a counting sort (two passes, no comparison):
// group k holds the items with key k, in increasing order, at items[start[k] .. start[k+1]).
// Items with a negative key are left out. Indices are int: callers check their counts fit.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace faceplan {

struct Groups {
  std::vector<int> start; // keys + 1 entries
  std::vector<int> items;
};

template <class KeyOf> Groups GroupByKey(std::int64_t count, int keys, KeyOf&& keyOf) {
  Groups groups;
  groups.start.assign(static_cast<size_t>(keys) + 1, 0);
  for (std::int64_t i = 0; i < count; ++i)
    if (const int key = keyOf(i); key >= 0)
      ++groups.start[key + 1];
  for (int k = 0; k < keys; ++k)
    groups.start[k + 1] += groups.start[k];
  groups.items.resize(groups.start[keys]);
  std::vector<int> fill(groups.start.begin(), groups.start.end() - 1);
  for (std::int64_t i = 0; i < count; ++i)
    if (const int key = keyOf(i); key >= 0)
      groups.items[fill[key]++] = static_cast<int>(i);
  return groups;
}

} // namespace faceplan
