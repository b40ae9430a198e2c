// GLSL backend for IR functions.
//
// Emits one GLSL function per IR function, readably: one statement per named math statement, with the
// math's names and the source statement as a comment (`float D = length(q) - t.y; // D = ‖q‖ - t_2`),
// unnamed values inlined where used once, parentheses rather than precedence tricks, floats always
// with a point. Only what the result needs is emitted (unused outputs cost nothing). The lazy `If` and
// `Switch` become if-blocks holding exactly what their arms need (ir/Schedule.h); a Switch is a flat
// sequence of ifs, never a nested chain (llvmpipe stops tracking execution masks past ~80 nested ifs).
// ℤ values are GLSL ints, converted with float() where they meet real numbers.
//
// Globals are read by the names the target's storage gives them (GlobalStorage, decided by the scene
// backend): constants, uniforms, members of uniform blocks (read by their own name), private variables
// written by iqc_prepare, or elements of the data texture (read with `iqc_fetch(texel)`).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "glsl/Names.h"
#include "ir/IR.h"
#include "source/Source.h"

namespace iqc::glsl {

// GLSL type for an IR type ("float", "int", "vec3", "mat4", "mat4x3"; arrays: the element's type); empty
// when GLSL has none (error text in *why).
std::string type_name(const Type& t, std::string* why = nullptr);
// A float literal that always has a point: 1.0, 0.5, -2.25, 1.0e-05.
std::string float_literal(double v);
// A constant of type t from row-major components: 0.5, vec3(1.0, 0.0, 0.0), mat3(...) (column-major), 3 (ℤ),
// true; arrays: float[2](1.0, 2.0).
std::string constant(const Type& t, const std::vector<double>& row_major);
// The same, compact (no spaces, whole numbers without a point inside constructors): for large tables.
std::string compact_constant(const Type& t, const std::vector<double>& row_major);

// Where a global lives on the target.
struct GlobalStorage {
    enum class Kind { Const, Uniform, BlockMember, Private, Texture } kind = Kind::Const;
    std::string name;  // its GLSL name (Texture: the function that gathers a whole array, `name()`, where one is read whole)
    int texel = 0;     // Texture: the texel of element 0's first column
    int texels = 1;    // Texture: texels per element (one per matrix column)
};

// Element k (a GLSL int expression; `k_const` when a literal) of type t (a scalar, ℤ, vector or matrix GLSL
// has) stored in the data texture at s: `iqc_fetch(texel).xyz`, a matrix from one texel per column.
std::string texture_fetch(const GlobalStorage& s, const Type& t, const std::string& k, bool k_const);

class Emitter {
public:
    // Function names are drawn from `globals`, so they never collide with other global names. `storage`
    // has one entry per module global (it may be empty for modules without globals).
    Emitter(const ir::Module& m, Namer& globals, Diagnostics& diags, const std::vector<GlobalStorage>* storage = nullptr)
        : m_(m), globals_(globals), diags_(diags), storage_(storage) {}

    // The GLSL name of function `fn` (assigned on first use).
    const std::string& function_name(int fn);
    // Fixes the GLSL name of a function the runtime calls by that name (before any other naming).
    void set_function_name(int fn, const std::string& name);
    // `fn` and every function it calls, callees first, each once.
    std::vector<int> closure(const std::vector<int>& roots) const;
    // The GLSL definition of `fn`, with a leading comment line when `comment` is non-empty.
    std::string function(int fn, const std::string& comment = "");
    // `void NAME() { ... }` assigning each output of `fn` (a function without parameters) to the private
    // global of the same name (iqc_prepare).
    std::string procedure(int fn, const std::string& comment = "");

    const std::vector<GlobalStorage>* storage() const { return storage_; }

    // llvmpipe ends a shader invocation after 65,535 loop iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS: one
    // counter for every loop, whether its lanes are active or not). Counts the loop iterations one call of each
    // root makes, and where the rolled sums' loops (ir::Function::rolled_sum) make more than the budget (60,000
    // over `evaluations`, less the other loops' iterations), unrolls them further, down to no loop at all. A trial's 30 instances with two 40-point
    // sums each made 2,400 per evaluation and drew blocks of the blobs wrong after ~27. Other loops (groups of
    // instances, recurrences) keep their unrolling unless they alone pass the budget: then each runs its share of
    // it, up to 32 iterations a trip (60 group members marched with 2,048 steps drew blocks). Call before emitting.
    // `evaluations`: how many times a pixel's invocation calls the roots at most (0: unknown, kSumLoopBudget
    // iterations per call are kept).
    void limit_loop_iterations(const std::vector<int>& roots, double evaluations = 0);
    // How many iterations a loop of `trips` trips over body `body_fn` runs per trip.
    int unroll_of(int body_fn, long long trips) const;

private:
    const ir::Module& m_;
    Namer& globals_;
    Diagnostics& diags_;
    const std::vector<GlobalStorage>* storage_;
    std::map<int, std::string> names_;
    std::map<int, int> unroll_;  // rolled sums' bodies -> iterations per trip, where limit_loop_iterations chose
};

}  // namespace iqc::glsl
