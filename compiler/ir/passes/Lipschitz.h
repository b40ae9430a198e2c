// Lipschitz bounds derived by the compiler: sphere tracing steps by the distance, which is safe only when
// the field changes at most 1 per unit of distance; a field that changes faster (a sine displacement, a
// twist) must be divided by its Lipschitz factor K = max ‖∇D‖, or the march steps through the surface and
// leaves holes.
//
// For each scene item whose distance function carries a LipschitzSpec, the shape's object-space distance
// is differentiated (forward mode, ir/passes/Differentiate.h) and an upper bound of ‖∇D‖ over the item's
// region — its `bound` sphere, else the part of space the camera can reach within max_dist — is computed
// by interval arithmetic on the gradient's IR (ir/Intervals.h), refining the box where the bound is worst
// (branch and bound: the largest bound over a cover of the region by boxes bounds the whole region). The
// gradient is also sampled at points of the region (the largest sampled ‖∇D‖ is a lower bound of K).
//
// Two refinements tighten the derived bound where one interval evaluation of the whole gradient is loose:
// the chain rule at a cut (D = F(T(p)) with u = T(p) ∈ ℝ³ the only way p reaches D: sup‖∇F‖·sup‖J_T‖, ‖J_T‖
// by Gershgorin's bound of JᵀJ — a twist, a rotation by a piecewise-constant angle), and a union term by term
// (a min, max or select picks one operand's gradient: the largest operand bound, each with its own cut).
// They cost several estimates each, so the pass refines the first 16 items' bounds only (a scene of 300
// animated displaced tori took 8 s); later items keep the direct bound, which is safe, only looser. The
// search for jumps (below) is done for those 16 too.
//
// The item's distance is then divided by K_applied:
//  * the shape says `# lipschitz: K`: K (warned when a sample already exceeds it);
//  * the shape says `# exact` or `# bound` (1-Lipschitz by construction): 1;
//  * every sample is 1-Lipschitz and the derived bound is at most 2 (interval arithmetic loses the
//    orthogonality that makes a torus exactly 1-Lipschitz): 1;
//  * else the derived bound — unless it is not finite or exceeds 64 over the region (a twist without a
//    bound): then the item keeps 1 and gets a located warning naming the fix (`bound = R`).
//
// The gradient says nothing about jumps: a field that is 1-Lipschitz between them (‖repeat(p, c) - o‖ - r
// with the sphere off the cell's centre, a staircase of ⌊x⌋) passes every test above. Pairs of nearby points
// are sampled too; where two of them differ by more than K times their distance, the field is discontinuous,
// and the item gets a located warning (sphere tracing may step through the jump's faces).
#pragma once

#include <string>
#include <vector>

#include "ir/IR.h"
#include "ir/Intervals.h"
#include "ir/passes/Ranges.h"

