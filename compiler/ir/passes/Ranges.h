// Range analysis: interval arithmetic over a function's IR, from its parameters' and globals' slider bounds.
//
// Requires verified IR. Each value gets an interval per component, and whether it is "known": computed
// from constants, sliders (parameters and parameter globals) and constant globals only (not from the
// renderer's inputs — the query point, the surface point, normal and eye — nor from time, the mouse, a loop
// or a value prepared per pixel). Function parameters' bounds come from Function::param_bounds, globals'
// from Global::bounds (a constant's from its value). Then:
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
#include "ir/Intervals.h"

namespace iqc::ir {


struct RangeIssue {
    Span span;
    std::string message;
};

// Analyses (and, with `guard`, rewrites) function `fn`. Returns the warnings.
std::vector<RangeIssue> analyze_ranges(Module& m, int fn, bool guard);
// Every function of the module; warnings in source order, each once.
std::vector<RangeIssue> analyze_ranges(Module& m, bool guard);

}  // namespace iqc::ir
