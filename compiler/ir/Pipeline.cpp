#include "ir/Pipeline.h"

#include <chrono>
#include <fmt/format.h>
#include <functional>

#include "ir/passes/CSE.h"
#include "ir/passes/DCE.h"
#include "ir/passes/Differentiate.h"
#include "ir/passes/Fold.h"
#include "ir/passes/Inline.h"
#include "ir/passes/Lipschitz.h"
#include "ir/passes/MergeCalls.h"
#include "ir/passes/Stable.h"
#include "ir/passes/Tables.h"
#include "source/Internal.h"

namespace iqc::ir {

namespace {

void fold_all(Module& m) {
    for (auto& f : m.functions) fold_constants(m, f);
}
void cse_all(Module& m) {
    for (auto& f : m.functions) eliminate_common_subexpressions(f);
}

// iqc_gradient from iqc_distance_of, when the scene asks for analytic normals (it then has both names: the
// scene lowering adds iqc_gradient as a placeholder that this pass fills).
void gradient(Module& m, PipelineResult& r) {
    int dist = m.find(names::kDistanceOf), grad = m.find(names::kGradient);
    if (dist < 0 || grad < 0) return;
    std::string why;
    std::vector<std::pair<Span, std::string>> fallbacks;
    int g = differentiate(m, dist, 0, names::kGradient, &why, &fallbacks);
    if (g < 0) internal_error("gradient: the scene's distance has no derivative rule (" + why + ")");
    for (auto& [span, reason] : fallbacks)
        r.warnings.push_back({span, fmt::format("no analytic normal here ({}): the normals of the shapes that use it come "
                                                "from tetrahedron differences", reason)});
    Function made = std::move(m.functions[size_t(g)]);
    m.functions.pop_back();
    made.entry = m.functions[size_t(grad)].entry;
    if (made.body[made.result].name.empty()) made.body[made.result].name = "g";
    made.glsl_name = m.functions[size_t(grad)].glsl_name;
    m.functions[size_t(grad)] = std::move(made);
}

struct Pass {
    PassInfo info;
    std::function<void(Module&, const PipelineOptions&, PipelineResult&)> run;
};

const std::vector<Pass>& passes() {
    static const std::vector<Pass> list = {
        {{"stable", "stable rewrites of forms that fail in 32-bit floats: log-sum-exp, hypot, 1 - cos"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) {
             for (auto& w : rewrite_unstable_forms(m)) r.rewrites.push_back(std::move(w));
         }},
        {{"lipschitz", "each shape's Lipschitz bound, derived from its gradient; distances divided by it"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) {
             for (auto& w : apply_lipschitz_bounds(m, &r.lipschitz)) r.warnings.push_back(std::move(w));
         }},
        {{"inline", "inline the scene's building blocks into the scene functions"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { inline_marked(m); }},
        {{"tables", "compile-time tables on a lattice become arithmetic on the index"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { compress_tables(m); }},
        {{"fold", "constant folding and algebraic identities"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { fold_all(m); }},
        {{"cse", "common subexpression elimination"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { cse_all(m); }},
        {{"ranges", "range analysis: guards and slider warnings"},
         [](Module& m, const PipelineOptions& o, PipelineResult& r) { r.range_issues = analyze_ranges(m, o.guard_ranges); }},
        {{"gradient", "analytic normals: forward-mode differentiation of the scene distance"},
         [](Module& m, const PipelineOptions&, PipelineResult& r) { gradient(m, r); }},
        {{"calls", "calls to one function from several cases of a switch: one call on switched arguments"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { merge_switch_calls(m); }},
        {{"simplify", "fold and CSE again"},
         [](Module& m, const PipelineOptions&, PipelineResult&) {
             fold_all(m);
             cse_all(m);
         }},
        {{"dce", "dead code: instructions, then unreachable functions and globals"},
         [](Module& m, const PipelineOptions&, PipelineResult&) { eliminate_dead_code(m); }},
    };
    return list;
}

void check(const Module& m, const char* when) {
    std::string fault = verify(m);
    if (!fault.empty()) internal_error(fmt::format("invalid IR {}: {}", when, fault));
}

}  // namespace

const std::vector<PassInfo>& pipeline_passes() {
    static const std::vector<PassInfo> infos = [] {
        std::vector<PassInfo> v;
        for (const auto& p : passes()) v.push_back(p.info);
        return v;
    }();
    return infos;
}

bool is_pass_name(const std::string& name) {
    if (name == "lower") return true;
    for (const auto& p : passes())
        if (name == p.info.name) return true;
    return false;
}

bool run_pass(const std::string& name, Module& m, const PipelineOptions& o, PipelineResult& r) {
    for (const auto& p : passes())
        if (name == p.info.name) {
            p.run(m, o, r);
            return true;
        }
    return false;
}

PipelineResult run_pipeline(Module& m, const PipelineOptions& o) {
    PipelineResult r;
    if (o.verify_each) check(m, "after lowering");
    if (o.dump_after == "lower") r.dump = print(m);
    for (const auto& p : passes()) {
        auto t0 = std::chrono::steady_clock::now();
        if (o.inject_fault == p.info.name) internal_error(fmt::format("{}: injected fault (--inject-fault)", p.info.name));
        p.run(m, o, r);
        if (o.verify_each) check(m, fmt::format("after the {} pass", p.info.name).c_str());
        if (o.dump_after == p.info.name) r.dump = print(m);
        r.pass_ms.push_back({p.info.name, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()});
    }
    if (!o.verify_each) check(m, "after the pipeline");
    return r;
}

}  // namespace iqc::ir
