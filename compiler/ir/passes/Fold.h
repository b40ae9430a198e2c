// Constant folding and algebraic simplification.
//
// Requires verified IR. An instruction whose operands are all constants becomes a constant (evaluated by
// the evaluator's own rule, so folding cannot disagree with `iqc eval`), and so does a constant-index read
// of a constant global (not a parameter: sliders stay sliders); products with 1 or the
// identity matrix and sums with 0 are replaced by their other operand; If and Switch with a constant
// condition or selector are the chosen operand. Redirected instructions are left dead (the dce pass removes
// them).
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of instructions folded or simplified.
int fold_constants(const Module& m, Function& f);

}  // namespace iqc::ir
