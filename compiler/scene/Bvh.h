// A bounding-volume hierarchy over the instances of a group (scene/SceneLower.cpp traverses it in
// iqc_scene), built at compile time from each instance's `bound` sphere carried into world space. Its nodes
// are axis-aligned boxes: around clusters of a lattice they barely overlap (spheres around the same
// clusters overlap, and a point inside several of them descends into each), and the distance to a box is a
// few operations more than to a sphere.
//
// The tree has the same depth everywhere, so that each level is one counted loop in the shader: level 0 is
// a list of at most `branching` nodes, each node of level l < depth - 1 has its children in level l + 1 at
// [first, first + count), and a node of the last level has members [first, first + count) of the group in
// the order `order` gives. Every node has at most `branching` children, and its box contains the boxes of
// the nodes below it and the spheres of its members.
//
// Traversal (the union of the members' distances, sphere tracing's scene distance): a subtree whose box is
// no nearer than the nearest distance found so far is skipped. For a member whose distance is at least the
// distance to its own sphere (an exact or conservative distance of a shape inside its `bound`), skipping
// never changes the minimum (Rubin & Whitted 1980, bounding volumes; Hart 1996 §4 for sphere tracing's
// union of bounded objects).
#pragma once

#include <array>
#include <vector>

namespace iqc {

struct BoundingSphere {
    std::array<double, 3> center{0, 0, 0};  // world units
    double radius = 0;
};

struct BoundingBox {
    std::array<double, 3> center{0, 0, 0}, half{0, 0, 0};  // world units; half: the half-extents
};

struct BoundsTreeLevel {
    std::vector<BoundingBox> nodes;
    std::vector<int> first, count;  // per node: its children (next level's nodes, or members on the last level)
};

struct BoundsTree {
    std::vector<BoundsTreeLevel> levels;  // top first; empty when there is nothing to build
    std::vector<int> order;               // member positions (indices into the input) in leaf order
};

// The world-space sphere containing {p : ‖L p + o‖ ≤ R}, the object-space ball of radius R under the
// world → object map q = L p + o (L row-major 3×3, invertible): centre -L⁻¹o, radius R / σ_min(L), with
// σ_min from the eigenvalues of LᵀL (closed form for symmetric 3×3 matrices, Smith 1961), rounded up.
BoundingSphere world_sphere(const std::vector<double>& L, const std::vector<double>& o, double R);

// The box containing every box of `b`, rounded up so that float32 rounding of its centre and half-extents
// keeps it conservative.
BoundingBox enclosing_box(const std::vector<BoundingBox>& b);
// The box of a sphere.
BoundingBox box_of(const BoundingSphere& s);

// Builds the hierarchy over `members` (world spheres, n ≥ 1) with at most `branching` (≥ 2) children per
// node, splitting each set at the median of its centres along their widest axis.
BoundsTree build_bounds_tree(const std::vector<BoundingSphere>& members, int branching);

}  // namespace iqc
