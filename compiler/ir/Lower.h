// Lowering: checked AST -> IR functions.
//
// Requires a module that checked without errors. A shape, material or transform module becomes one IR
// function whose parameters are the module's free parameters (in declaration order) and whose result is
// its primary output (D, C, or the bare expression); every assigned name is recorded as an output. Local
// and imported functions become functions of their own (once each), with any module values they use
// passed as extra parameters. n-ary min/max become chains, integer powers become products (GLSL's pow is
// undefined for negative bases), and scalars that meet vectors in built-ins are broadcast explicitly.
#pragma once

#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "ir/IR.h"
#include "sema/Check.h"

namespace iqc {

struct LowerContext {
    ir::Module& module;
    // (module, local function, argument types) -> IR index: a function with symbolic sizes (ℝ^n) gets one
    // IR function per combination of sizes it is used with.
    std::map<std::tuple<const CheckedModule*, int, std::vector<Type>>, int> functions;
    std::map<const CheckedModule*, int> modules;  // whole modules (shapes, materials), lowered once
};

// Returns the index of the new function in ctx.module.
int lower_module(const CheckedModule& m, const std::string& name, const std::string& glsl_name, LowerContext& ctx);
// The module's function under its own name, lowered once per context (instances and imports share it).
int lower_module_cached(const CheckedModule& m, LowerContext& ctx);

// What range analysis may assume about the module's parameters: their slider bounds, except for what the
// renderer binds (the roles, a material's `P_L` and `C_L`), which are inputs.
std::vector<ir::ValueBounds> parameter_bounds(const CheckedModule& m);

}  // namespace iqc
