// The pass pipeline: the one place that says which passes run on a compile's IR, and in which order.
//
//   lipschitz each shape's Lipschitz bound over where it is marched, derived from its gradient's IR by
//             interval arithmetic; the item's distance divided by it (ir/passes/Lipschitz.h)
//   inline    the scene's building blocks (marked inline_hint) into the scene functions
//   tables    compile-time tables on a lattice (grid offsets) become arithmetic on the index
//   fold      constants, constant globals, identities, lazy choices with constant conditions
//   cse       one value per computation (shared values are one value for the analyses that follow)
//   ranges    range analysis: guards where an operation can leave its domain, warnings where a slider can
//             take it there (ir/passes/Ranges.h)
//   gradient  analytic normals: iqc_gradient by forward-mode differentiation of iqc_distance_of
//   segment   segment tracing: iqc_segment_gain from the interval extension of each instance's gradient
//             (ir/passes/IntervalExtension.h)
//   simplify  fold + cse again (the gradient's identity seeds, the guards' constants)
//   dce       dead instructions, then functions and globals no entry function reaches
//
// Every pass runs on every function. With `verify_each` (tests, debug builds) the IR is verified before
// the first pass and after every pass; a fault is an internal error naming the pass. `dump_after` prints
// the module after the named pass (`--dump-ir=after-NAME`); `inject_fault` makes the named pass fail (the
// tests of the exit-3 path).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "ir/IR.h"
#include "ir/passes/Stable.h"
#include "ir/passes/Ranges.h"

namespace iqc::ir {

struct PipelineOptions {
#ifdef NDEBUG
    bool verify_each = false;
#else
    bool verify_each = true;
#endif
    std::string dump_after;    // a pass name, "lower" (before the first pass) or "" (no dump)
    std::string inject_fault;  // a pass name
    bool guard_ranges = true;  // insert the range guards (off: analysis and warnings only)
};

struct PipelineResult {
    std::vector<RangeIssue> range_issues;                 // from the ranges pass
    std::vector<RangeIssue> warnings;                     // what else a pass wants the user to know (gradient, lipschitz)
    std::string segment_refused;                          // why the segment pass kept iqc_segment_gain at 1 ("": it did not)
    std::vector<std::string> lipschitz;                   // per scene item: derived, sampled and applied bounds
    double lipschitz_largest = 1;                         // the largest Lipschitz factor a distance was divided by
    std::vector<StableRewrite> rewrites;                  // what the stable pass rewrote, where
    std::string dump;                                     // the module after `dump_after`
    std::vector<std::pair<std::string, double>> pass_ms;  // wall time per pass
};

struct PassInfo {
    const char* name;
    const char* summary;
};

// The passes in order (names for --dump-ir=after-NAME and --help).
const std::vector<PassInfo>& pipeline_passes();
bool is_pass_name(const std::string& name);

// Runs the pipeline on `m`. Throws InternalError when the IR fails verification or a pass fails.
PipelineResult run_pipeline(Module& m, const PipelineOptions& o);

// Runs one pass by name (pass tests); false when there is no such pass.
bool run_pass(const std::string& name, Module& m, const PipelineOptions& o, PipelineResult& r);

}  // namespace iqc::ir
