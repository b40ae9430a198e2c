// Pixel-invariant sums computed once per pixel, before marching.
//
// Requires verified IR of a scene (a module with iqc_scene; any other module is left alone). A value of a scene
// function that reads neither its query point nor anything computed from it — only constants, the parameters'
// globals, time and the mouse — is the same at every step of every march of a pixel, yet the march evaluates
// it at each step. Where such a value holds a loop (a rolled ∑ over a sequence, ir/Lower.cpp), it becomes a
// prepared global that iqc_prepare computes (ir/IR.h, Global::Kind::Prepared; the runtime calls it once per
// pixel, the evaluator once per parameter values): a weighted centroid `c = ∑_i w_i x_i / ∑_j w_j` over 100
// points cost two 100-trip loops per scene evaluation, and a constant `∑_i ∑_j ∑_k ‖x_i - x_j + x_k‖` over 100
// points 10⁶ terms per evaluation (a webgl2 render did not finish in 120 s).
//
// Only in what the march runs at each step (the functions iqc_scene, iqc_scene_unbounded, iqc_distance_of,
// iqc_gradient, segment tracing's bounds and the per-instance baseline call): a material runs once per pixel and
// light anyway, and each hoisted value stays live across the whole march (llvmpipe's compile of five point clouds
// whose materials' sums were hoisted too: 14 s against 0.8 s).
//
// Hoisted are the largest such values the rest of the function uses (the division above, not its two sums),
// where their type is a number, vector or matrix (else their operands). A function's parameter counts as
// invariant where every call passes it the same global or constant (a shape's sequence bound in place by the
// `arrays` pass, a weight); a function iqc_prepare itself calls, and loop bodies (their parameters change from
// trip to trip; ir/Lower.cpp already computes an index-free inner sum before its loop), are left alone, as are
// prepared globals (iqc_prepare computes them in order). Identical values share one global.
//
// At most 16 float components in all (ir/passes/Hoist.cpp kMaxComponents): each hoisted value is live across the
// whole march, and llvmpipe's compile slows past that (20 hoisted centroids: 33.5 s first frame, 20.7 s with five).
//
// The cost: the value is computed at every pixel, also where the march would have skipped the code that uses
// it (an instance's arm of a bounding-volume test that the pixel's rays never enter).
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

// Returns the number of values hoisted (uses replaced by a prepared global).
int hoist_pixel_invariants(Module& m);

}  // namespace iqc::ir
