#pragma once
/// \file Greedy colouring of items that touch nodes (elements for the threaded assembly, chunks of
/// elements for the matrix-free operator): items of one colour share no node, so one thread per
/// item may add into the nodes' rows without locks.
#include <vector>

#include "core/types.hpp"

namespace crackle::fem {

/// Each item, in increasing order, takes the smallest colour that no item sharing a node with it has
/// yet. `for_each_node(item, visit)` calls visit(node) for every node the item touches (repeats
/// allowed, each node is looked at once per item); `for_each_item(node, visit)` calls visit(item) for
/// every item touching the node. Returns the items of each colour, in increasing order.
template <typename NodesOfItem, typename ItemsOfNode>
std::vector<std::vector<Index>> greedy_colouring(Index n_items, Index n_nodes, NodesOfItem&& for_each_node,
                                                 ItemsOfNode&& for_each_item) {
  std::vector<int> colour(static_cast<std::size_t>(n_items), -1);
  std::vector<Index> last(static_cast<std::size_t>(n_nodes), -1);  // the last item that looked at the node
  std::vector<Index> stamp;  // stamp[c] == item: colour c is taken by a neighbour of the item
  std::vector<std::vector<Index>> classes;
  for (Index item = 0; item < n_items; ++item) {
    for_each_node(item, [&](Index node) {
      if (last[node] == item) return;
      last[node] = item;
      for_each_item(node, [&](Index other) {
        const int used = colour[other];
        if (used >= 0) stamp[used] = item;
      });
    });
    int chosen = 0;
    while (chosen < static_cast<int>(stamp.size()) && stamp[chosen] == item) ++chosen;
    if (chosen == static_cast<int>(stamp.size())) {
      stamp.push_back(-1);
      classes.emplace_back();
    }
    colour[item] = chosen;
    classes[chosen].push_back(item);
  }
  return classes;
}

}  // namespace crackle::fem
