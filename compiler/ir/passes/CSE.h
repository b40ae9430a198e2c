// Common subexpression elimination.
//
// Requires verified IR. Every IR operation is pure (functions included), so two instructions with the
// same operation, type, operands and constant data compute the same value: later copies are redirected
// to the first. Named statements keep their own instruction (they are the user's names), but later
// unnamed copies of them reuse the named value. Redirected instructions are left dead in the body;
// consumers (the evaluator, the GLSL backend) skip what the result does not use.
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of instructions redirected.
int eliminate_common_subexpressions(Function& f);

}  // namespace iqc::ir
