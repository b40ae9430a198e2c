// Inlining: a call replaced by the callee's body, its parameters bound to the arguments.
//
// Requires verified IR. The scene's building blocks (one instance's distance, its gradient) are small
// functions marked `inline_hint`; the inline pass puts them into the scene functions that call them, so the
// emitted scene reads as one function and later passes (fold, CSE) see across the boundary. Inlined
// values keep no names (the caller's names stay readable), except that a named call keeps its name on a
// copy. Loops are copied as they are (their bodies stay functions of their own).
#pragma once

#include <functional>

#include "ir/IR.h"

namespace iqc::ir {

// A copy of `f` with every call (only_marked: every call of an `inline_hint` function) replaced by the
// callee's body, recursively.
Function inline_calls(const Module& m, const Function& f, bool only_marked = false);
// A copy of `f` with every call replaced by the callee's body, recursively, except calls of the functions
// `keep` accepts (their arguments are still inlined).
Function inline_calls_except(const Module& m, const Function& f, const std::function<bool(const Function&)>& keep);

// inline_calls, with the constant arguments of calls of functions that are not `inline_hint` (the ones the
// GLSL backend keeps as functions) rounded to float, as the shader passes them: for analyses whose results
// must hold for the shader (a box, a radius), where a call R_z(10000000.49) folded in double turns by 183°
// and the shader's R_z(10000000.0) by 155°.
Function inline_calls_as_emitted(const Module& m, const Function& f);

// Inlines the `inline_hint` functions into their callers, in every function; returns the calls inlined.
int inline_marked(Module& m);

}  // namespace iqc::ir
