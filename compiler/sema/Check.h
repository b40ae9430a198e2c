// Checker: names, types with sizes, and statement order for one module.
//
// Requires a parsed module. Resolves every name (parameters, assigned values, local functions, imports,
// built-ins, π), infers every expression's type, orders statements by their data dependencies (a module
// may use `q` before the line that defines it), and reports: undefined names (with a did-you-mean), names
// assigned twice, dependency cycles, operand types that do not fit (naming both sides), and missing `D`/`C`
// outputs. Errors are collected; checking goes on where it can.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "syntax/Ast.h"

namespace iqc {

// What a Name/Call/operator node was resolved to (stored in ast::Expr::resolved, with Expr::aux).
enum Resolved : int {
    R_None = 0,
    R_Param,      // module parameter, aux = index in CheckedModule::params
    R_Value,      // a value assigned in the module
    R_Local,      // local function parameter, aux = index
    R_Capture,    // inside a local function: a module value or parameter it uses, aux = capture index
    R_Pi,         // π
    R_Builtin,    // call of a built-in, aux = builtin id
    R_LocalFn,    // call of a local function, aux = index in CheckedModule::functions
    R_ImportFn,   // call of an imported function, aux = index in CheckedModule::imports
    R_Scale,      // `a(b)` where a is a value: multiplication
    R_Mul,        // product (scalar, matrix-vector, matrix-matrix, outer)
    R_DotProduct, // a ⋅ b of two equal-size vectors
    R_Pow,        // scalar power
    R_Inverse,    // matrix⁻¹
    R_Length,     // ‖vector‖
    R_AbsValue,   // |x|, ‖scalar‖
    R_Det,        // |matrix|
    R_Input,      // a reserved input: aux 0 = time (seconds), 1 = mouse (ℝ², [0,1]² of the view)
    R_SumIndex,   // the index of an enclosing ∑ (1-based)
    R_BlockZero,  // a 0 block of a block matrix, sized from its neighbours
    R_BlockOnes,  // a 1 block of a block matrix
    R_BlockIdentity,  // I in a block matrix
    R_LoopIndex,  // the index variable of the enclosing recurrence (ℤ)
    R_SeqCurrent, // z_k inside its recurrence: the current element, aux = sequence
    R_SeqFirst,   // z_1: the sequence's first element, aux = sequence
    R_SeqLast,    // z_(N+1): the element the recurrence ends with, aux = sequence
    R_ImportModule,  // call of a whole module imported as a function, aux = index in CheckedModule::imports
    R_Constant,   // a built-in constant imported by name (e from trigonometry), aux = builtin id
    R_MatPow,     // matrix power A^k, aux = k (a whole number; -1 is the inverse)
    R_Norm1,      // ‖v‖_1
    R_NormMax,    // ‖v‖_∞
    R_NormP,      // ‖v‖_p (args[1] is p)
    R_NormMatrix, // ‖v‖_M = √(vᵀ M v)
    R_Frobenius,  // ‖A‖, ‖A‖_F
    R_Norm0,      // ‖v‖_0: the number of components that are not 0
    R_Nuclear,    // ‖A‖_*: the sum of A's singular values
};

struct ParamInfo {
    std::string name;
    Span span;
    Type type;
    bool bounded = false;
    std::vector<double> lo, hi;  // per component, when bounded
    std::vector<double> value;   // default: given, else the bounds' midpoint, else 0
    bool has_default = false;
    std::string description;
    std::string seq_index;    // a sequence x_i ∈ ℝ³: its index letter (the type is then an array)
    bool zero_based = false;  // `b ∈ ℤ index`: an index counting from 0

