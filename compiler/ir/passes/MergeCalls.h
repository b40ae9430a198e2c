// Calls merged across a switch's cases.
//
// Requires verified IR. Where two or more cases of a Switch are calls to the same function (instances that
// share a material, each with its own parameters: `if (id == 0) c = lambert(p, N, k_d0); if (id == 1) c =
// lambert(p, N, k_d1); ...`), the calls become one call whose differing arguments are switched on the same
// selector (`k_d = id == 0 ? k_d0 : k_d1; c = lambert(p, N, k_d)`). Arguments that are the same value in every
// case stay as they are; a switched argument's default (the value for the cases that pass it) is one safe to
// compute for any selector (not a group's table read at id - k, out of range for other ids). The merged call
// runs whatever the selector (every IR function is pure, so running it on another case's arguments and
// discarding the value is harmless); the selected case gets exactly the value its own call computed. On a SIMD renderer (llvmpipe, a GPU warp whose pixels hit different instances) a chain
// of k calls costs k bodies; the merged one costs one, plus k argument selections.
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of calls merged away (k cases calling one function merge k - 1 of them).
int merge_switch_calls(Module& m);

}  // namespace iqc::ir
