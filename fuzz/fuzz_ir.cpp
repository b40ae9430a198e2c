// libFuzzer harness: a module that checks is lowered to IR and run through the pass pipeline the compiler
// uses (ir/Pipeline.h: inline, fold, cse, ranges with guards, simplify, dce) with the IR verified before and
// after every pass, and a shape's distance differentiated as analytic normals do; then evaluated in double
// precision (with a small step budget) and printed as GLSL. An internal error or a crash is a bug (abort);
// diagnostics are fine.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "glsl/Emit.h"
#include "ir/Eval.h"
#include "ir/Lower.h"
#include "ir/Pipeline.h"
#include "ir/passes/Differentiate.h"
#include "FuzzModule.h"
#include "source/Internal.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace iqc;
    fuzz::FuzzModule f(data, size);
    auto m = f.lib.parse_check(f.src, "fuzz", false);
    if (!m->ok || f.diags.has_errors()) return 0;
    try {
        ir::Module irm;
        LowerContext ctx{irm, {}, {}};
        int fn = lower_module(*m, "fuzz", "fuzz", ctx);
        irm.functions[size_t(fn)].entry = true;
        int query = m->find_param("p");
        if (m->ast.kind == ast::ModuleKind::Shape && query >= 0 && m->params[size_t(query)].type == Type::vector(3)) {
            std::string why;
            int g = ir::differentiate(irm, fn, query, "fuzz_gradient", &why);
            if (g >= 0) irm.functions[size_t(g)].entry = true;
        }
        ir::PipelineOptions po;
        po.verify_each = true;
        ir::run_pipeline(irm, po);
        fn = irm.find("fuzz");
        if (fn < 0) return 0;
        std::vector<ir::Value> args;
        for (const auto& p : m->params) args.push_back({p.type, p.value});
        ir::EvalInputs inputs;
        inputs.max_steps = 200000;
        try {
            ir::evaluate(irm, fn, args, inputs);
        } catch (const ir::EvalLimit&) {
        }
        glsl::Namer globals;
        glsl::Emitter emitter(irm, globals, f.diags);
        std::string code;
        for (int f : emitter.closure({fn})) code += emitter.function(f);
        return code.size() == size_t(-1);
    } catch (const ir::SizeLimit&) {
        return 0;  // code past the IR size limit: the compiler reports it as a located error (exit 1)
    } catch (const InternalError& e) {
        std::fprintf(stderr, "internal error: %s\n", e.what());
        std::abort();
    }
}
