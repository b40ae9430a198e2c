// The double-precision evaluator: runs an IR function on values.
//
// It is the reference for `iqc eval`, for compile-time folding (constant transforms are evaluated and
// inverted here, once) and, later, for the numerical tests. Built-ins use the evaluation rules of the
// built-in table (sema/Builtins.h), so they mean the same as in the folder and the GLSL backend.
#pragma once

#include <string>
#include <vector>

#include "ir/IR.h"
#include "source/Limits.h"

namespace iqc::ir {

struct Value {
    Type type;
    std::vector<double> v;  // components; matrices row-major
    double operator[](size_t i) const { return v[i]; }
};

// The reserved inputs (`time`, `mouse`), and the work budget of one evaluation.
struct EvalInputs {
    double time = 0;
    double mouse[2] = {0, 0};
    // One step per instruction plus one per component it produces; a recurrence whose iterations alone
    // exceed what is left is refused before it starts. Past the budget the evaluator throws EvalLimit.
    uint64_t max_steps = limits::kMaxEvalSteps;
    mutable uint64_t steps = 0;
};

// Thrown when an evaluation would exceed EvalInputs::max_steps; `span`: the recurrence or the
// instruction where it stopped. Callers turn it into a located diagnostic.
struct EvalLimit {
    Span span;
};

// Evaluates function `fn` of `m` with the given arguments; returns every value of its body (index = ValueId).
std::vector<Value> evaluate_all(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in = {});
// Evaluates and returns the function's result.
Value evaluate(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in = {});

// One instruction applied to its operands' values (args: the function's arguments, for Param).
Value eval_instr(const Module& m, const Function& f, const Instr& in, const std::vector<const Value*>& operands,
                 const std::vector<Value>& args, const EvalInputs& inputs);

// Math helpers shared with scene assembly.
std::vector<double> mat_inverse(const std::vector<double>& a, int n, bool* singular);
double mat_det(const std::vector<double>& a, int n);

// "1.5", "(1, 2, 3)", "[1 2; 3 4]" — full precision (shortest round-trip).
std::string format_value(const Value& v);

}  // namespace iqc::ir
