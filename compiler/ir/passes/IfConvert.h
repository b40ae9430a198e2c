// If-conversion: a switched argument of a call with cheap arms becomes eager selects.
//
// Requires verified IR. A lazy If or Switch (ir/Schedule.h: only the chosen arm runs) whose value is a scalar,
// an integer, a boolean or a vector, that only calls read as an argument (the switched arguments MergeCalls
// makes: two plates' points, each a rotation and an offset, passed to one call of `plate`), and whose arms (each
// arm's own instructions, with the arms of choices inside it) are cheap and safe to compute whatever the
// selector, becomes a Select (a chain of them for a Switch: case k's test `id == lo` or `lo <= id && id < hi`,
// the default last): the classic if-conversion of compilers for predicated and SIMD machines (Allen, Kennedy,
// Porterfield & Warren, "Conversion of control dependence to data dependence", POPL 1983). Cheap: at most
// kMaxArms arms, kMaxArmCost instructions per arm and kMaxTotalCost over all arms, reads of values and
// components free, and some arithmetic in at least one arm (a branch that only reads values every driver flattens itself, and
// `if (l == 0) position = light_1_position;` reads better than nested selects). Safe: no call (its cost is not
// known here), recurrence, array index that is not a constant (out of range in another case), or integer
// division by anything but a non-zero constant; a NaN or ∞ an untaken arm computes is discarded by the select.
//
// Why, measured as the instructions llvmpipe (Mesa's software renderer, our test renderer) executes to compile
// and draw a shader at 8×8 (valgrind, deterministic): the grazing-plane bench scene's if-blocks choosing the
// plates' points cost 366 M against 351 M as selects (the hand-written reference: 312 M), hard case 43's three
// boxes' 731 M against 714 M; its frame time is unchanged. Choices whose value is not an argument (a
// dispatch's result: the analytic normal's gradients, 351 M → 360 M as selects; a material's colour) stay as
// they are: there selects measured worse or no better. A GPU runs the selects' few extra instructions at no
// measurable cost; costly arms stay lazy.
//
// One dispatch is converted too: iqc_distance_of's (each instance's own distance, what finite-difference normals
// take their taps of), where it has 2 to kMaxArms cases and its arms, calls costed by their callees' bodies (no
// lazy choice, loop or unsafe read in them), cost at most kMaxDispatchCost instructions in all. Every tap then
// computes every instance's distance, as a hand-written normal tapping the whole scene does, and the runtime
// passing only instances' ids, the widest case stands innermost untested and the default goes. llvmpipe runs
// every if body anyway; its compile of the if-chain cost more: a few shapes 327.0 -> 321.1 M instructions (the
// hand-written reference 316.7), the grazing plane 341.4 -> 334.8 M (312.7), frame and picture unchanged (the
// GLSL backend computes a select's call operands in statements: ?: would be a branch again).
#pragma once

#include "ir/IR.h"

namespace iqc::ir {

inline constexpr int kMaxArmCost = 16;    // instructions in one arm
inline constexpr int kMaxTotalCost = 48;  // instructions over all arms of one choice
inline constexpr int kMaxArms = 8;        // arms of one choice (cases and the default): 40 instances' points
                                          // of one add each were a 39-deep select, all 40 computed per tap
inline constexpr int kMaxDispatchCost = 64;  // instructions over all instances' distances (calls' bodies
                                             // counted) for iqc_distance_of's dispatch to become selects

// Returns the number of If and Switch instructions converted.
int convert_cheap_choices(Module& m);
// One function (its nested choices too).
int convert_cheap_choices(const Module& m, Function& f);

}  // namespace iqc::ir
