// The one table of built-in functions: for each, its name in the math, the module that must be imported
// to use it (none for min, max, exp, log, ...; `trigonometry` for sin, cos, ...), its signature rule, its
// evaluation rule in double precision, and its GLSL spelling. The checker, the evaluator/folder and the GLSL
// backend all read this table, so they cannot drift apart.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sema/Type.h"

namespace iqc {

enum class Sig {
    Elementwise1,  // (T) -> T, T scalar or vector
    Elementwise2,  // (T, T) -> T, a scalar operand broadcasts
    Nary,          // (T, T, ...) -> T, at least 2, a scalar operand broadcasts (min, max)
    Clamp,         // (T, lo, hi) -> T
    Mix,           // (T, T, t) -> T
    Length,        // (ℝⁿ) -> ℝ
    Normalize,     // (ℝⁿ) -> ℝⁿ
    // Names that are not IR built-ins: the checker types them and the lowering expresses them with other
    // IR operations (an Op::Builtin never carries these ids).
    Constant,      // e (Euler's number): a value, not a function
    Trace,         // tr(A), trace(A): square matrix -> ℝ, the sum of the diagonal
    Det,           // det(A): square matrix -> ℝ (Op::Det)
    Inverse,       // inv(A): square matrix -> matrix (Op::Inverse)
    Diag,          // diag(v): ℝⁿ -> n×n diagonal matrix; diag(A): square matrix -> its diagonal ℝⁿ
    Vec,           // vec(A): m×n matrix -> ℝ^(mn), the columns stacked (column-major)
    Unsupported,   // rank, null, orth: results of data-dependent size; rejected with a message
};

struct BuiltinInfo {
    const char* name;           // as written in the math
    const char* module;         // import needed ("" when always available)
    Sig sig;
    double (*eval1)(double);    // Elementwise1
    double (*eval2)(double, double);  // Elementwise2 / Nary fold
    // GLSL spelling: a function name (`sin` -> sin(x)), or a template in which `#` stands for the
    // (parenthesised) argument (`1.0 / tan(#)`). Empty for the non-IR signatures above.
    const char* glsl;
    // Known to the name splitter without an import: `sin` is never s·i·n. Names I♥LA only knows after
    // an import (`cot`, `tr`, `vec`, ...) are false: without the import, `tr` is t·r as in I♥LA.
    bool reserved;
    // Elementwise on matrices too (I♥LA's trigonometric functions: sin(A) is sin of each entry).
    bool matrices = false;
};

const std::vector<BuiltinInfo>& builtins();
// The built-in of that name; other spellings I♥LA accepts resolve to the same entry (arcsin -> asin,
// arsinh -> asinh, trace -> tr).
std::optional<int> find_builtin(std::string_view name);
inline const BuiltinInfo& builtin(int id) { return builtins()[size_t(id)]; }

// Multi-letter names the language knows without a declaration (built-in functions and the reserved
// inputs `time` and `mouse`), so the parser does not split them into letters.
std::vector<std::string> known_names();

// Modules made only of built-ins (`trigonometry`, `linearalgebra`), for import checking.
bool is_builtin_module(std::string_view name);
const std::vector<std::string>& builtin_modules();
// A trigonometric or hyperbolic function, which I♥LA lets carry a power before its argument: sin²(x).
bool is_power_function(std::string_view name);

// Every name a built-in module exports (aliases included), for "did you mean" and hints.
std::vector<std::string> builtin_module_names(std::string_view module);

// Result type of applying built-in `id` to the argument types, or an error message.
struct BuiltinCheck {
    Type type;
    std::string error;  // non-empty on failure
    int bad_arg = -1;   // argument the error is about, if any
};
// `name` is the spelling used in messages (the user's, e.g. arcsin); empty: the table's.
BuiltinCheck check_builtin(int id, const std::vector<Type>& args, std::string_view name = {});

}  // namespace iqc
