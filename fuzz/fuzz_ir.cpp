// libFuzzer harness: a module that checks is lowered to IR and run through the pass pipeline the compiler
// uses (ir/Pipeline.h: inline, fold, cse, ranges with guards, simplify, dce) with the IR verified before and
// after every pass, and a shape's distance differentiated as analytic normals do; then evaluated in double
// precision (with a small step budget) and printed as GLSL; a shape's interval extension over a box (segment
// tracing's bounds) is checked to hold the distance at the box's centre. An internal error or a crash is a bug (abort);
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
#include "ir/passes/IntervalExtension.h"
#include "ir/Builder.h"
#include <cmath>
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
        // The interval extension (segment tracing's bounds) of a shape's distance over a box around its
        // origin holds the distance at the box's centre (ir/passes/IntervalExtension.h).
        bool valued = true;  // every other parameter has a value of its type (a constant of the extension)
        for (size_t k = 0; k < m->params.size(); ++k)
            valued &= int(k) == query || int(m->params[k].value.size()) == std::max(1, m->params[k].type.components());
        if (valued && m->ast.kind == ast::ModuleKind::Shape && query >= 0 && m->params[size_t(query)].type == Type::vector(3)) {
            ir::Function e;
            e.name = "fuzz_box";
            ir::Builder b(irm, e);
            ir::ValueId lo = b.param("lo", Type::vector(3)), hi = b.param("hi", Type::vector(3));
            std::vector<ir::ValueId> others;
            for (size_t k = 0; k < m->params.size(); ++k)
                others.push_back(int(k) == query ? lo : b.constant(m->params[k].type, m->params[k].value));
            ir::IntervalCode c = ir::emit_interval_extension(b, irm, fn, query, lo, hi, others);
            if (c.ok && irm.functions[size_t(fn)].result_type() == Type::scalar()) {
                e.result = b.construct(Type::vector(2), {c.lo, c.hi});
                irm.functions.push_back(std::move(e));
                std::string fault = ir::verify(irm);
                if (!fault.empty()) internal_error("interval extension: " + fault);
                int box = int(irm.functions.size()) - 1;
                std::vector<ir::Value> at = args;
                at[size_t(query)] = {Type::vector(3), {0.1, 0.2, 0.3}};
                try {
                    ir::EvalInputs small;
                    small.max_steps = 200000;
                    ir::Value v = ir::evaluate(irm, fn, at, small);
                    ir::Value r = ir::evaluate(irm, box, {{Type::vector(3), {-0.4, -0.3, -0.2}}, {Type::vector(3), {0.6, 0.7, 0.8}}}, small);
                    double slack = 1e-9 * (1 + std::fabs(v.v[0]));
                    if (std::isfinite(v.v[0]) && !(r.v[0] <= v.v[0] + slack && r.v[1] >= v.v[0] - slack) &&
                        !std::isnan(r.v[0]) && !std::isnan(r.v[1]))
                        internal_error("interval extension: the distance at the box's centre lies outside its interval");
                } catch (const ir::EvalLimit&) {
                }
            }
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
