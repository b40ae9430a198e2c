// A shape's extent, derived from its distance function by interval arithmetic: the radius of a ball around
// the origin of its own space that contains every point where the distance can be ≤ 0 (the solid and its
// surface). The scene compiler uses it as a `bound` the user did not write, so that a large group of
// instances gets a bounding-volume hierarchy (scene/Bvh.h).
//
// Method: branch and bound over boxes (Moore, "Interval Analysis", 1966; Snyder, "Interval analysis for
// computer graphics", SIGGRAPH 1992): a box where the interval of the distance lies above 0 holds no point of
// the solid and is dropped; the others are split into octants, first over a cube of half-side `reach` (a box
// left on its boundary: unbounded), then a few times over the hull of what is left, and last best first: the
// box with the farthest corner is split until it is small against that distance. The radius is the farthest
// corner of a box left, so it contains the solid whatever the overestimation of intervals (which only keeps
// more boxes, and makes the radius larger). Where one pass of intervals leaves a box unproven and the function
// has comparisons (a piecewise choice, a sign), the box is analysed again case by case (ir/CaseSplit.h: each
// case narrows what it implies), whose lowest value over the cases still bounds the distance from below: the
// hull of the octahedron's three cases alone proves no half-space free.
// A convex polytope written as the largest of its planes' distances (a tetrahedron) is bounded by its planes
// instead (ir/ConvexBound.h: Farkas combinations for the box's sides, the farthest vertex for the radius), where
// intervals leave every plane's distance unbounded below over a half-space.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "ir/IR.h"
#include "ir/Intervals.h"

namespace iqc::ir {

// Function `fn` of `m` returns a scalar distance; parameter `query` is the ℝ³ point, the others lie in
// `params` (one entry per parameter, its components' intervals; the query's entry is ignored). Returns the
// radius (object-space units, rounded up), or nothing when a box touching the cube of half-side `reach`, or a
// half-space beyond one of its faces, may hold the solid (an unbounded shape, such as a plane; a part farther
// than `reach`; a distance the intervals cannot bound), or when the work budget (interval evaluations) runs
// out first.
std::optional<double> support_radius(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double reach = 1024, int budget = 20000);

// An axis-aligned box that contains every point where the distance can be ≤ `level`, found side by side:
// each side is the nearest plane c such that the half-space beyond it (x_a ≥ c, or ≤) is proven free of
// such points (bisection on c; a proof splits the half-space into boxes, up to `per_proof` of them, and
// gives up at once where the half-space's point nearest the origin, or a box's centre, lies in the set; a box
// one pass leaves unproven is tried case by case, as support_radius does, within an allowance per proof and a
// pool of instructions as large as `work`). A side no plane within 2²⁰ units closes is ±∞.
// Loops of constant trip count up to `loop_trips` are analysed (interval_analysis). `work` bounds the
// instructions analysed in all (about 10 ms per million): once spent, the sides not yet closed are ±∞. Same
// function conventions as support_radius. Returns nothing when every side is ±∞ (no box to clip rays to).
struct SupportBox {
    std::array<double, 3> lo, hi;  // world (or object) units; ±∞ where unbounded
};
std::optional<SupportBox> support_box(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                      double level, int per_proof = 48, int loop_trips = 16, long work = 1500000);

// A quick test, for ordering work: whether support_box's first step, on the axes as they are, leaves a side
// open (the half-space beyond 2²⁰ units on some side is not proven free of points at or below `level`, or the
// function cannot be boxed, or `work` instructions analysed do not decide): six proofs of up to `per_proof`
// boxes. support_box's rotated pairs may still close such a side.
bool support_box_open(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params, double level,
                      int per_proof = 48, int loop_trips = 16, long work = 300000);

// An upper bound of the distance's depth inside the solid, max(−d) over the box [lo, hi] (finite on every side;
// for an exact signed distance the radius of the largest ball inside the solid: a shell's or a tube's half
// thickness). Best-first branch and bound (Moore 1966): the box whose interval of d reaches lowest is split in
// two at its widest side until that bound is within 10% of a depth found at a box's centre, or `work`
// instructions (or 20,000 splits) are spent; nothing where the function cannot be boxed or no bound under +∞ is found. A distance
// that underestimates (a Lipschitz bound, not exact) gives a smaller depth than the solid's.
std::optional<double> deepest_bound(const Module& m, int fn, int query, std::vector<std::vector<Interval>> params,
                                    const std::array<double, 3>& lo, const std::array<double, 3>& hi, int loop_trips = 16,
                                    long work = 1500000);

}  // namespace iqc::ir
