// Range analysis: interval arithmetic over a function's IR, from its parameters' slider bounds.
//
// Requires verified IR. Each value gets an interval per component, and whether it is "known": computed
// from constants and free parameters only (not from the renderer's inputs — the query point, the surface
// point, normal and eye — nor from time, the mouse or a loop). Then:
//  * where an operation can leave its domain and the math has a continuous limit, a guard is inserted so
//    the shader cannot produce a NaN: acos/asin(clamp(x, -1, 1)), sqrt(max(x, 0)), pow(max(a, 0), b), and
//    atan2(0, 0) = 0 (what the evaluator's atan2 gives; GLSL leaves it undefined);
//  * where a known value can leave the domain (division by an interval containing 0, sqrt/log of a
//    possibly negative value, acos/asin outside [-1, 1], pow of a possibly negative base, normalize of a
//    possibly zero vector, mod by a possibly zero modulus) a located warning is reported: a slider can
//    reach it.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ir/IR.h"

namespace iqc::ir {

struct Interval {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
};

// A parameter's range: one interval per component, or nullopt for a value the renderer supplies.
using ParamRange = std::optional<std::vector<Interval>>;

struct RangeIssue {
    Span span;
    std::string message;
};

// Analyses (and, with `guard`, rewrites) function `fn`. Returns the warnings.
std::vector<RangeIssue> analyze_ranges(Module& m, int fn, const std::vector<ParamRange>& params, bool guard);

}  // namespace iqc::ir
