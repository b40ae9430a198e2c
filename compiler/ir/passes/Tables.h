// Table compression: a read `T[k]` of a compile-time table (a Constant array global, such as a group's
// per-instance offsets) whose entries follow a lattice becomes arithmetic on k, and the table goes.
//
// A component's entries s[0..N) follow a lattice when s[k] = b + Σ_t a_t·((k div d_t) mod m_t) exactly (to
// a relative 1e-9), as instances laid out by nested loops on a regular grid do: k mod 10, k div 10 mod 10,
// k div 100. The terms are found level by level — a level's step is s[1] - s[0], its run length the first
// index where that step stops holding — then every entry is checked. Tables that do not fit (random
// positions, rotations) stay tables. Why: a constant array indexed by a loop counter is slow on GPUs and
// llvmpipe, and a 10,000-entry table would be most of the shader's text.
//
// Requires verified IR; runs on every function (group loops are functions of their own).
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of reads replaced.
int compress_tables(Module& m);

}  // namespace iqc::ir
