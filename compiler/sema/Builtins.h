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
};

struct BuiltinInfo {
    const char* name;           // as written in the math
    const char* module;         // import needed ("" when always available)
    Sig sig;
    double (*eval1)(double);    // Elementwise1
    double (*eval2)(double, double);  // Elementwise2 / Nary fold
    const char* glsl;           // GLSL function
};

const std::vector<BuiltinInfo>& builtins();
std::optional<int> find_builtin(std::string_view name);
inline const BuiltinInfo& builtin(int id) { return builtins()[size_t(id)]; }

// Multi-letter names the language knows without a declaration (built-in functions and the reserved
// inputs `time` and `mouse`), so the parser does not split them into letters.
std::vector<std::string> known_names();

// Modules made only of built-ins (e.g. `trigonometry`), for import checking.
bool is_builtin_module(std::string_view name);

// Result type of applying built-in `id` to the argument types, or an error message.
struct BuiltinCheck {
    Type type;
    std::string error;  // non-empty on failure
    int bad_arg = -1;   // argument the error is about, if any
};
BuiltinCheck check_builtin(int id, const std::vector<Type>& args);

}  // namespace iqc
