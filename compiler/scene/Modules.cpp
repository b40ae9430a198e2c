#include "scene/Modules.h"

#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <regex>
#include <filesystem>
#include <fmt/format.h>

#include "resources/Embedded.h"
#include "sema/Hints.h"
#include "source/Limits.h"
#include "ir/Lower.h"
#include "ir/Pipeline.h"
#include "sema/Builtins.h"
#include "source/Limits.h"
#include "syntax/Parser.h"

namespace iqc {

namespace fs = std::filesystem;

const std::vector<std::pair<std::string, std::string>>& ModuleLibrary::transform_imports() {
    static const std::vector<std::pair<std::string, std::string>> v = {
        {"T", "transformations"}, {"R_x", "transformations"}, {"R_y", "transformations"},
        {"R_z", "transformations"}, {"S", "transformations"}};
    return v;
}

void ModuleLibrary::add(const ModuleSource& m) {
    auto it = registry_.find(m.name);
    if (it != registry_.end()) {
        auto& e = d_.error(m.where, fmt::format("module '{}' is defined twice", m.name));
        Diagnostics::note(e, it->second->where, fmt::format("also defined here ({})", it->second->origin));
        return;
    }
    registry_[m.name] = &m;
}

bool ModuleLibrary::is_file_name(const std::string& name) {
    if (name.empty() || name.size() > 200 || name[0] == '.') return false;
    for (char c : name)
        if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7F) return false;
    return true;
}

const ModuleSource* ModuleLibrary::find_source(const std::string& name, Span where) {
    if (auto it = registry_.find(name); it != registry_.end()) return it->second;
    if (!is_file_name(name)) return nullptr;  // never a path: `type = "../x"` finds nothing
    auto own = [&](std::unique_ptr<ModuleSource> ms) {
        registry_[name] = ms.get();
        owned_.push_back(std::move(ms));
        return owned_.back().get();
    };
    for (const auto& dir : dirs_) {
        fs::path p = fs::path(dir) / (name + ".iql");
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) continue;
        std::string text, err;
        if (!read_source_file(p.string(), sm_.total_bytes(), text, err)) {
            std::string msg = fmt::format("cannot read module file '{}': {}", p.string(), err);
            if (where.valid()) d_.error(where, msg);
            else d_.error_nospan(msg);
            return nullptr;
        }
        auto ms = std::make_unique<ModuleSource>();
        ms->name = name;
        ms->file = sm_.add_from_disk(p.string(), std::move(text));
        ms->ranges = {{0, uint32_t(sm_.text(ms->file).size())}};
        ms->where = {ms->file, 0, 1};
        ms->origin = "module file";
        return own(std::move(ms));
    }
    std::string path = "stdlib/" + name + ".iql";
    auto text = embedded_file(path);
    if (!text) return nullptr;
    auto ms = std::make_unique<ModuleSource>();
    ms->name = name;
    ms->file = sm_.add(path, std::string(*text));
    ms->ranges = {{0, uint32_t(text->size())}};
    ms->where = {ms->file, 0, 1};
    ms->origin = "stdlib";
    return own(std::move(ms));
}

std::vector<std::string> ModuleLibrary::names() const {
    std::vector<std::string> names;
    for (auto& [n, m] : registry_) names.push_back(n);
    for (std::string& n : library_module_names()) names.push_back(std::move(n));
    for (const auto& dir : dirs_) {
        std::error_code ec;
        for (auto& e : fs::directory_iterator(dir, ec))
            if (e.path().extension() == ".iql") names.push_back(e.path().stem().string());
    }
    return names;
}

std::unique_ptr<CheckedModule> ModuleLibrary::check_with(const std::string& name,
                                                        const std::map<std::string, Type>& given_types,
                                                        const std::map<std::string, std::shared_ptr<const ast::Module>>& given_functions) {
    const ModuleSource* src = find_source(name, {});
    if (!src) return nullptr;
    auto m = parse_check(*src, name, false, given_types, given_functions);
    m->ast.span = src->where;
    return m;
}

