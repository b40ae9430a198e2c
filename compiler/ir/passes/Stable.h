// Stable rewrites: the classic forms that lose everything in 32-bit floats, rewritten to equivalents that do
// not. Each rewrite is exact in real arithmetic (the double evaluator gives the same values to rounding).
//
//   log-sum-exp   log(e^a₁ + … + e^aₙ)  ->  m + log(e^(a₁−m) + … + e^(aₙ−m)),  m = max(aᵢ); terms may carry
//                 weights (w e^a), constant factors (e^a/2 = e^(a − ln 2)), products and powers of exponentials and
//                 a base c > 0 (c^a = e^(a ln c), c a constant or a positive slider); the log's argument may be a
//                 product, quotient, power or root of such sums and positive values (log(S/4) = log S − log 4)
//                 (the exponential smooth minimum -k ln(e^(-a/k) + e^(-b/k)): e^(-a/k) underflows to 0 in
//                 float once a/k > 103, and ln 0 = -∞; shifted, one term is e^0 = 1 and none overflows)
//   log cosh      log(cosh x)  ->  |x| + log(1 + e^(−2|x|)) − ln 2  (cosh overflows in float once |x| > 89)
//   hypot         sqrt(x₁² + … + xₙ²), 2 ≤ n ≤ 4  ->  length((x₁, …, xₙ))  (one norm: its derivative and
//                 its Lipschitz bound are the norm's, 1, not a quotient that intervals cannot bound)
//   1 − cos       1 − cos x  ->  2 sin²(x/2)  (cos x rounds to 1 for |x| < 2.4e-4 in float: the
//                 difference cancels to 0, where the rewrite keeps x²/2)
//
// x/‖x‖ is not here: the ranges pass guards it (normalize of a vector that can be 0).
// Requires verified IR; rewritten values keep their names; the unstable originals are left for the dce pass.
#pragma once

#include <string>
#include <vector>

#include "ir/IR.h"
#include "source/Source.h"

namespace iqc::ir {

struct StableRewrite {
    Span where;        // the rewritten expression (its instruction's span: may be empty for generated code)
    std::string what;  // "log-sum-exp", "log cosh", "hypot", "1 - cos"
    std::string function;
};

// Rewrites every function of `m`; returns what fired, in order.
std::vector<StableRewrite> rewrite_unstable_forms(Module& m);

}  // namespace iqc::ir
