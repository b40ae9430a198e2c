// Case splitting for interval arithmetic on the IR.
//
// Case splitting: the gradient of a min, max, clamp or |x| is a choice between its operands' gradients by a
// comparison (ir/passes/Differentiate.cpp), and interval arithmetic on a box where the comparison can go
// either way takes the hull of both — a box's distance min(max(d₁, d₂), 0) + ‖max(d, 0)‖ gets gradient 2
// from two terms of which only one varies at any point. Here each undecided comparison a ≤ b of a function
// without calls is split into its two cases (closed: a point where a = b is in both), and each case narrows
// what it implies: the operands (a ≤ b: a below b's top, b above a's bottom), and, backwards through the
// values they were computed from, as far as sums, differences, negations, components, |x|, min and max allow
// (the forward–backward narrowing of constraint propagation, HC4: Benhamou et al., "Revising hull and box
// consistency", ICLP 1999). The values are then recomputed with what the case knows, so d₁ ≥ 0 leaves
// max(d, 0)'s first component d₁ and min(max(d₁, d₂), 0) zero. A case whose narrowing leaves an empty
// interval cannot happen and bounds nothing. Every point of the box lies in the case of its own comparisons,
// and every narrowing holds at it, so the largest bound over the cases bounds the gradient over the box.
// `passes` caps the interval evaluations per box; comparisons left undecided then are hulled as before.
//
// The same splits serve any quantity of a function's result that interval arithmetic bounds from above: the
// norm of a gradient (ir/passes/Lipschitz.cpp: the largest over the cases bounds it over the box), or minus
// the lower end of a distance (ir/Support.cpp: the lowest over the cases is a lower bound of the distance
// over the box, where the hull of an octahedron's three cases, each a permutation of |p|, loses what each
// knows and leaves the half-space beyond any plane unproven).
#pragma once

#include <functional>
#include <limits>
#include <vector>

#include "ir/IR.h"
#include "ir/Intervals.h"

namespace iqc::ir {

// What is bounded over a case: a function of the result's bounds, larger is worse (the largest over the cases
// bounds it over the box).
using CaseScore = std::function<double(const Bounds& result)>;

struct CaseSplitOptions {
    bool query_point = true;  // parameter 0 is the query point p (not a cut's intermediate vector u = T(p))
    // A sign of a query coordinate also has the case x = 0 exactly, where parameter 0 is not the query point
    // but values of it that may hold still on a volume of p (a blend's distances).
    bool zero_cases = false;
    int loop_trips = 0;       // as interval_analysis's (loops of constant trip count analysed per iteration)
    long* work = nullptr;     // as interval_analysis's: a budget of instructions, decremented
    // The least score there is: what a case that cannot happen scores (a norm: 0).
    double floor = -std::numeric_limits<double>::infinity();
    // Where only whether the score stays below a value matters: once a case's score reaches `target`, the
    // search stops and returns a value ≥ target (not then a bound: the cases not yet seen may score more).
    double target = std::numeric_limits<double>::infinity();
};

// The largest score over the cases of function `f` of `m` (calls inlined: comparisons inside callees are not
// split) when its parameters lie in `params`, with at most `passes` interval passes; `passes_left`, when
// given, receives the passes not spent. At most the score of one unsplit pass (the hull); `floor` where no
// case can happen; at least `target` where the search stopped there.
double case_split_bound(const Module& m, const Function& f, const std::vector<std::vector<Interval>>& params,
                        const CaseScore& score, int passes, const CaseSplitOptions& options = {},
                        int* passes_left = nullptr);

}  // namespace iqc::ir
