#include "engine/scene/winding_caps.hpp"

#include <algorithm>
#include <cstdlib>
#include <unordered_map>
#include <utility>

namespace vkray {
namespace {

// The net uses of each edge of a set of triangles: +1 for each run from the lower id to the higher,
// -1 for each the other way; the edges whose uses cancel are dropped as they reach 0.
using NetEdges = std::unordered_map<uint64_t, int32_t>;

uint64_t edge_key(uint32_t a, uint32_t b) { return uint64_t{std::min(a, b)} << 32 | std::max(a, b); }

void add_triangle(NetEdges& net, const std::array<uint32_t, 3>& corners) {
  for (int k = 0; k < 3; ++k) {
    const uint32_t a = corners[k], b = corners[(k + 1) % 3];
    if (a == b) continue;  // a degenerate corner runs nowhere
    const auto [entry, inserted] = net.try_emplace(edge_key(a, b), 0);
    entry->second += a < b ? 1 : -1;
    if (entry->second == 0) net.erase(entry);
  }
}

// `from` added into `into`, the larger kept: each edge moves O(log n) times over a tree.
void merge_into(NetEdges& into, NetEdges&& from) {
  if (from.size() > into.size()) std::swap(into, from);
  for (const auto& [key, uses] : from) {
    const auto [entry, inserted] = into.try_emplace(key, 0);
    entry->second += uses;
    if (entry->second == 0) into.erase(entry);
  }
}

size_t boundary_size(const NetEdges& net) {
  size_t edges = 0;
  for (const auto& [key, uses] : net) edges += static_cast<size_t>(std::abs(uses));
  return edges;
}

// Each edge with non-zero net uses, |net| times, oriented by the sign, in the order of their keys
// (the same caps every build).
void append_edges(const NetEdges& net, std::vector<CapEdge>& edges) {
  std::vector<std::pair<uint64_t, int32_t>> sorted(net.begin(), net.end());
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [key, uses] : sorted) {
    const auto low = static_cast<uint32_t>(key >> 32), high = static_cast<uint32_t>(key);
    const CapEdge edge = uses > 0 ? CapEdge{low, high} : CapEdge{high, low};
    for (int32_t k = 0; k < std::abs(uses); ++k) edges.push_back(edge);
  }
}

}  // namespace

std::vector<CapEdge> boundary_edges(const std::vector<std::array<uint32_t, 3>>& triangles) {
  NetEdges net;
  for (const auto& corners : triangles) add_triangle(net, corners);
  std::vector<CapEdge> edges;
  append_edges(net, edges);
  return edges;
}

WindingCaps build_winding_caps(const Bvh& tree, const std::function<std::optional<std::array<uint32_t, 3>>(uint32_t)>& corners,
                               const std::function<bool(uint32_t)>& capped, uint32_t root) {
  WindingCaps caps;
  caps.first.assign(tree.nodes.size(), {WindingCaps::no_cap, WindingCaps::no_cap});
  caps.count.assign(tree.nodes.size(), {0, 0});
  if (tree.nodes.empty()) return caps;
  std::vector<uint8_t> reached(tree.nodes.size(), 0);  // the nodes below `root`
  std::vector<uint32_t> pending{root};
  while (!pending.empty()) {
    const uint32_t node = pending.back();
    pending.pop_back();
    reached[node] = 1;
    for (const uint32_t child : tree.nodes[node]) {
      if (!is_leaf(child) && !reached[child]) pending.push_back(child);
    }
  }
  struct Subtree {
    NetEdges net;
    size_t triangles = 0;
    bool cappable = true;
  };
  std::vector<Subtree> below(tree.nodes.size());  // each node's, from its children's, then given up to its parent
  const auto leaf = [&](uint32_t child) {
    Subtree subtree;
    for (uint32_t k = 0; k < leaf_count(child); ++k) {
      const uint32_t entry = tree.primitive_order[leaf_first(child) + k];
      subtree.cappable = subtree.cappable && capped(entry);
      if (const auto triangle = corners(entry)) add_triangle(subtree.net, *triangle), ++subtree.triangles;
    }
    return subtree;
  };
  // Children have larger indices than their parents (depth-first order): a reverse sweep meets every
  // child first. A lone leaf is referenced twice by the root (Bvh::nodes): its triangles once.
  for (size_t node = tree.nodes.size(); node-- > 0;) {
    if (!reached[node]) continue;
    const auto& children = tree.nodes[node];
    Subtree merged;
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children[1] == children[0]) break;
      Subtree child = is_leaf(children[side]) ? leaf(children[side]) : std::move(below[children[side]]);
      // Capped where the cap costs no more edges than the walk triangles, and may stand for it.
      const size_t edges = boundary_size(child.net);
      if (!is_leaf(children[side]) && child.cappable && edges <= child.triangles) {
        caps.first[node][side] = static_cast<uint32_t>(caps.edges.size());
        caps.count[node][side] = static_cast<uint32_t>(edges);
        append_edges(child.net, caps.edges);
      }
      merge_into(merged.net, std::move(child.net));
      merged.triangles += child.triangles;
      merged.cappable = merged.cappable && child.cappable;
    }
    below[node] = std::move(merged);
  }
  append_edges(below[root].net, caps.root);
  return caps;
}

}  // namespace vkray
