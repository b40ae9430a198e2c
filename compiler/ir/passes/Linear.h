// Cancellation of linear terms: a scalar value that is a linear combination of other values (sums,
// differences, negations, products and quotients by constants) whose terms cancel or merge is re-emitted as
// its canonical sum, and a comparison of two such values whose difference has fewer terms compares that
// difference with a constant: (a + d) - a becomes d, a < a + d becomes d > 0.
//
// Exact in real arithmetic; in floating point it rounds differently from the forms it replaces, so the
// pipeline does not run it on emitted code. It serves the interval analyses (ir/passes/Lipschitz.cpp): a
// blend f(a, b) of two distances is analysed over a = x, b = x + d, where x ranges over all the distances and
// d over a narrow band; interval arithmetic on (x + d) - x gives an interval as wide as x's (the dependency
// problem, Moore 1966), on d the band.
//
// Requires verified IR without calls (inline first). Each form keeps at most 8 terms (a longer one is a term
// of its own).
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of values re-emitted. The body is rebuilt without the instructions replaced; what only
// they read is left dead for dce.
int cancel_linear_terms(Function& f);

}  // namespace iqc::ir
