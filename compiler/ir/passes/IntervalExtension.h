// The interval extension of an IR function, as IR: code that computes, at run time, an interval that
// contains every value a function takes while one of its parameters ranges over a box (Moore, "Interval
// Analysis", 1966: the natural extension, each operation replaced by its interval rule). Segment tracing
// (Galin et al., "Segment Tracing Using Local Lipschitz Bounds", Eurographics 2020) evaluates the extension
// of a distance's gradient over the box of the next segment of the ray: a local Lipschitz bound, derived
// per operator by the compiler, instead of one global factor for the whole region.
//
// The rules are those of ir/Intervals.cpp (the compile-time analysis, in double precision), written as
// IR so that the emitted shader and the double-precision evaluator run the same code: sums and products
// of bounds, monotone functions at the ends, sin and cos with the extrema the interval holds, |x|, min,
// max, clamp, comparisons as (certainly, possibly) pairs and choices as hulls of the arms they may take.
// Every value is taken apart into scalar components (a matrix product is sums of scalar products).
// Values that do not depend on the box are left as they are (exact), whatever their operation.
//
// What has no rule here (a loop, an array read, an integer, a matrix inverse or a switch selector that
// depends on the box; tan, the hyperbolic inverses, mod and pow with an exponent or modulus that depends on
// it) makes the result unknown: `ok` false and `why` says what. atan2 (and two-argument atan) is [-π, π].
// Calls are followed into the callee. Values that only a choice's untaken arm uses do not matter when a
// constant decides the choice.
// An unbounded result (a division by an interval that holds 0) is ±1e30, not ∞: 32-bit floats would turn
// ∞ - ∞ into NaN. The code is in 32-bit floats on the GPU without directed rounding: callers widen what
// they read by a relative margin, and the arguments of functions with jumps are widened by 10⁻⁵ of their
// magnitude (a point's own rounding must not land across a jump the interval's ends do not reach).
#pragma once

#include <string>
#include <vector>

#include "ir/Builder.h"
#include "ir/IR.h"

namespace iqc::ir {

struct IntervalCode {
    bool ok = false;
    ValueId lo = 0, hi = 0;  // the result's interval (values of the builder's function, of fn's result type)
    // A condition (a boolean value of the builder's function) that holds where the function is continuous over
    // the box as far as its operations tell: no floor, ceil, round, fract, mod, sign or step whose argument's
    // interval spans one of its jumps, no choice whose condition the box leaves undecided (a piecewise
    // definition may jump where it switches). -1: no such operation depends on the box (continuous).
    ValueId continuous = ValueId(-1);
    std::string why;         // when not ok: the first operation without a rule that the result depends on
};

// Appends to `b`'s function the interval extension of function `fn` of `m` (which `b` must be building a
// new function for, not yet in m): parameter `wrt` of fn ranges over [lo, hi] (values of b of its type),
// every other parameter j is exactly args[j] (values of b; args[wrt] is ignored). Calls of fn with
// arguments that depend on the box are not followed: inline first (ir/passes/Inline.h).
IntervalCode emit_interval_extension(Builder& b, const Module& m, int fn, int wrt, ValueId lo, ValueId hi,
                                     const std::vector<ValueId>& args);

}  // namespace iqc::ir
