// Where each instruction of a function runs.
//
// `If` and `Switch` are lazy: an instruction whose every use lies inside one arm of such an operation (its
// `then` or `else` operand, a case or the default, or instructions that themselves run only there) runs
// only when that arm is chosen. The schedule groups a function's live instructions into nested regions:
// region 0 is the function body, and every arm of a live lazy operation is a child region of the region
// that operation runs in. Each region lists its instructions in body order (SSA order is kept, so each
// operand is computed before its use, in the same region or an enclosing one).
//
// The GLSL backend prints arms as if-blocks; the evaluator runs only the chosen arm. Dead instructions
// (not needed by the roots) belong to no region.
#pragma once

#include <vector>

#include "ir/IR.h"

namespace iqc::ir {

struct Schedule {
    struct Region {
        int parent = -1;           // enclosing region (-1 for the body)
        ValueId owner = 0;         // the lazy operation whose arm this is (regions > 0)
        int operand = 0;           // which operand of the owner the arm computes
        std::vector<ValueId> instrs;  // in body order
    };
    std::vector<Region> regions;   // regions[0] is the function body
    std::vector<int> region_of;    // per instruction: its region, or -1 when dead
    // For a live lazy operation, the region of each operand position (-1 where the operand is not an arm:
    // the condition or selector).
    std::vector<std::vector<int>> arms;

    bool live(ValueId v) const { return region_of[v] >= 0; }
};

// The schedule of `f` computing `roots` (the result and, for functions with several outputs, those).
Schedule schedule(const Function& f, const std::vector<ValueId>& roots);
// The schedule computing the result and every output.
Schedule schedule(const Function& f);

// Whether operand `k` of `in` is an arm of a lazy operation.
inline bool is_arm(const Instr& in, size_t k) {
    return (in.op == Op::If && k >= 1) || (in.op == Op::Switch && k >= 1);
}

}  // namespace iqc::ir
