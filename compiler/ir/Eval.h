// The double-precision evaluator: runs IR functions on values.
//
// It is the one meaning of the IR: `iqc eval`, compile-time folding (constant transforms are evaluated and
// inverted here, once), SceneModel (the scene as a double-precision reference) and every numerical test
// run it. Built-ins use the evaluation rules of the built-in table (sema/Builtins.h), so they mean the same
// as in the folder and the GLSL backend. `If` and `Switch` run only the chosen arm (ir/Schedule.h).
//
// Globals: parameters start at their default values (Evaluator::set_global overrides them), constants are
// what the module says, and prepared globals are computed by the module's `iqc_prepare` function (when it
// has one) when a call first reads one (a shape's own function reads none: the Lipschitz pass builds an
// evaluator per instance, and preparing every instance's transform for each made a scene of n moving
// instances cost n² evaluations of iqc_prepare; 2,000 took 88 s).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ir/IR.h"
#include "source/Limits.h"

namespace iqc::ir {

struct Value {
    Type type;
    std::vector<double> v;  // components; matrices row-major; arrays element after element
    double operator[](size_t i) const { return v[i]; }
};

// The reserved inputs (`time`, `mouse`), and the work budget of one evaluation.
struct EvalInputs {
    double time = 0;
    double mouse[2] = {0, 0};
    // One step per instruction plus one per component it produces, counted afresh for every call; a
    // recurrence whose iterations alone exceed what is left is refused before it starts. Past the budget
    // the evaluator throws EvalLimit.
    uint64_t max_steps = limits::kMaxEvalSteps;
};

// Thrown when an evaluation would exceed EvalInputs::max_steps; `span`: the recurrence or the
// instruction where it stopped. Callers turn it into a located diagnostic.
struct EvalLimit {
    Span span;
};

class Evaluator {
public:
    // `m` must outlive the evaluator. The prepared globals are computed (iqc_prepare) at the first read.
    explicit Evaluator(const Module& m, const EvalInputs& inputs = {});
    ~Evaluator();
    Evaluator(const Evaluator&) = delete;
    Evaluator& operator=(const Evaluator&) = delete;

    // Overrides a parameter global (components row-major); the prepared globals are recomputed at their next
    // read.
    void set_global(int global, std::vector<double> value);

    // The function's result.
    Value call(int fn, const std::vector<Value>& args);
    // Every value of the function's body (index = ValueId; values in arms not taken, and dead ones, are
    // empty).
    std::vector<Value> call_all(int fn, const std::vector<Value>& args);
    // Fast path: arguments as component arrays; the result's components are written to `out`.
    void call(int fn, const double* const* args, double* out);
    // Evaluator steps taken by every call so far (the same unit as EvalInputs::max_steps): a measure of work
    // that, unlike time, is the same on every machine and under any load.
    uint64_t work() const { return work_; }

    struct Plan;  // per function: schedule and value layout (Eval.cpp)

private:
    const Module& m_;
    EvalInputs inputs_;
    std::vector<std::vector<double>> globals_;
    uint64_t steps_ = 0;  // work of the current call (EvalInputs::max_steps)
    uint64_t work_ = 0;   // of the finished calls
    mutable std::vector<std::unique_ptr<Plan>> plans_;
    bool prepared_ = false;  // the prepared globals hold iqc_prepare's values for the current parameters
    // A frame's values and their places, one per depth of calls (reused by every call at that depth).
    struct FrameBuffers {
        std::vector<double> data;
        std::vector<const double*> at;
    };
    std::vector<std::unique_ptr<FrameBuffers>> frames_;
    size_t depth_ = 0;
    FrameBuffers& frame_buffers();  // the next depth's (the frame gives it back when it ends)
    const Plan& plan(int fn) const;
    const std::vector<double>& read_global(int g);  // prepares first where g is a prepared global
    void prepare();
    friend struct Frame;
};

// Evaluates function `fn` of `m` with the given arguments (a fresh Evaluator: globals at their defaults).
std::vector<Value> evaluate_all(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in = {});
Value evaluate(const Module& m, int fn, const std::vector<Value>& args, const EvalInputs& in = {});

// One instruction applied to constant operands (the folder's rule; not for Param, Global, Call, Loop,
// Member, Input). Throws InternalError for those.
Value eval_instr(const Module& m, const Function& f, const Instr& in, const std::vector<const Value*>& operands);

// Math helpers shared with scene lowering.
std::vector<double> mat_inverse(const std::vector<double>& a, int n, bool* singular);
double mat_det(const std::vector<double>& a, int n);

// "1.5", "(1, 2, 3)", "[1 2; 3 4]" — full precision (shortest round-trip).
std::string format_value(const Value& v);

}  // namespace iqc::ir
