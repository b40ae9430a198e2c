// GLSL backend for IR functions.
//
// Emits one GLSL function per IR function, readably: one statement per named math statement, with the
// math's names and the source statement as a comment (`float D = length(q) - t.y; // D = ‖q‖ - t_2`),
// unnamed values inlined where used once, parentheses rather than precedence tricks, floats always
// with a point. Only what the result needs is emitted (unused outputs cost nothing).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "glsl/Names.h"
#include "ir/IR.h"

namespace iqc::glsl {

// GLSL type for an IR type ("float", "vec3", "mat4", "mat4x3"); empty when GLSL has none (error text in *why).
std::string type_name(const Type& t, std::string* why = nullptr);
// A float literal that always has a point: 1.0, 0.5, -2.25, 1.0e-05.
std::string float_literal(double v);
// A constant of type t from row-major components: 0.5, vec3(1.0, 0.0, 0.0), mat3(...) (column-major).
std::string constant(const Type& t, const std::vector<double>& row_major);

class Emitter {
public:
    // Function names are drawn from `globals`, so they never collide with other global names.
    Emitter(const ir::Module& m, Namer& globals, Diagnostics& diags) : m_(m), globals_(globals), diags_(diags) {}

    // The GLSL name of function `fn` (assigned on first use).
    const std::string& function_name(int fn);
    // `fn` and every function it calls, callees first, each once.
    std::vector<int> closure(const std::vector<int>& roots) const;
    // The GLSL definition of `fn`, with a leading comment line when `comment` is non-empty.
    std::string function(int fn, const std::string& comment = "");

private:
    const ir::Module& m_;
    Namer& globals_;
    Diagnostics& diags_;
    std::map<int, std::string> names_;
};

}  // namespace iqc::glsl