const CheckedModule* ModuleLibrary::variant(const std::string& name, const std::map<std::string, int>& lengths) {
    auto key = std::make_pair(name, lengths);
    if (auto it = variants_.find(key); it != variants_.end()) return it->second.get();
    const CheckedModule* base = get(name, {});
    if (!base) return nullptr;
    std::map<std::string, Type> given;
    std::string suffix;
    for (const auto& [param, n] : lengths) {
        int pi = base->find_param(param);
        if (pi < 0 || !base->params[size_t(pi)].type.is_array()) continue;
        given[param] = Type::array(base->params[size_t(pi)].type.element(), n);
        suffix += fmt::format("_{}{}", param, n);
    }
    std::unique_ptr<CheckedModule> m = check_with(name, given);
    if (!m) return nullptr;
    m->ir_name = name + suffix;
    return variants_.emplace(key, std::move(m)).first->second.get();
}

std::shared_ptr<const ast::Module> ModuleLibrary::parse_function(const ModuleSource& src) {
    ParseOptions po;
    for (const auto& n : known_names()) po.known_names.insert(n);
    po.allow_header = false;
    return std::make_shared<const ast::Module>(parse_module(sm_, src.file, src.ranges, src.name, po, d_));
}

std::optional<ir::Value> ModuleLibrary::evaluate_constant(const std::string& name, const std::string& text, SourceManager& sm,
                                                         Diagnostics& d) {
    FileId f = sm.add(name, text);
    ModuleSource src;
    src.name = "value";
    src.file = f;
    src.ranges = {{0, uint32_t(text.size())}};
    src.where = {f, 0, 1};
    ModuleLibrary lib(sm, d);
    size_t before = d.error_count();
    lib.constants_ = true;
    auto m = lib.parse_check(src, "value", false);
    if (d.error_count() != before) return std::nullopt;
    if (m->ast.stmts.size() != 1 || !m->ast.decls.empty()) {
        // `(2,0,0);r=0.5`, a value and then more (the rest would be ignored), or a declaration `x ∈ ℝ` (no value).
        Span at{f, 0, uint32_t(std::max<size_t>(1, text.size()))};
        if (m->ast.stmts.size() > 1) {
            const ast::Stmt& extra = m->ast.stmts[1];
            if (extra.name_span.end > extra.name_span.begin) at = extra.name_span;
            else if (extra.value) at = extra.value->span;
        } else if (!m->ast.decls.empty() && m->ast.decls[0].span.end > m->ast.decls[0].span.begin) {
            at = m->ast.decls[0].span;
        }
        d.error(at, m->ast.stmts.empty()
                        ? fmt::format("the value of '{}' must be an expression: a number, a vector (1, 2, 3), a matrix [1 2; 3 4] "
                                      "or a sequence {{(1, 2), (3, 4)}}, not a declaration", name)
                        : fmt::format("the value of '{}' must be one expression; this is more (set each name with its own option)", name));
        return std::nullopt;
    }
    if (!m->ret || !m->params.empty() || !(m->primary_type.is_numeric() || m->primary_type.is_array())) {
        d.error({f, 0, uint32_t(std::max<size_t>(1, text.size()))},
                fmt::format("the value of '{}' must be a number, a vector (1, 2, 3), a matrix [1 2; 3 4] or a sequence "
                            "{{(1, 2), (3, 4)}}", name));
        return std::nullopt;
    }
    ir::Module irm;
    try {
        LowerContext ctx{irm, {}, {}};
        int fn = lower_module(*m, "value", "value", ctx);
        irm.functions[size_t(fn)].entry = true;
        // time and the mouse are inputs, not constants: evaluated here they were 0, so `default = time` or
        // shape_params = { r = "time" } became 0 without a word (a new user's trial).
        for (const ir::Function& g : irm.functions)
            for (const ir::Instr& in : g.body)
                if (in.op == ir::Op::Input) {
                    d.error({f, 0, uint32_t(std::max<size_t>(1, text.size()))},
                            fmt::format("the value of '{}' must be a constant: it reads {}, which changes while the shader runs",
                                        name, in.aux == 0 ? "time" : "the mouse"));
                    return std::nullopt;
                }
        ir::run_pipeline(irm, {});
        ir::Value v = ir::evaluate(irm, irm.find("value"), {});
        for (double x : v.v) {
            if (!std::isfinite(x)) {
                d.error({f, 0, uint32_t(std::max<size_t>(1, text.size()))},
                        fmt::format("the value of '{}' is not a finite number ({})", name, ir::format_value(v)));
                return std::nullopt;
            }
            if (!limits::fits_float(x)) {  // like a literal: shaders compute in float (FLT_MAX as printed rounds to it)
                d.error({f, 0, uint32_t(std::max<size_t>(1, text.size()))},
                        fmt::format("the value of '{}' is outside the range of 32-bit floats (at most about 3.4e38), which "
                                    "shaders compute in ({})", name, ir::format_value(v)));
                return std::nullopt;
            }
        }
        return v;
    } catch (const ir::EvalLimit& limit) {
        d.error(limit.span, fmt::format("evaluating this would take more than {} steps", limits::kMaxEvalSteps));
        return std::nullopt;
    } catch (const ir::SizeLimit& limit) {
        d.error({f, 0, uint32_t(std::max<size_t>(1, text.size()))}, ir::size_limit_message());
        return std::nullopt;
    }
}

