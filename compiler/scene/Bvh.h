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

// Members whose spheres' centres fill a regular axis-aligned lattice, one member a cell: member k's centre is
// origin + (i·spacing₀, j·spacing₁, l·spacing₂) for the one cell (i, j, l) ∈ [0, n₀)×[0, n₁)×[0, n₂) with
// k = base + i·stride₀ + j·stride₁ + l·stride₂. Found, the scene function needs no tables to find the members
// near a point (the hand-written shader's "visit only the cells that can hold the nearest", Quilez's domain
// repetition with neighbours): a member whose sphere is no nearer than a distance already found cannot
// lower the minimum (Hart 1996 §4), and the cells whose centres lie within that distance plus the radius of
// the point, per axis, are an index box.
struct InstanceLattice {
    std::array<double, 3> origin{0, 0, 0};   // world centre of cell (0, 0, 0)
    std::array<double, 3> spacing{1, 1, 1};  // world units (> 0; 1 on an axis of one cell)
    std::array<int, 3> n{0, 0, 0};           // cells per axis; all 0: no lattice
    std::array<long long, 3> stride{0, 0, 0};
    long long base = 0;
    long long members = 0;  // N: cells whose k lies outside [0, N) are empty (a partly filled last layer)
    // Where some cell is empty: the axis along which the cell one step back (index − 1) of every empty cell is
    // filled (the nearest cell's stand-in); -1 when every cell is filled.
    int back_axis = -1;
    double radius = 0;     // the largest sphere's radius (world units)
    double deviation = 0;  // the largest distance of a centre's coordinate from its cell's (world units)
    bool found() const { return n[0] > 0; }
};

// The lattice of `members` (n ≥ 2), or none (n all 0) when their centres are not one (each coordinate within
// 10⁻³ of the spacing, or 10⁻⁶ of the extent, of its cell's: `deviation`),
// a cell holds two members, member indices are not affine in the cells, more than half the cells are empty,
// or an empty cell's k falls in [0, N) or has no filled cell one step back along one axis.
InstanceLattice find_instance_lattice(const std::vector<BoundingSphere>& members);

}  // namespace iqc
