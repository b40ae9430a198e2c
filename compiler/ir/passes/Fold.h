// Constant folding and algebraic simplification.
//
// Requires verified IR. An instruction whose operands are all constants becomes a constant (evaluated by
// the evaluator's own rule, so folding cannot disagree with `iqc eval`); products with 0, 1 or the
// identity matrix and sums with 0 are replaced by their value. Used on functions the compiler derives
// (gradients), whose seeds are identity matrices; redirected instructions are left dead.
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of instructions folded or simplified.
int fold_constants(const Module& m, Function& f);

}  // namespace iqc::ir
