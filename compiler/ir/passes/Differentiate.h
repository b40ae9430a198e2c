// Forward-mode differentiation: from a function F(p, params...) -> ℝ, builds G(p, params...) -> ℝ³,
// the gradient of F with respect to its parameter p ∈ ℝ³ (the shape's query point), exact up to
// rounding. Used for analytic normals: one gradient evaluation of the hit instance instead of four or
// six evaluations of the whole scene.
//
// Calls are inlined first. Every value carries its tangent alongside: a scalar's gradient (ℝ³), a vector's
// Jacobian (ℝ^(n×3), row i the gradient of component i). Values that do not depend on p carry none (no
// code). Rules follow the usual derivatives; where the math has a kink, the derivative of the branch
// taken (min, max, abs, clamp, piecewise), and derivative guards where it is singular (‖v‖ at 0, √ at 0).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "ir/IR.h"

namespace iqc::ir {

// Returns the index of the new function in m, or -1 with `why` set when F's result needs something without
// a derivative rule here (a recurrence's loop, a matrix that depends on p). Where such a value is used
// only in arms of lazy If/Switch operations, those arms get a zero gradient instead (the renderer falls
// back to finite differences there), and `fallbacks` lists each such value's span and reason.
int differentiate(Module& m, int fn, int wrt_param, const std::string& name, std::string* why,
                  std::vector<std::pair<Span, std::string>>* fallbacks = nullptr);


}  // namespace iqc::ir