std::unique_ptr<CheckedModule> ModuleLibrary::parse_check(const ModuleSource& src, const std::string& name, bool transform,
                                                         const std::map<std::string, Type>& given_types,
                                                         const std::map<std::string, std::shared_ptr<const ast::Module>>& given_functions) {
    ParseOptions po;
    for (const auto& n : known_names()) po.known_names.insert(n);
    CheckOptions co;
    co.given_types = given_types;
    co.given_functions = given_functions;
    if (constants_) {  // a constant may use the trigonometric functions without importing them
        for (const auto& b : builtins())
            if (std::string(b.module) == "trigonometry") {
                co.implicit_imports.push_back({b.name, "trigonometry"});
                po.known_names.insert(b.name);  // cot, asinh: names after an import
            }
    } else {
        // Defaults and bounds that need more than folding: the evaluator, on a scratch source.
        co.constant = [this](const ast::Expr& e) -> std::optional<std::vector<double>> {
            SourceManager scratch;
            Diagnostics quiet(scratch);  // not a constant: the checker reports it where it is
            auto v = evaluate_constant("constant", std::string(sm_.slice(e.span)), scratch, quiet);
            if (!v) return std::nullopt;
            return v->v;
        };
    }
    if (transform) {
        po.allow_header = false;
        for (auto& [n, mod] : transform_imports()) po.known_names.insert(n);
        co.implicit_imports = transform_imports();
    }
    size_t before = d_.error_count();
    ast::Module ast = parse_module(sm_, src.file, src.ranges, name, po, d_);
    if (!src.ranges.empty()) ast.span = {src.file, src.ranges[0].begin, src.ranges[0].begin + 1};
    ModuleLookup lookup = [this](const std::string& n, Span where) { return get(n, where); };
    auto m = check_module(std::move(ast), lookup, co, d_);
    if (d_.error_count() != before) m->ok = false;  // syntax errors too
    // Pragmas in comment lines, each said once: `# exact` (a true distance, so 1-Lipschitz) excludes `# bound`
    // and `# lipschitz: K`; `# bound` with `# lipschitz: K` is a K-Lipschitz bound.
    std::map<std::string, Span> said;
    auto pragma = [&](Span at, const std::string& kind) {
        const char* clash = nullptr;
        if (said.count(kind)) clash = kind.c_str();
        else if (kind == "exact" && said.count("bound")) clash = "bound";
        else if (kind == "exact" && said.count("lipschitz")) clash = "lipschitz";
        else if ((kind == "bound" || kind == "lipschitz") && said.count("exact")) clash = "exact";
        if (clash) {
            auto& e = d_.error(at, kind == clash ? fmt::format("'# {}' is said twice in this module", kind)
                                                 : fmt::format("'# {}' contradicts '# {}': an exact distance is 1-Lipschitz and not "
                                                               "only a bound (say `# bound` with `# lipschitz: K` for a K-Lipschitz bound)",
                                                               kind, clash));
            Diagnostics::note(e, said[clash], "said here first");
            return false;
        }
        said[kind] = at;
        return true;
    };
    for (const auto& r : src.ranges) {
        std::string_view text = sm_.text(src.file).substr(r.begin, r.end - r.begin);
        size_t pos = 0;
        while (pos < text.size()) {
            size_t eol = text.find('\n', pos);
            if (eol == std::string_view::npos) eol = text.size();
            std::string_view line = text.substr(pos, eol - pos);
            size_t h = line.find_first_not_of(" \t");
            if (h != std::string_view::npos && line[h] == '#') {
                std::string_view body = line.substr(h + 1);
                while (!body.empty() && body.front() == ' ') body.remove_prefix(1);
                Span at = {src.file, uint32_t(r.begin + pos + h), uint32_t(r.begin + eol)};
                // The first word of the comment, whole ("# exactly as…" and "# bound (its slope…)" are prose).
                size_t w = 0;
                while (w < body.size() && (std::isalnum(static_cast<unsigned char>(body[w])) || body[w] == '_')) ++w;
                std::string word(body.substr(0, w));
                std::string_view after = body.substr(w);
                // Any case (`# Lipschitz: 5` was prose, so the factor went unused without a word), and a comment of
                // its own after the pragma (`# exact  # Quilez's sdBox`).
                for (char& ch : word) ch = char(std::tolower(static_cast<unsigned char>(ch)));
                if (size_t hash = after.find('#'); hash != std::string_view::npos) after = after.substr(0, hash);
                const size_t c = after.find_first_not_of(" \t\r");  // what follows the word: nothing, a colon, prose
                const bool colon = c != std::string_view::npos && after[c] == ':';
                uint32_t after_at = uint32_t(r.begin + (after.data() - text.data()));
                if (word == "exact" || word == "bound") {
                    // Alone on its line; a value after a colon is a mistake worth saying ("# bound: 3").
                    if (c == std::string_view::npos) {
                        if (pragma(at, word)) m->exactness = word;
                    } else if (colon) {
                        d_.error({src.file, after_at, uint32_t(after_at + after.size())},
                                 fmt::format("'# {}' takes no value (a K-Lipschitz bound is '# bound' on one line and "
                                             "'# lipschitz: K' on another)", word));
                    }
                } else if (word == "lipschitz" && (colon || body.substr(0, w) == "lipschitz")) {
                    // Lower case, or any case with a colon: `# Lipschitz factors: …` is prose.
                    // `# lipschitz: K`, K a decimal number (digits, a point, an exponent) and nothing else on the line:
                    // "1/0.3" read as 1 and "1_000" as 1 made marching unsafe (a new user's trial).
                    std::string_view v = colon ? after.substr(c + 1) : std::string_view();
                    size_t v0 = v.find_first_not_of(" \t");
                    v = v0 == std::string_view::npos ? std::string_view() : v.substr(v0);
                    while (!v.empty() && (v.back() == ' ' || v.back() == '\t' || v.back() == '\r')) v.remove_suffix(1);
                    static const std::regex number(R"(([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?)");
                    bool ok = !v.empty() && std::regex_match(v.begin(), v.end(), number);
                    double k = ok ? std::strtod(std::string(v).c_str(), nullptr) : 0;
                    Span vat = v.empty() ? at : Span{src.file, uint32_t(r.begin + (v.data() - text.data())),
                                                        uint32_t(r.begin + (v.data() - text.data()) + v.size())};
                    if (!colon)
                        d_.error(at, "a Lipschitz pragma is written '# lipschitz: K' (a colon, then the number K ≥ 1)");
                    else if (!ok && !v.empty())
                        d_.error(vat, fmt::format("'# lipschitz: K' needs a decimal number K ≥ 1 (how much D can change per unit "
                                                  "of distance, e.g. 2.5 or 1e3), not '{}'", escape_controls(std::string(v))));
                    else if (!(k >= 1) || !limits::fits_float(k))
                        d_.error(vat, "'# lipschitz: K' needs a number K ≥ 1 (how much D can change per unit of distance), within "
                                      "32-bit floats (at most about 3.4e38)");
                    else if (pragma(at, "lipschitz"))
                        m->lipschitz = k, m->lipschitz_declared = true;
                }
            }
            pos = eol + 1;
        }
    }
    return m;
}

const CheckedModule* ModuleLibrary::get(const std::string& name, Span where) {
    if (auto it = checked_.find(name); it != checked_.end()) return it->second.get();
    if (in_progress_.count(name)) {
        d_.error(where, fmt::format("module '{}' imports itself (an import cycle)", name));
        return nullptr;
    }
    const ModuleSource* src = find_source(name, where);
    if (!src) return nullptr;
    if (in_progress_.size() >= size_t(limits::kMaxImportDepth)) {
        d_.error(where, fmt::format("module '{}' is imported through more than {} nested imports", name,
                                    limits::kMaxImportDepth));
        return nullptr;
    }
    in_progress_.insert(name);
    auto m = parse_check(*src, name, false);
    in_progress_.erase(name);
    m->ast.span = src->where;
    return (checked_[name] = std::move(m)).get();
}

}  // namespace iqc
