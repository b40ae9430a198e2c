// A convex piecewise-linear lower bound of a distance, and the polytope it bounds.
//
// A shape written as the largest of its faces' plane distances — a tetrahedron, max(−p₂, p⋅n₁, p⋅n₂, p⋅n₃) − r,
// or any convex polytope a user writes the same way — has no box by interval arithmetic (ir/Support.h): over
// the half-space x ≥ c, with y and z unbounded, every plane distance p⋅nᵢ is unbounded below, so no side is
// proven free, though their maximum grows with x. What intervals lose is the correlation between the planes;
// here it is kept: structural rules over the IR find d(p) ≥ maxᵢ (aᵢ⋅p + bᵢ) (exact where the distance is
// that maximum), and the polytope P = {p : aᵢ⋅p + bᵢ ≤ level for every i} then holds every point where the
// distance is ≤ level. Its extent along ±e_k is a linear program: by Farkas' lemma it is bounded on that side
// exactly where some convex combination Σ λᵢ aᵢ = c·(±e_k) with c > 0 exists, and then
// Σ λᵢ (aᵢ⋅p + bᵢ) = ±c·p_k + Σ λᵢ bᵢ > level beyond ±p_k = (level − Σ λᵢ bᵢ) / c; the least such plane over the
// basic solutions (at most three λᵢ non-zero) is the side (Schrijver, "Theory of Linear and Integer
// Programming", 1986: Farkas' lemma, basic solutions). A bounded polytope's farthest point from the origin is
// one of its vertices (three planes met), which gives the radius of a ball around it.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "ir/IR.h"
#include "ir/Intervals.h"
#include "ir/Support.h"

namespace iqc::ir {

// One plane of the bound: a ⋅ p + b.
struct AffinePiece {
    std::array<double, 3> a{};
    double b = 0;
};

// Pieces with d(p) ≥ maxᵢ (aᵢ⋅p + bᵢ) for every p, where `g` (a function with its calls inlined and constants
// folded: ir/Support.cpp's flattened copy) returns the scalar distance d and parameter `query` is p ∈ ℝ³; the
// other parameters lie in `params` (one entry per parameter; the query's is ignored), a value that does not
// depend on p counts at its interval's end that keeps the bound below d. The rules: p's components and values
// independent of p; sums, differences, negations, products and quotients by constants, dot products and
// matrix products with constants (affine values, exactly); max of bounds (the union of their pieces); |x| of
// an affine x (two pieces); a positive constant times a bound; a sum of bounds (their pieces' sums). Nothing
// where d is something else (a min, a norm, a choice), where a coefficient of p is not one constant, or past
// `max_pieces` pieces (128: the box's and the radius's searches take every three).
std::optional<std::vector<AffinePiece>> convex_lower_bound(const Module& m, const Function& g, int query,
                                                           std::vector<std::vector<Interval>> params,
                                                           size_t max_pieces = 128);

// A value of `g` that is a constant affine map of the query point, v = A p + b (A's rows; A invertible and
// mixing axes: some row has two non-zero entries), found by the same rules: a rotation written inside a
// module, q = R p or R (p − c), which interval arithmetic cannot see through (over a half-space beyond a plane
// each component of R p is unbounded). support_box analyses such a shape over boxes of v and maps the box
// back through A⁻¹. In body order; a value whose A or b is not one number (a parameter's range, a slider, a
// constant the shader's float would move) is not one.
struct AffineMap {
    ValueId value = 0;
    std::array<std::array<double, 3>, 3> A{};
    std::array<double, 3> b{};
    std::array<std::array<double, 3>, 3> inverse{};  // A⁻¹
};
std::vector<AffineMap> affine_maps(const Module& m, const Function& g, int query, std::vector<std::vector<Interval>> params);

// The box of the polytope {p : aᵢ⋅p + bᵢ ≤ level for every i} (object units), side by side as the Farkas
// certificate above gives it, rounded outward; ±∞ on a side no combination of the pieces closes.
SupportBox polytope_box(const std::vector<AffinePiece>& pieces, double level);

// The radius of a ball around the origin holding that polytope: its farthest vertex (every three planes solved,
// with unit normals), rounded up, or the box's farthest corner where three planes are too nearly dependent to
// place their vertex; nothing where it is unbounded (a side of polytope_box is ±∞), empty, or has more than
// 128 pieces.
std::optional<double> polytope_radius(const std::vector<AffinePiece>& pieces, double level);

}  // namespace iqc::ir
