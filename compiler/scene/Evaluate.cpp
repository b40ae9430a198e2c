#include "scene/Evaluate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "ir/Lower.h"
#include "ir/Pipeline.h"
#include "scene/Modules.h"
#include "scene/Scene.h"

namespace iqc {

namespace fs = std::filesystem;

namespace {

void report_eval_limit(Diagnostics& d, const ir::EvalLimit& limit) {
    d.error(limit.span, fmt::format("evaluating this would take more than {} steps: a recurrence or sum too large to "
                                    "evaluate (iqc eval stops there)", limits::kMaxEvalSteps));
}

// Evaluates a value such as `3`, `-0.5`, `(1, 2, 3)`, `[1 2; 3 4]` or `√2` (any constant expression); `where`:
// the value's text as a file of its own ("--set NAME"), for diagnostics about it.
bool parse_value(const std::string& name, const std::string& text, SourceManager& sm, Diagnostics& d, ir::Value& out, Span& where) {
    const FileId f = FileId(sm.size());  // evaluate_constant adds the value's text first
    auto v = ModuleLibrary::evaluate_constant(fmt::format("--set {}", name), text, sm, d);
    if (!v) return false;
    where = {f, 0, uint32_t(std::max<size_t>(1, text.size()))};
    out = std::move(*v);
    return true;
}

}  // namespace

namespace {
bool evaluate_checked(const EvalRequest& req, SourceManager& sm, Diagnostics& d, std::vector<EvalOutput>& out);
}

bool evaluate_module_file(const EvalRequest& req, SourceManager& sm, Diagnostics& d, std::vector<EvalOutput>& out) {
    try {
        return evaluate_checked(req, sm, d, out);
    } catch (const ir::SizeLimit& limit) {
        if (limit.span.valid()) d.error(limit.span, ir::size_limit_message());
        else d.error_nospan(ir::size_limit_message());
        return false;
    }
}

namespace {
bool evaluate_checked(const EvalRequest& req, SourceManager& sm, Diagnostics& d, std::vector<EvalOutput>& out) {
    size_t before = d.error_count();
    auto clock = std::chrono::steady_clock::now();
    auto lap = [&](const char* name) {
        auto now = std::chrono::steady_clock::now();
        if (req.timings) req.timings->push_back({name, std::chrono::duration<double, std::milli>(now - clock).count()});
        clock = now;
    };
    std::string ext = fs::path(req.path).extension().string();
    SceneDesc scene;
    std::string dir = fs::path(req.path).parent_path().string();
    ModuleLibrary lib(sm, d, {dir});
    std::string name = req.module;
    if (ext == ".md" || ext == ".iq" || ext == ".toml") {
        if (!load_scene(req.path, sm, d, scene) && scene.modules.empty()) return false;
        // Problems in the scene part do not matter for evaluating a module: keep only module errors.
        for (const auto& m : scene.modules) lib.add(m);
        if (name.empty()) {
            if (scene.modules.empty()) {
                std::set<std::string> types;
                for (const auto& inst : scene.instances) types.insert(inst.type);
                d.error({scene.file, 0, 1},
                        types.empty() ? fmt::format("'{}' defines no modules to evaluate", req.path)
                                      : fmt::format("'{}' defines no modules: its shapes ({}) come from the standard library; "
                                                    "choose one with --module NAME", req.path, fmt::join(types, ", ")));
                return false;
            }
            if (scene.modules.size() != 1) {
                std::vector<std::string> names;
                for (auto& m : scene.modules) names.push_back(m.name);
                d.error_nospan(fmt::format("'{}' defines {} modules: choose one with --module ({})", req.path,
                                           scene.modules.size(), fmt::join(names, ", ")));
                return false;
            }
            name = scene.modules[0].name;
        }
    } else {
        std::string text;
        ModuleSource ms;
        SceneDesc tmp;
        std::string err;
        if (!read_source_file(req.path, sm.total_bytes(), text, err)) {
            d.error_nospan(fmt::format("cannot read '{}': {}", req.path, err));
            return false;
        }
        ms.file = sm.add_from_disk(req.path, std::move(text));
        ms.name = name.empty() ? fs::path(req.path).stem().string() : name;
        ms.ranges = {{0, uint32_t(sm.text(ms.file).size())}};
        ms.where = {ms.file, 0, 1};
        ms.origin = "module file";
        scene.modules.push_back(ms);
        lib.add(scene.modules.back());
        name = ms.name;
    }
    lap("read");
    // The values set from the command line first: their types bind symbolic sizes (v ∈ ℝ^n).
    std::map<std::string, ir::Value> given;
    std::map<std::string, Type> given_types;
    std::map<std::string, std::shared_ptr<const ast::Module>> given_functions;
    std::map<std::string, Span> given_spans;  // each value's text (`--set NAME:1:1`)
    for (const auto& [sname, stext] : req.sets) {
        if (size_t paren = sname.find('('); paren != std::string::npos) {  // f(x)=x²: a function parameter's definition
            std::string text = sname + " = " + stext;
            FileId ff = sm.add(fmt::format("--set {}", sname), text);
            ModuleSource fs{"value", ff, {{0, uint32_t(text.size())}}, {ff, 0, 1}, "value"};
            std::string fname = sname.substr(0, paren);
            if (fname.size() > 2 && fname.front() == '`' && fname.back() == '`') fname = fname.substr(1, fname.size() - 2);
            given_functions[fname] = lib.parse_function(fs);
            continue;
        }
        ir::Value v;
        Span where;
        if (!parse_value(sname, stext, sm, d, v, where)) continue;
        given[sname] = v;
        given_spans[sname] = where;
        given_types[sname] = v.type;
    }
    if (d.error_count() != before) return false;
    std::unique_ptr<CheckedModule> checked = lib.check_with(name, given_types, given_functions);
    lap("lex + parse + check");
    const CheckedModule* m = checked.get();
    if (!m) {
        d.error_nospan(fmt::format("no module named '{}' in '{}'", name, req.path));
        return false;
    }
    if (!m->ok || d.error_count() != before) return false;
    std::vector<ir::Value> args;
    for (const auto& p : m->params) args.push_back({p.type, p.value});
    for (const auto& [sname, v] : given) {
        int pi = m->find_param(sname);
        if (pi < 0) {
            std::vector<std::string> cands;
            for (const auto& p : m->params) cands.push_back(p.name);
            std::string msg = fmt::format("the module has no parameter '{}'", sname);
            if (auto s = did_you_mean(sname, cands)) msg += fmt::format(" (did you mean '{}'?)", *s);
            else if (!cands.empty()) msg += fmt::format(" (its parameters: {})", fmt::join(cands, ", "));
            d.error(given_spans[sname], msg);
            continue;
        }
        const Type& want = m->params[size_t(pi)].type;
        if (v.type != want && !(want.is_scalar() && v.type.is_scalar())) {
            d.error(given_spans[sname], fmt::format("'{}' is {}, but the value is {}", sname, want.str(), v.type.str()));
            continue;
        }
        if (want.kind == Type::Integer && v.v[0] != std::floor(v.v[0])) {
            d.error(given_spans[sname], fmt::format("'{}' is ℤ, but the value {} is not a whole number", sname, v.v[0]));
            continue;
        }
        if (want.kind == Type::Integer && !limits::is_int32(v.v[0])) {
            d.error(given_spans[sname], fmt::format("'{}' is ℤ, but the value {} is not a 32-bit integer (a shader's int: "
                                                    "-2147483648 … 2147483647)", sname, v.v[0]));
            continue;
        }
        // As a scene's override is: a value past the sliders is evaluated, and warned (the guards range analysis
        // proved hold within the bounds only). It was silent here (a new user's trial).
        const auto& par = m->params[size_t(pi)];
        if (int i = par.outside_bounds(v.v); i >= 0) d.warning(given_spans[sname], par.outside_bounds_message(v.v, i, sname));
        args[size_t(pi)] = {want, v.v};
    }
    if (d.error_count() != before) return false;
    ir::Module irm;
    LowerContext ctx{irm, {}, {}};
    int fn = lower_module(*m, name, name, ctx);
    irm.functions[size_t(fn)].entry = true;
    lap("lower to IR");
    ir::PipelineOptions po;
    po.inject_fault = req.inject_fault;
    ir::PipelineResult pr = ir::run_pipeline(irm, po);
    for (const auto& w : pr.range_issues) d.warning(w.span, w.message);
    fn = irm.find(name);
    lap("pass pipeline");
    std::vector<ir::Value> all;
    try {
        all = ir::evaluate_all(irm, fn, args, req.inputs);
    } catch (const ir::EvalLimit& limit) {
        report_eval_limit(d, limit);
        return false;
    }
    lap("evaluate");
    const ir::Function& F = irm.functions[size_t(fn)];
    // Outputs in source order.
    std::vector<std::pair<uint32_t, EvalOutput>> ordered;
    for (const auto& [oname, v] : F.outputs) ordered.push_back({F.body[v].span.begin, {oname, all[v]}});
    std::stable_sort(ordered.begin(), ordered.end(), [](auto& a, auto& b) { return a.first < b.first; });
    for (auto& o : ordered) out.push_back(std::move(o.second));
    if (m->ret) out.push_back({"ret", all[F.result]});
    return true;
}

}  // namespace

}  // namespace iqc