namespace iqc::ir {

struct LipschitzEstimate {
    double derived = 0;   // proven upper bound of ‖∇f‖ over the region (∞ when none could be derived)
    double sampled = 0;   // the largest ‖∇f‖ seen at sample points (a lower bound of the true K)
    std::string why;      // when derived is ∞: what has no derivative rule or no bound
    // A jump: two points `delta` apart (the first at `jump_at`) whose distances differ by `jump`, more than
    // any continuous field with gradient ≤ derived allows (a floor, a mod, a repetition of a shape that
    // crosses its cell): no Lipschitz bound holds across it. 0: none found.
    double jump = 0, delta = 0;
    std::vector<double> jump_at;
    // The work spent: interval evaluations of a gradient (or a warp's Jacobian) over a box or at a point, the
    // refinements' included (a regression measure; a box is ~1-100 µs depending on the shape's size).
    long boxes = 0;
    // The analysis work (ir::analysis_work's unit: evaluator steps and bounded instructions) the estimate took, set by
    // apply_lipschitz_bounds, where the slider cells' estimates are budgeted by it.
    uint64_t work = 0;
    bool unevaluable = false;  // neither the gradient nor the distance evaluates within the step limit (`why` says)
    // The largest Σ|∂f/∂x_i| the analysis of a blend f of distances x_i (a smooth minimum written in the module)
    // met at a point of its arguments: above 1, f is no convex combination of its distances' gradients, and a
    // slope above 1 may hide in a band the samples miss (0: no blend analysed).
    double blend_steepest = 0;
    // Where the sliders are uniforms and the bound is within 2 with every sample within 1: the bound derived with
    // each slider at its default (0: not derived). Within 1 there, the rest comes from the sliders' ranges, and the
    // derived bound is applied, not 1 (k‖p − b‖ beside a flatter ball, k ∈ [0.85, 1.98]: steeper only near b at
    // k's high end, where no sample fell).
    double at_defaults = 0;
    // Without a useful bound: the steepest sample where the distance is ≥ 0 (outside the shape, where sphere tracing
    // steps from; 0: none taken). The K marched by then comes from it.
    double outside = 0;
    // A group whose parameters are constants: `derived` is the largest of its members' bounds, each with the member's
    // values (the group's over the hull of its per-member tables was larger).
    bool per_member = false;
};

// Bounds ‖∇f‖ with respect to parameter 0 (ℝ³) of function `fn` over `box` (its three components); other
// parameters take the intervals in `others` (one per parameter after the first). Adds nothing to `m`.
// `ball` > 0: only points of the box within that distance of the origin count (a `bound` sphere).
// `refine`: try the tighter bounds (chain rule at a warp, unions, roots of squares, case splitting) where the
// direct one decides something; case splitting spends at most `*split_work` interval instruction evaluations
// (decremented; null: 8·10⁶, about a second). `jumps`: look for a jump (LipschitzEstimate::jump) against the
// bound derived. `derived_suffices`: the caller applies the derived bound wherever it is useful (finite, ≤ 64: a
// slider cell away from the defaults), so the samples that choose or word a K (near the shape, at the sliders'
// settings: ~85% of a smooth union's cell) are not taken there; the uniform ones are.
// `shared`: where `valid`, a refined bound of the same shape over a box that holds `box` (uniform targets: instances
// that differ only in the sliders' defaults share one), taken instead of refining (the refinements are ~90% of a
// smooth subtraction's estimate). Else, with `force`, the refinements run even where the bound is within 2 and every
// sample within 1 (the bound is for others, whose samples may not be).
struct RefinedBound {
    bool valid = false, force = false;
    double derived = 0, blend_steepest = 0;
    // The samples at settings of the sliders (their ends, corners, random values: over the same ranges for every item
    // that shares this), taken once by the first estimate that reaches them and reused by the others: four moving fbm
    // rings spent 40% of each whole estimate on them (trial76, N3).
    bool settings_valid = false;
    double settings_sampled = 0, settings_outside = 0;
};
LipschitzEstimate estimate_lipschitz(const Module& m, int fn, const std::vector<Interval>& box,
                                     const std::vector<std::vector<Interval>>& others, double ball = 0,
                                     int samples = 1000, int boxes = 128, bool refine = true, double* split_work = nullptr,
                                     bool jumps = true, bool derived_suffices = false, RefinedBound* shared = nullptr);

// A standard-library combinator of two distances (stdlib/operators.iql: "operators.smooth_union", …) and its
// Lipschitz factor in them: ‖∇F(a, b)‖ ≤ factor · max(‖∇a‖, ‖∇b‖). 0 for any other function name.
double combinator_factor(const std::string& function_name);

// The pass: every function with a LipschitzSpec. Returns the warnings (located at the instances) and, in
// `report`, one line per item ("shape 'twisted': K ≤ 7.6 derived, 3.9 sampled, 7.6 applied"); in `largest`, the
// largest factor applied (1 where none is divided): sphere tracing's steps near that item are K times shorter.
std::vector<RangeIssue> apply_lipschitz_bounds(Module& m, std::vector<std::string>* report = nullptr, double* largest = nullptr);

}  // namespace iqc::ir
