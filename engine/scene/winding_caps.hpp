// The caps that let a tree answer the generalized winding number exactly and fast: for each subtree
// of a BVH over triangles, the edges of its boundary (where its triangles do not close up), each once
// per net use, oriented as its triangles run along it.
//
// Why that answers exactly: the subtree's triangles and a cap that closes their boundary (a fan of
// triangles from each boundary edge to one point c) form a closed surface: its boundary cancels edge
// by edge. The winding number of a closed surface is 0 wherever it lies outside a convex set holding
// the surface, here the subtree's box (the triangles are in it, and so is every fan triangle, from
// two of their vertices to c, the box's centre). So at a point p outside the box, the subtree's
// winding number is minus the cap's: w = sum over boundary edges (a -> b) of
// solid_angle(a, b, c) / 4 pi (the fan triangle (b, a, c) turned over). This is Jacobson, Kavan and
// Sorkine-Hornung's hierarchical evaluation ("Robust Inside-Outside Segmentation using Generalized
// Winding Numbers", SIGGRAPH 2013, 3.2), exact up to rounding: no far-field approximation. A closed
// mesh's subtrees have boundaries of a few edges per triangle they hold to the power 1/2, and the
// whole mesh's none, so a walk evaluates the triangles of the leaves whose boxes hold p, and for every
// other subtree at most its boundary.
#pragma once

#include "engine/scene/bvh.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace vkray {

// A boundary edge: two vertex ids, in the order the subtree's triangles run along it (a vertex id is
// whatever the caller numbers vertices by: two triangles close up along an edge only where they name
// the same ids).
struct CapEdge {
  uint32_t from = 0, to = 0;
  bool operator==(const CapEdge&) const = default;
};

struct WindingCaps {
  static constexpr uint32_t no_cap = UINT32_MAX;
  // By node, for each child: its cap's first edge in `edges` and count, or no_cap where the walk goes
  // into the child instead (a leaf: its triangles are as few as its boundary's edges; a subtree whose
  // boundary has more edges than it has triangles; one holding what a cap cannot stand for).
  std::vector<std::array<uint32_t, 2>> first;
  std::vector<std::array<uint32_t, 2>> count;
  std::vector<CapEdge> edges;
  // The whole tree's boundary: an empty one is a closed surface, 0 wherever the root's box is not.
  std::vector<CapEdge> root;
};

// The caps of `tree`'s subtrees. `corners(entry)` gives the vertex ids of primitive `entry` (an index
// into the builder's input, as Bvh::primitive_order holds them) in its winding order, or none for a
// primitive that is no triangle; `capped(entry)` whether a cap may stand for it outside its subtree's
// box (a triangle may; a sphere contributes nothing there; an instance of a mesh that is not closed
// may not). A subtree holding an entry that may not is walked.
// `root`: the tree's root node among `tree.nodes` (which may hold other trees: only the nodes below
// `root` are capped; the others' entries stay no_cap).
WindingCaps build_winding_caps(const Bvh& tree, const std::function<std::optional<std::array<uint32_t, 3>>(uint32_t)>& corners,
                               const std::function<bool(uint32_t)>& capped, uint32_t root = 0);

// The boundary edges of a set of triangles (each its three vertex ids in winding order): those whose
// uses do not cancel, |net| times each. Empty for a closed surface.
std::vector<CapEdge> boundary_edges(const std::vector<std::array<uint32_t, 3>>& triangles);

}  // namespace vkray
