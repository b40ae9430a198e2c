// Dead code elimination.
//
// Requires verified IR. Removes every instruction that neither the result nor an output of its function
// needs (what CSE and folding redirected, what a guard replaced), renumbering the rest in order; then, in a
// module with entry functions (those the runtime or the evaluator calls), removes every function and global
// that no entry reaches, renumbering calls, loops and global reads.
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of instructions removed from `f`.
int eliminate_dead_code(Function& f);
// Every function, then unreachable functions and globals; returns the number of instructions removed.
int eliminate_dead_code(Module& m);

}  // namespace iqc::ir