    // The first component of `v` outside the slider bounds, compared as the shader's 32-bit floats (0.1 + 0.2
    // is 0.30000000000000004 in doubles, past a bound of 0.3, but the same float); -1 when none is (or unbounded).
    int outside_bounds(const std::vector<double>& v) const {
        if (!bounded) return -1;
        for (size_t i = 0; i < v.size() && i < lo.size(); ++i)
            if (float(v[i]) < float(lo[i]) || float(v[i]) > float(hi[i])) return int(i);
        return -1;
    }
    // "the value X of 'name' is outside its slider bounds [lo, hi]" for component i (a scene's override, eval's --set).
    std::string outside_bounds_message(const std::vector<double>& v, int i, const std::string& as) const;
};

struct CheckedModule;

struct LocalFunction {
    const ast::Stmt* stmt = nullptr;
    // A function parameter of the module (f: ℝ → ℝ) bound to a definition given from outside: its declared
    // type, which types the definition's parameters and result.
    const ast::TypeSpec* declared = nullptr;
    std::vector<std::pair<std::string, Type>> params;
    Type result;
    // Module values and parameters the body uses; passed as extra arguments after the declared ones.
    std::vector<std::pair<std::string, Type>> captures;
    bool checked = false;
    bool checking = false;  // recursion detection
    // A parameter with a symbolic size (x ∈ ℝ^n) makes the function generic: it is checked once per
    // combination of argument types it is called with (params/result above are those of the last one).
    bool generic = false;
    std::map<std::vector<Type>, std::pair<std::vector<std::pair<std::string, Type>>, Type>> instances;
};

struct ImportedFunction {
    std::string name;
    std::string module;
    Span span;
    const CheckedModule* from = nullptr;  // null for built-in modules
    int function = -1;                    // index in from->functions
    int builtin = -1;                     // for built-in modules
    // `torus from torus`: a shape, material or value module used as a function of its parameters (in
    // declaration order), returning its D, C or value.
    bool whole_module = false;
};

// A sequence defined by a first element and a recurrence: z_1 = p; z_(k+1) = f(z_k) for k ∈ 1..N.
struct Sequence {
    std::string name;
    const ast::Stmt* init = nullptr;
    const ast::Stmt* rec = nullptr;
    Type type;
    int group = -1;
};

// Recurrences with one index variable and one range run together, as one loop.
struct LoopGroup {
    std::string var;
    int lo = 1, hi = 0;  // var runs over lo..hi; the sequences end at element hi + 1
    std::string hi_name; // when the end is a ℤ parameter (hi is then unknown until run time)
    std::string last() const { return hi_name.empty() ? std::to_string(hi + 1) : "(" + hi_name + "+1)"; }
    std::vector<int> sequences;
    const ast::Stmt* leader = nullptr;  // its first recurrence (stands for the group in `order`)
};

struct CheckedModule {
    ast::Module ast;
    std::vector<ParamInfo> params;             // free parameters, in declaration order
    std::vector<const ast::Stmt*> order;       // Assign/Return statements in dependency order
    std::map<std::string, Type> values;        // assigned name -> type
    std::vector<LocalFunction> functions;
    std::vector<ImportedFunction> imports;
    const ast::Stmt* ret = nullptr;            // the bare expression, if any
    std::vector<Sequence> sequences;
    std::vector<LoopGroup> groups;
    int find_sequence(const std::string& n) const;
    std::string primary;                       // "D" (shape), "C" (material) or "" (the bare expression)
    // From the module's comment lines: `# lipschitz: K` (D changes at most K per unit: the renderer divides
    // by K so marching stays safe) and `# exact` / `# bound` (what D is; for documentation and tests).
    double lipschitz = 1;
    bool lipschitz_declared = false;  // the pragma was written (`# lipschitz: 1` too: then no derived bound replaces it)
    std::vector<std::shared_ptr<const ast::Module>> bound_functions;  // keeps given definitions alive
    std::string exactness;
    Type primary_type;
    // The parameters the renderer binds (the only rules for them: the scene compiler uses these): a shape's
    // query point; a material's surface point, unit normal and eye position, in that order. -1 where missing.
    std::vector<int> roles;
    bool ok = false;
    // The IR function's name where it is not ast.name: a variant checked for other sequence lengths (an
    // instance's 3 points where the module's default has 2: "blob_x3", ModuleLibrary::variant).
    std::string ir_name;

    int find_param(const std::string& n) const;
    int find_function(const std::string& n) const;
};

// Looks up a module by name for imports; may check it on demand. Returns null when there is none.
using ModuleLookup = std::function<const CheckedModule*(const std::string& name, Span where)>;

struct CheckOptions {
    // Names imported without an import line (the scene's transforms get T, R_x, ... from transformations).
    std::vector<std::pair<std::string, std::string>> implicit_imports;  // name, module
    // Types of parameters known from outside (e.g. `iqc eval --set`), which bind symbolic sizes (ℝ^n).
    std::map<std::string, Type> given_types;
    // Definitions of the module's function parameters (f: ℝ → ℝ), given from outside (`iqc eval --set
    // 'f(x)=x²'`): each a parsed module whose first statement defines the function.
    std::map<std::string, std::shared_ptr<const ast::Module>> given_functions;
    // The value of a constant expression that const_eval cannot fold (√2, sin(1), 2^(1/3), …) for defaults
    // and bounds: the scene layer lowers it and runs the evaluator (one meaning for every value). Empty, or
    // nullopt: not a constant.
    std::function<std::optional<std::vector<double>>(const ast::Expr&)> constant;
};

std::unique_ptr<CheckedModule> check_module(ast::Module module, const ModuleLookup& lookup,
                                            const CheckOptions& opts, Diagnostics& diags);

// Evaluates a constant expression (numbers, π, + - * / ^, vectors) as used in bounds and defaults.
std::optional<std::vector<double>> const_eval(const ast::Expr& e);

// The closest candidate within a small edit distance, for "did you mean" notes.
std::optional<std::string> did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace iqc
