// Array arguments bound to the globals they are.
//
// Requires verified IR. A call that passes a global array whole (a module's sequence parameter, x_i ∈ ℝ³, an
// array one instance owns) calls a copy of its callee that reads that global where it read the parameter, and
// the argument goes. GLSL passes arrays by value: `m(p, m_1_shape_x)` copies the whole array from its uniform
// block into the callee at every call, which llvmpipe runs as a load and a store per element (a trial's three
// instances with 300-vector sequences: 51 s a frame at 160x90 against 62 ms with Shadertoy's constants), and an
// array in the data texture (past a block's 16 KiB) had to be gathered texel by texel into a local array per
// call (Mesa's compile of a 1,025-vector sequence did not finish). Read in place, only the elements the callee
// indexes are read (from the block, or fetched from the texture).
//
// A loop's captured global array (a rolled ∑ over a sequence: ir/Lower.cpp) binds in its body the same way.
//
// One copy per callee and binding (calls that pass the same global share it); copies are bound again where
// they pass the global on. Where parameters are constants (Shadertoy) only arrays of kBoundConstantArray (64)
// elements or more: the driver folds a short constant array's values into the code (a copy of the function per
// instance would only grow it), but three instances' `const vec3 x[1100]` passed by value to six calls kept
// Mesa's compile from finishing in 120 s (7 s bound). The originals nothing calls any more go with dead-code
// elimination.
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of calls rebound.
int bind_array_arguments(Module& m);

}  // namespace iqc::ir
