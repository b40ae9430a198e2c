#include "scene/Compile.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <memory>
#include <set>

#include "glsl/Emit.h"
#include "glsl/ShadertoyWrapper.h"
#include "glsl/Validate.h"
#include "ir/Eval.h"
#include "ir/Lower.h"
#include "ir/passes/CSE.h"
#include "ir/passes/Differentiate.h"
#include "ir/passes/Ranges.h"
#include "scene/Modules.h"
#include "scene/Template.h"
#include "resources/Embedded.h"
#include "sema/Builtins.h"
#include "sema/Check.h"
#include "syntax/Parser.h"

namespace iqc {

namespace {

std::string join_values(const std::vector<double>& v) {
    if (v.size() == 1) return fmt::format("{}", v[0]);
    return fmt::format("({})", fmt::join(v, ", "));
}

// Largest singular value of a 3×3 matrix (row-major): sqrt of the largest eigenvalue of LᵀL (Jacobi).
double spectral_norm3(const std::vector<double>& L) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += L[size_t(k * 3 + i)] * L[size_t(k * 3 + j)];
            a[i][j] = s;
        }
    for (int sweep = 0; sweep < 64; ++sweep) {
        double off = std::fabs(a[0][1]) + std::fabs(a[0][2]) + std::fabs(a[1][2]);
        if (off < 1e-300) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (std::fabs(a[p][q]) < 1e-300) continue;
                double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
                double c = 1 / std::sqrt(t * t + 1), s = t * c;
                // a = Jᵀ a J with the rotation J in the (p, q) plane.
                for (int k = 0; k < 3; ++k) {
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
    }
    return std::sqrt(std::max({a[0][0], a[1][1], a[2][2], 0.0}));
}

struct InstancePlan {
    const InstanceDesc* desc = nullptr;
    std::string name;  // instance name as the user sees it
    std::string glsl;  // its GLSL prefix
    const CheckedModule* shape = nullptr;
    int shape_fn = -1;
    int query = -1;  // index of the shape's query-point parameter
    std::vector<std::vector<double>> shape_values;
    const CheckedModule* material = nullptr;
    int material_fn = -1;
    int roles[3] = {-1, -1, -1};  // material parameters bound to the surface point, normal and eye
    std::vector<std::vector<double>> material_values;
    std::map<std::string, std::string> constants;  // "shape.t" -> GLSL constant or uniform name
    bool has_transform = false;
    std::vector<double> inv_linear, inv_offset;  // world -> object, at the parameters' values
    double scale = 1;                            // 1 / Lipschitz factor of the world -> object map
    std::string transform_comment;
    // A transform evaluated per pixel (its parameters are uniforms, or it uses time or mouse).
    const CheckedModule* transform = nullptr;
    int transform_fn = -1;
    bool transform_runtime = false;
    int gradient_fn = -1;  // analytic normals: the shape's gradient function (-1: differences instead)
};

class SceneCompiler {
public:
    SceneCompiler(const SceneDesc& s, SourceManager& sm, Diagnostics& d, const CompileOptions& o)
        : s_(s), sm_(sm), d_(d), opts_(o) {}
    CompileResult run();

private:
    const SceneDesc& s_;
    SourceManager& sm_;
    Diagnostics& d_;
    const CompileOptions& opts_;
    ModuleLibrary lib_{sm_, d_, {std::filesystem::path(s_.path).parent_path().string()}};
    std::vector<std::unique_ptr<CheckedModule>> transforms_;
    ir::Module ir_;
    LowerContext lower_{ir_, {}};

    bool plan_instance(const InstanceDesc& inst, InstancePlan& plan, std::map<std::string, int>& counts,
                       std::set<std::string>& names, const std::set<std::string>& explicit_names);
    bool apply_overrides(const std::vector<ParamOverride>& ovs, const CheckedModule& m, const char* role,
                         const std::vector<int>& bound, std::vector<std::vector<double>>& values);
    bool plan_transform(const InstanceDesc& inst, InstancePlan& plan);
    int lower(const CheckedModule* m);
    bool uses_inputs(int fn) const;
    std::string assemble(std::vector<InstancePlan>& plans, std::string& meta);
    std::vector<std::pair<std::string, std::vector<double>>> uniform_defaults_;
    double bound_margin_ = 0.1;  // IQC_BOUND_MARGIN, when an instance has `bound`
};

bool SceneCompiler::apply_overrides(const std::vector<ParamOverride>& ovs, const CheckedModule& m, const char* role,
                                    const std::vector<int>& bound, std::vector<std::vector<double>>& values) {
    bool ok = true;
    for (const auto& ov : ovs) {
        int pi = m.find_param(ov.name);
        if (pi < 0) {
            std::vector<std::string> cands;
            for (size_t i = 0; i < m.params.size(); ++i)
                if (std::find(bound.begin(), bound.end(), int(i)) == bound.end()) cands.push_back(m.params[i].name);
            auto& e = d_.error(ov.span, fmt::format("{} '{}' has no parameter '{}'", role, m.ast.name, ov.name));
            if (auto sug = did_you_mean(ov.name, cands)) Diagnostics::note(e, ov.span, fmt::format("did you mean '{}'?", *sug));
            else if (!cands.empty()) Diagnostics::note(e, ov.span, fmt::format("its parameters are: {}", fmt::join(cands, ", ")));
            ok = false;
            continue;
        }
        if (std::find(bound.begin(), bound.end(), pi) != bound.end()) {
            d_.error(ov.span, fmt::format("'{}' is bound by the renderer and cannot be set", ov.name));
            ok = false;
            continue;
        }
        const ParamInfo& p = m.params[size_t(pi)];
        if (int(ov.value.size()) != p.type.components()) {
            d_.error(ov.span, fmt::format("'{}' is {} but the value has {} component{}", ov.name, p.type.str(),
                                          ov.value.size(), ov.value.size() == 1 ? "" : "s"));
            ok = false;
            continue;
        }
        if (p.bounded)
            for (size_t i = 0; i < ov.value.size(); ++i)
                if (ov.value[i] < p.lo[i] || ov.value[i] > p.hi[i]) {
                    d_.warning(ov.span, fmt::format("the value {} of '{}' is outside its slider bounds [{}, {}]", ov.value[i],
                                                    ov.name, p.lo[i], p.hi[i]));
                    break;
                }
        values[size_t(pi)] = ov.value;
    }
    return ok;
}

bool SceneCompiler::plan_transform(const InstanceDesc& inst, InstancePlan& plan) {
    if (!inst.transform) return true;
    const ModuleSource& src = *inst.transform;
    bool blank = true;
    for (auto& r : src.ranges)
        for (char c : sm_.text(src.file).substr(r.begin, r.end - r.begin)) blank &= (c == ' ' || c == '\n' || c == '\t' || c == '\r');
    if (blank) return true;  // "" is the identity
    auto m = lib_.parse_check(src, plan.name + ".transform", true);
    if (!m->ok) return false;
    Span where = src.where;
    if (!m->ret) {
        d_.error(where, "a transform must end with a matrix expression such as T(X)⋅`R_x`(r)");
        return false;
    }
    if (m->primary_type != Type::matrix(4, 4)) {
        d_.error(m->ret->value->span, fmt::format("a transform must be a 4×4 matrix, but this is {}", m->primary_type.str()));
        return false;
    }
    int fn = lower_module(*m, plan.name + ".transform", plan.name + "_transform", lower_);
    plan.transform = m.get();
    plan.transform_fn = fn;
    plan.transform_runtime = opts_.target != Target::Shadertoy || uses_inputs(fn) || opts_.per_instance;
    std::vector<ir::Value> args;
    std::vector<std::string> settings;
    for (const auto& p : m->params) {
        args.push_back({p.type, p.value});
        settings.push_back(fmt::format("{} = {}", p.name, join_values(p.value)));
    }
    ir::Value M;
    try {
        M = ir::evaluate(ir_, fn, args);
    } catch (const ir::EvalLimit& limit) {
        d_.error(limit.span, fmt::format("evaluating the transform would take more than {} steps", limits::kMaxEvalSteps));
        return false;
    }
    const auto& v = M.v;
    plan.transform_comment = std::string(sm_.slice(m->ret->span));
    for (char& c : plan.transform_comment)
        if (c == '\n') c = ' ';
    if (!settings.empty()) plan.transform_comment += fmt::format(" with {}", fmt::join(settings, ", "));
    for (double x : v)
        if (!std::isfinite(x)) {
            d_.error(m->ret->value->span, "the transform evaluates to a matrix with non-finite entries");
            return false;
        }
    if (std::fabs(v[12]) > 1e-9 || std::fabs(v[13]) > 1e-9 || std::fabs(v[14]) > 1e-9 || std::fabs(v[15] - 1) > 1e-9) {
        d_.error(m->ret->value->span,
                 fmt::format("the transform's last row is ({}, {}, {}, {}), not (0, 0, 0, 1): only affine transforms are "
                             "supported", v[12], v[13], v[14], v[15]));
        return false;
    }
    bool singular = false;
    std::vector<double> inv = ir::mat_inverse(v, 4, &singular);
    if (singular) {
        d_.error(m->ret->value->span, "the transform is singular (it flattens space and has no inverse)");
        return false;
    }
    plan.has_transform = true;
    plan.inv_linear = {inv[0], inv[1], inv[2], inv[4], inv[5], inv[6], inv[8], inv[9], inv[10]};
    plan.inv_offset = {inv[3], inv[7], inv[11]};
    double norm = spectral_norm3(plan.inv_linear);
    plan.scale = std::fabs(norm - 1) < 1e-9 ? 1.0 : 1.0 / norm;
    transforms_.push_back(std::move(m));
    return true;
}

// `names`: the names of the instances planned so far; `explicit_names`: every name the scene gives, which
// generated names avoid.
bool SceneCompiler::plan_instance(const InstanceDesc& inst, InstancePlan& plan, std::map<std::string, int>& counts,
                                  std::set<std::string>& names, const std::set<std::string>& explicit_names) {
    plan.desc = &inst;
    bool ok = true;
    plan.name = inst.name.empty() ? fmt::format("{}_{}", inst.type, ++counts[inst.type]) : inst.name;
    if (!inst.name.empty()) {
        if (names.count(inst.name)) {
            d_.error(inst.name_span, fmt::format("two instances are named '{}'", inst.name));
            ok = false;
        }
    } else {
        while (names.count(plan.name) || explicit_names.count(plan.name))
            plan.name = fmt::format("{}_{}", inst.type, ++counts[inst.type]);
    }
    names.insert(plan.name);
    plan.shape = lib_.get(inst.type, inst.type_span);
    if (!plan.shape) {
        auto& e = d_.error(inst.type_span, fmt::format("unknown shape '{}'", inst.type));
        if (auto sug = did_you_mean(inst.type, lib_.names())) Diagnostics::note(e, inst.type_span, fmt::format("did you mean '{}'?", *sug));
        return false;
    }
    if (plan.shape->ast.kind != ast::ModuleKind::Shape) {
        d_.error(inst.type_span, fmt::format("'{}' is not a shape (its module does not start with 'shape')", inst.type));
        return false;
    }
    if (!plan.shape->ok) return false;
    const auto& sp = plan.shape->params;
    for (size_t i = 0; i < sp.size(); ++i)
        if (sp[i].name == "p") plan.query = int(i);
    if (plan.query < 0 && !sp.empty()) plan.query = 0;
    if (plan.query < 0 || sp[size_t(plan.query)].type != Type::vector(3)) {
        d_.error(inst.type_span, fmt::format("shape '{}' needs a query point 'p ∈ ℝ³' as a parameter", inst.type));
        return false;
    }
    for (auto& p : sp) plan.shape_values.push_back(p.value);
    ok &= apply_overrides(inst.shape_params, *plan.shape, "shape", {plan.query}, plan.shape_values);
    if (!inst.material.empty()) {
        plan.material = lib_.get(inst.material, inst.material_span);
        if (!plan.material) {
            auto& e = d_.error(inst.material_span, fmt::format("unknown material '{}'", inst.material));
            if (auto sug = did_you_mean(inst.material, lib_.names()))
                Diagnostics::note(e, inst.material_span, fmt::format("did you mean '{}'?", *sug));
            return false;
        }
        if (plan.material->ast.kind != ast::ModuleKind::Material) {
            d_.error(inst.material_span, fmt::format("'{}' is not a material (its module does not start with 'material')", inst.material));
            return false;
        }
        if (!plan.material->ok) return false;
        // The renderer binds the surface point, the normal and the eye: by their conventional names
        // (p, N̂, I) where the module uses them, otherwise the first three parameters in order.
        const auto& mp = plan.material->params;
        const std::vector<std::vector<std::string>> role_names = {{"p"}, {"N̂", "N", "n̂", "n"}, {"I", "eye", "E"}};
        for (int r = 0; r < 3; ++r)
            for (const auto& cand : role_names[size_t(r)])
                if (plan.roles[r] < 0) plan.roles[r] = plan.material->find_param(cand);
        std::set<int> used;
        for (int r = 0; r < 3; ++r)
            if (plan.roles[r] >= 0) used.insert(plan.roles[r]);
        for (int r = 0, next = 0; r < 3; ++r) {
            if (plan.roles[r] >= 0) continue;
            while (next < int(mp.size()) && used.count(next)) ++next;
            if (next < int(mp.size())) {
                plan.roles[r] = next;
                used.insert(next);
            }
        }
        static const char* role_desc[] = {"the surface point (p ∈ ℝ³)", "the unit normal (N̂ ∈ ℝ³)", "the eye position (I ∈ ℝ³)"};
        for (int r = 0; r < 3; ++r)
            if (plan.roles[r] < 0 || mp[size_t(plan.roles[r])].type != Type::vector(3)) {
                d_.error(inst.material_span, fmt::format("material '{}' needs {} as a parameter", inst.material, role_desc[r]));
                return false;
            }
        for (auto& p : mp) plan.material_values.push_back(p.value);
        ok &= apply_overrides(inst.material_params, *plan.material, "material",
                              {plan.roles[0], plan.roles[1], plan.roles[2]}, plan.material_values);
    } else if (!inst.material_params.empty()) {
        d_.error(inst.material_params.front().span, "'material_params' needs a 'material'");
        ok = false;
    }
    ok &= plan_transform(inst, plan);
    return ok;
}

// Whether a function (or anything it calls or loops over) reads `time` or `mouse`.
bool SceneCompiler::uses_inputs(int fn) const {
    for (const ir::Instr& in : ir_.functions[size_t(fn)].body) {
        if (in.op == ir::Op::Input) return true;
        if ((in.op == ir::Op::Call || in.op == ir::Op::Loop) && uses_inputs(in.aux)) return true;
    }
    return false;
}

int SceneCompiler::lower(const CheckedModule* m) { return lower_module_cached(*m, lower_); }

std::string param_comment(const ParamInfo& p) {
    std::string s = fmt::format("{} ∈ ", p.name);
    if (p.bounded) {
        std::vector<std::string> iv;
        for (size_t i = 0; i < p.lo.size(); ++i) iv.push_back(fmt::format("[{}, {}]", p.lo[i], p.hi[i]));
        s += fmt::format("{}", fmt::join(iv, "×"));
    } else {
        s += p.type.str();
    }
    if (!p.description.empty()) s += ": " + p.description;
    return s;
}


std::string vec3_literal(const std::array<double, 3>& v) { return glsl::constant(Type::vector(3), {v[0], v[1], v[2]}); }

// The renderer's conventions for material parameters (docs/scene.md).
const char* kLightPosition = "P_L";
const char* kLightColor = "C_L";
const char* kReflectivity = "k_r";
const char* kTransmission = "k_t";
const char* kRefractiveIndex = "η";

// Uniform vectors a GLSL type takes (WebGL2 counts in vec4 slots).
int uniform_vectors(const Type& t) { return t.is_matrix() ? t.cols : 1; }

std::string SceneCompiler::assemble(std::vector<InstancePlan>& plans, std::string& meta) {
    const bool shadertoy = opts_.target == Target::Shadertoy;
    const RenderDesc& render = s_.render;
    const EffectsDesc& fx = s_.effects;
    March march = opts_.march.value_or(render.march);
    Normals normals = opts_.normals.value_or(render.normals);
    double hit = opts_.hit.value_or(render.hit);
    int max_steps = opts_.max_steps.value_or(render.max_steps);
    bool lights = !s_.lights.empty();
    glsl::Namer globals;
    glsl::Emitter em(ir_, globals, d_);
    // Functions: every shape and material used, runtime transforms, and what they call (callees first).
    std::vector<int> roots;
    for (auto& p : plans) {
        roots.push_back(p.shape_fn);
        if (p.material) roots.push_back(p.material_fn);
        if (p.transform_runtime) roots.push_back(p.transform_fn);
        if (p.gradient_fn >= 0 && normals == Normals::Analytic) roots.push_back(p.gradient_fn);
    }
    std::vector<int> fns = em.closure(roots);
    for (int f : fns) em.function_name(f);
    nlohmann::ordered_json jparams = nlohmann::ordered_json::array();
    std::map<std::string, int> budget;  // instance -> uniform vectors
    auto declare = [&](const std::string& name, const Type& t, const std::vector<double>& value, const std::string& comment) {
        if (shadertoy)
            return fmt::format("const {} {} = {};  // {}\n", glsl::type_name(t), name, glsl::constant(t, value), glsl::comment_text(comment));
        return fmt::format("uniform {} {};  // {} (default {})\n", glsl::type_name(t), name, glsl::comment_text(comment), join_values(value));
    };
    auto describe = [&](const std::string& instance, const std::string& module, const char* role, const ParamInfo& pi,
                        const std::vector<double>& value, const std::string& glsl_name) {
        nlohmann::ordered_json j;
        j["instance"] = instance;
        j["module"] = module;
        j["role"] = role;
        j["name"] = pi.name;
        j[shadertoy ? "constant" : "uniform"] = glsl_name;
        j["type"] = glsl::type_name(pi.type);
        j["components"] = pi.type.components();
        if (pi.bounded) {
            nlohmann::ordered_json b = nlohmann::ordered_json::array();
            for (size_t i = 0; i < pi.lo.size(); ++i) b.push_back({pi.lo[i], pi.hi[i]});
            j["bounds"] = b;
        } else {
            j["bounds"] = nullptr;
        }
        j["default"] = value;
        j["description"] = pi.description;
        jparams.push_back(j);
        if (!shadertoy) {
            // GLSL matrices are column-major.
            std::vector<double> v = value;
            if (pi.type.is_matrix())
                for (int r = 0; r < pi.type.rows; ++r)
                    for (int c = 0; c < pi.type.cols; ++c) v[size_t(c * pi.type.rows + r)] = value[size_t(r * pi.type.cols + c)];
            uniform_defaults_.push_back({glsl_name, v});
        }
        budget[instance] += uniform_vectors(pi.type);
    };
    // Lights (bound to materials' `P_L` and `C_L`).
    std::string light_decls;
    std::vector<std::pair<std::string, std::string>> light_names;  // position, colour
    nlohmann::ordered_json jlights = nlohmann::ordered_json::array();
    for (const auto& l : s_.lights) {
        std::string pos = globals.unique(l.name + "_position"), col = globals.unique(l.name + "_color");
        ParamInfo pp{"position", l.span, Type::vector(3), false, {}, {}, {l.position[0], l.position[1], l.position[2]}, true, "light position"};
        ParamInfo pc{"color", l.span, Type::vector(3), false, {}, {}, {l.color[0], l.color[1], l.color[2]}, true, "light colour"};
        light_decls += declare(pos, pp.type, pp.value, l.name + " position");
        light_decls += declare(col, pc.type, pc.value, l.name + " colour");
        describe(l.name, "", "light", pp, pp.value, pos);
        describe(l.name, "", "light", pc, pc.value, col);
        light_names.push_back({pos, col});
        nlohmann::ordered_json jl;
        jl["name"] = l.name;
        jl["position"] = pos;
        jl["color"] = col;
        jlights.push_back(jl);
    }
    if (!light_decls.empty()) light_decls = "// ---- lights ----\n" + light_decls + "\n";
    // Parameters: constants on Shadertoy, uniforms elsewhere.
    std::string params;
    glsl::Namer prefixes;  // instance prefixes are parts of names, not names: unique among themselves
    for (auto& p : plans) {
        p.glsl = prefixes.unique(p.name);
        std::string block;
        auto emit_params = [&](const CheckedModule& m, const std::vector<std::vector<double>>& values, const char* role,
                               const std::vector<int>& bound) {
            for (size_t i = 0; i < m.params.size(); ++i) {
                if (std::find(bound.begin(), bound.end(), int(i)) != bound.end()) continue;
                const ParamInfo& pi = m.params[i];
                std::string n = globals.unique(fmt::format("{}_{}_{}", p.glsl, role, glsl::identifier(pi.name)));
                p.constants[std::string(role) + "." + pi.name] = n;
                block += declare(n, pi.type, values[i], param_comment(pi));
                describe(p.name, m.ast.name, role, pi, values[i], n);
            }
        };
        emit_params(*p.shape, p.shape_values, "shape", {p.query});
        if (p.material) {
            std::vector<int> bound = {p.roles[0], p.roles[1], p.roles[2]};
            if (lights) {
                for (const char* n : {kLightPosition, kLightColor})
                    if (int pi = p.material->find_param(n); pi >= 0 && p.material->params[size_t(pi)].type == Type::vector(3))
                        bound.push_back(pi);
            }
            emit_params(*p.material, p.material_values, "material", bound);
        }
        if (p.transform_runtime)
            for (size_t i = 0; i < p.transform->params.size(); ++i) {
                const ParamInfo& pi = p.transform->params[i];
                std::string n = globals.unique(fmt::format("{}_transform_{}", p.glsl, glsl::identifier(pi.name)));
                p.constants["transform." + pi.name] = n;
                block += declare(n, pi.type, pi.value, param_comment(pi));
                describe(p.name, "transform", "transform", pi, pi.value, n);
            }
        if (!block.empty())
            params += fmt::format("// {}\n{}", glsl::comment_text(fmt::format("{}: {}{}", p.name, p.desc->type,
                                                                      p.material ? " with " + p.desc->material : std::string())), block);
    }
    if (!params.empty())
        params = (shadertoy ? "// ---- parameters (Shadertoy has no sliders: edit the values here) ----\n"
                            : "// ---- parameters (uniforms; defaults in the comments and the --meta JSON) ----\n") + params + "\n";
    // WebGL2's uniform budget.
    if (opts_.target == Target::WebGL2) {
        int total = 4;  // iResolution, iTime, iMouse, iFrame
        for (auto& [n, v] : budget) total += v;
        if (total > 224) {
            std::vector<std::pair<int, std::string>> users;
            for (auto& [n, v] : budget) users.push_back({-v, n});
            std::sort(users.begin(), users.end());
            std::string list;
            for (size_t i = 0; i < users.size() && i < 5; ++i) list += fmt::format("{}{} ({})", i ? ", " : "", users[i].second, -users[i].first);
            d_.error(plans.empty() ? Span{s_.file, 0, 1} : plans[0].desc->span,
                     fmt::format("the scene needs {} uniform vectors, more than WebGL2's 224; the biggest users: {}. Use "
                                 "--target shadertoy (constants) or fewer instances", total, list));
            return "";
        }
    }
    std::string functions;
    for (int f : fns) {
        const ir::Function& fn = ir_.functions[size_t(f)];
        std::string comment;
        for (auto& p : plans) {
            if (p.shape_fn == f) comment = "shape " + p.shape->ast.name;
            if (p.material && p.material_fn == f) comment = "material " + p.material->ast.name;
            if (p.transform_runtime && p.transform_fn == f) comment = "transform of " + p.name;
            if (p.gradient_fn == f) comment = "gradient of shape " + p.shape->ast.name + " (derived by iqc)";
        }
        if (comment.empty()) comment = fn.name;
        functions += "\n" + em.function(f, comment);
    }
    if (!functions.empty()) functions = "// ---- modules ----" + functions;
    // Transforms, scene body, materials.
    std::string transforms, prepare, body, shade, gradient, reflect, transmit, per_instance_inverse, per_instance_distance;
    bool lipschitz = false, any_bound = false;
    for (size_t i = 0; i < plans.size(); ++i) {
        InstancePlan& p = plans[i];
        const std::string label = glsl::comment_text(p.name);  // the instance's name in comments
        const std::string transform_text = glsl::comment_text(p.transform_comment);
        std::string q = "p", scale;
        if (p.has_transform && p.transform_runtime) {
            std::string lin = globals.unique(p.glsl + "_to_object");
            std::string off = globals.unique(p.glsl + "_offset");
            std::string sc = globals.unique(p.glsl + "_scale");
            transforms += fmt::format("// {}: {} (evaluated per pixel in iqc_prepare)\nmat3 {};\nvec3 {};\nfloat {};\n", label,
                                      transform_text, lin, off, sc);
            std::vector<std::string> targs;
            for (const auto& pi : p.transform->params) targs.push_back(p.constants.at("transform." + pi.name));
            prepare += fmt::format("    {{\n        mat4 inv = inverse({}({}));  // {}\n        {} = mat3(inv);\n        {} = inv[3].xyz;\n"
                                   "        {} = 1.0 / iqc_max_singular({});\n    }}\n",
                                   em.function_name(p.transform_fn), fmt::join(targs, ", "), label, lin, off, sc, lin);
            lipschitz = true;
            q = lin + " * p + " + off;
            scale = sc;
        } else if (p.has_transform) {
            transforms += fmt::format("// {}: {}\n", label, transform_text);
            bool identity = true;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) identity &= std::fabs(p.inv_linear[size_t(r * 3 + c)] - (r == c ? 1.0 : 0.0)) < 1e-12;
            bool no_offset = std::fabs(p.inv_offset[0]) + std::fabs(p.inv_offset[1]) + std::fabs(p.inv_offset[2]) < 1e-12;
            std::string lin = globals.unique(p.glsl + "_to_object");
            std::string off = globals.unique(p.glsl + "_offset");
            if (!identity) {
                transforms += fmt::format("const mat3 {} = {};\n", lin, glsl::constant(Type::matrix(3, 3), p.inv_linear));
                q = lin + " * p";
            }
            if (!no_offset) {
                transforms += fmt::format("const vec3 {} = {};\n", off, glsl::constant(Type::vector(3), p.inv_offset));
                q += " + " + off;
            }
            if (p.scale != 1.0) {
                scale = globals.unique(p.glsl + "_scale");
                transforms += fmt::format("const float {} = {};  // 1 / Lipschitz factor: keeps distances conservative\n",
                                          scale, glsl::float_literal(p.scale));
            }
        }
        std::vector<std::string> args;
        const auto& sp = p.shape->params;
        for (size_t k = 0; k < sp.size(); ++k) args.push_back(int(k) == p.query ? q : p.constants.at("shape." + sp[k].name));
        std::string call = fmt::format("{}({})", em.function_name(p.shape_fn), fmt::join(args, ", "));
        if (!scale.empty()) call += " * " + scale;
        if (p.shape->lipschitz != 1)
            call += fmt::format(" / {}", glsl::float_literal(p.shape->lipschitz));  // `# lipschitz` of the shape: stays conservative
        if (normals == Normals::Analytic) {
            if (p.gradient_fn >= 0) {
                // ∇(d ∘ world→object) = Lᵀ ∇d (L the linear part); the scale does not change the direction.
                std::string grad = fmt::format("{}({})", em.function_name(p.gradient_fn), fmt::join(args, ", "));
                std::string lin = q.substr(0, q.find(" * p"));
                bool has_linear = q.find(" * p") != std::string::npos;
                gradient += fmt::format("    if (id == {}) g = {};  // {}\n", i,
                                        has_linear ? fmt::format("transpose({}) * {}", lin, grad) : grad, label);
            } else {
                gradient += fmt::format("    if (id == {}) g = iqc_tetrahedron_gradient(p, t);  // {}\n", i, label);

            }
        }
        bool counted = opts_.instrument || opts_.bench;  // instrumented builds count shape evaluations
        double bound = p.desc ? p.desc->bound : 0;
        if (bound > 0) {
            // `bound = R`: outside the object-space sphere ‖q‖ = R (by more than IQC_BOUND_MARGIN in world units),
            // the sphere's distance, scaled as the shape's, is a lower bound and the shape is not evaluated.
            std::vector<std::string> bargs = args;
            bargs[size_t(p.query)] = "iqc_q";
            std::string bcall = fmt::format("{}({})", em.function_name(p.shape_fn), fmt::join(bargs, ", "));
            std::string suffix;
            if (!scale.empty()) suffix += " * " + scale;
            if (p.shape->lipschitz != 1) suffix += fmt::format(" / {}", glsl::float_literal(p.shape->lipschitz));
            body += fmt::format("    {{  // {}: bounding sphere of radius {}\n        vec3 iqc_q = {};\n"
                                "        float iqc_b = (length(iqc_q) - {}){};\n        if (iqc_b > IQC_BOUND_MARGIN) d = iqc_b;\n"
                                "        else {{\n{}            d = {}{};\n        }}\n    }}\n",
                                label, glsl::float_literal(bound), q, glsl::float_literal(bound), suffix,
                                counted ? "            iqc_shape_evals++;\n" : "", bcall, suffix);
            any_bound = true;
        } else {
            if (counted) body += "    iqc_shape_evals++;\n";
            body += fmt::format("    d = {};  // {}\n", call, label);
        }
        if (opts_.per_instance) {
            // I♥IQ's architecture, as code the driver can compile: per instance, its transform inverted (at
            // each pixel) and its own distance, selected by the instance's index.
            std::vector<std::string> pargs = args;
            pargs[size_t(p.query)] = "q";
            std::string inv = "mat4(1.0)";
            if (p.has_transform) {
                std::vector<std::string> targs;
                for (const auto& pi : p.transform->params) targs.push_back(p.constants.at("transform." + pi.name));
                inv = fmt::format("inverse({}({}))", em.function_name(p.transform_fn), fmt::join(targs, ", "));
            }
            std::string dist = fmt::format("{}({})", em.function_name(p.shape_fn), fmt::join(pargs, ", "));
            if (p.shape->lipschitz != 1) dist += fmt::format(" / {}", glsl::float_literal(p.shape->lipschitz));
            per_instance_inverse += fmt::format("    if (i == {}) return {};  // {}\n", i, inv, label);
            per_instance_distance += fmt::format("    if (i == {}) return {};\n", i, dist);
        }
        body += fmt::format("    if (d < res.x) res = vec2(d, {});\n", glsl::float_literal(double(i)));
        if (p.material) {
            const auto& mp = p.material->params;
            int pl = p.material->find_param(kLightPosition), cl = p.material->find_param(kLightColor);
            bool per_light = lights && pl >= 0 && mp[size_t(pl)].type == Type::vector(3);
            auto material_call = [&](const std::string& light_pos, const std::string& light_col) {
                std::vector<std::string> margs;
                for (size_t k = 0; k < mp.size(); ++k) {
                    if (int(k) == p.roles[0]) margs.push_back("p");
                    else if (int(k) == p.roles[1]) margs.push_back("N");
                    else if (int(k) == p.roles[2]) margs.push_back("eye");
                    else if (per_light && int(k) == pl) margs.push_back(light_pos);
                    else if (per_light && int(k) == cl && mp[k].type == Type::vector(3)) margs.push_back(light_col);
                    else margs.push_back(p.constants.at("material." + mp[k].name));
                }
                return fmt::format("{}({})", em.function_name(p.material_fn), fmt::join(margs, ", "));
            };
            if (!per_light) {
                shade += fmt::format("    if (id == {}) return {};  // {}\n", i, material_call("", ""), label);
            } else {
                shade += fmt::format("    if (id == {}) {{  // {}: {} once per light\n        vec3 c = vec3(0.0);\n", i, label,
                                     glsl::comment_text(p.material->ast.name));
                for (const auto& [pos, col] : light_names) {
                    std::string term = material_call(pos, col);
                    if (fx.shadows != Shadows::None) term += fmt::format(" * iqc_shadow(p, N, {})", pos);
                    shade += fmt::format("        c += {};\n", term);
                }
                shade += "        return c;\n    }\n";
            }
            auto vec3_of = [&](const char* name) -> std::string {
                int k = p.material->find_param(name);
                if (k < 0) return "";
                const std::string& n = p.constants.count(std::string("material.") + name) ? p.constants.at(std::string("material.") + name) : "";
                if (n.empty()) return "";
                return mp[size_t(k)].type.is_scalar() ? fmt::format("vec3({})", n) : mp[size_t(k)].type == Type::vector(3) ? n : "";
            };
            if (std::string kr = vec3_of(kReflectivity); !kr.empty())
                reflect += fmt::format("    if (id == {}) return {};  // {}\n", i, kr, label);
            if (std::string kt = vec3_of(kTransmission); !kt.empty()) {
                int ek = p.material->find_param(kRefractiveIndex);
                if (ek < 0) ek = p.material->find_param("eta");
                std::string eta = ek >= 0 && mp[size_t(ek)].type.is_scalar() ? p.constants.at("material." + mp[size_t(ek)].name) : "1.5";
                transmit += fmt::format("    if (id == {}) return vec4({}, {});  // {}\n", i, kt, eta, label);
            }
        }
    }
    if (!transforms.empty()) transforms += "\n";
    auto fmt_vec = [](const std::array<double, 3>& v) { return vec3_literal(v); };
    double focal = 1.0 / std::tan(s_.camera.fov * M_PI / 360.0);
    TemplateArgs ta;
    auto& V = ta.values;
    auto& F = ta.flags;
    V["TITLE"] = glsl::comment_text(s_.title);
    V["VERSION"] = IQC_VERSION;
    V["SOURCE"] = glsl::comment_text(std::filesystem::path(s_.path).filename().string());
    V["TARGET"] = target_name(opts_.target);
    V["MAX_STEPS"] = std::to_string(max_steps);
    V["MAX_DIST"] = glsl::float_literal(render.max_dist);
    V["HIT"] = glsl::float_literal(hit);
    V["HIT_DOC"] = render.hit_relative ? "hit tolerance per unit of distance along the ray" : "hit tolerance (world units)";
    V["BACKGROUND"] = fmt_vec(render.background);
    V["CAMERA_POSITION"] = fmt_vec(s_.camera.position);
    V["CAMERA_TARGET"] = fmt_vec(s_.camera.target);
    V["CAMERA_FOCAL"] = glsl::float_literal(focal);
    V["FIXED_STEP"] = glsl::float_literal(render.step > 0 ? render.step : render.max_dist / max_steps);
    V["RELAXATION"] = glsl::float_literal(render.relaxation);
    V["SHADOW_K"] = glsl::float_literal(fx.shadow_softness);
    V["FOG"] = glsl::float_literal(fx.fog);
    V["FOG_COLOR"] = fmt_vec(fx.fog_color.value_or(render.background));
    V["BOUNCES"] = std::to_string(fx.reflections + (fx.refraction ? 2 : 0));
    V["AA"] = std::to_string(fx.antialias);
    V["PARAMETERS"] = params;
    V["LIGHTS"] = light_decls;
    V["FUNCTIONS"] = functions;
    if (any_bound) {
        // Ten hit tolerances (at the farthest distance for a relative tolerance), and at least 0.1: a march
        // never stops on a bounding sphere, and the shape is evaluated wherever a hit is possible.
        bound_margin_ = std::max(0.1, 10 * hit * (render.hit_relative ? render.max_dist : 1.0));
        transforms = fmt::format("const float IQC_BOUND_MARGIN = {};  // `bound`: the shape is evaluated within this "
                                 "distance of its bounding sphere\n", glsl::float_literal(bound_margin_)) + transforms;
    }
    V["TRANSFORMS"] = transforms;
    V["PREPARE_BODY"] = prepare;
    V["SCENE_BODY"] = body;
    V["SHADE_BODY"] = shade;
    V["GRADIENT_BODY"] = gradient;
    V["REFLECT_BODY"] = reflect;
    V["TRANSMIT_BODY"] = transmit;
    V["PER_INSTANCE_INVERSE"] = per_instance_inverse;
    V["PER_INSTANCE_DISTANCE"] = per_instance_distance;
    V["INSTANCES"] = std::to_string(plans.size());
    F.insert(opts_.target == Target::Shadertoy ? "SHADERTOY" : opts_.target == Target::WebGL2 ? "WEBGL2" : "GLSL330");
    static const char* marches[] = {"MARCH_FIXED", "MARCH_SPHERE", "MARCH_RELAXED", "MARCH_AUTO"};
    F.insert(opts_.per_instance ? "PER_INSTANCE" : marches[int(march)]);
    if (opts_.per_instance) lipschitz = true;
    static const char* normal_flags[] = {"NORMALS_CENTRAL", "NORMALS_FORWARD", "NORMALS_TETRAHEDRON", "NORMALS_ANALYTIC"};
    F.insert(normal_flags[int(normals)]);
    if (render.hit_relative) F.insert("HIT_RELATIVE");
    if (fx.shadows == Shadows::Hard && lights) F.insert("SHADOWS_HARD");
    if (fx.shadows == Shadows::Soft && lights) F.insert("SHADOWS_SOFT");
    if (fx.ao) F.insert("AO");
    if (fx.fog > 0) F.insert("FOG");
    if (fx.reflections > 0 && !reflect.empty()) F.insert("REFLECTIONS");
    if (fx.refraction && !transmit.empty()) F.insert("REFRACTION");
    if (F.count("REFLECTIONS") || F.count("REFRACTION")) F.insert("BOUNCES");
    if (fx.antialias > 1) F.insert("AA");
    static const char* debug_flags[] = {"", "DEBUG_NORMALS", "DEBUG_STEPS", "DEBUG_DEPTH"};
    if (render.debug != DebugView::None) F.insert(debug_flags[int(render.debug)]);
    if (s_.camera.orbit) F.insert("ORBIT");
    if (!prepare.empty()) F.insert("PREPARE");
    if (lipschitz) F.insert("LIPSCHITZ");

    if (opts_.instrument || opts_.bench) F.insert("INSTRUMENT");
    if (opts_.geometry || opts_.bench) F.insert("GEOMETRY");
    if (opts_.bench) F.insert("BENCH");
    nlohmann::ordered_json j;
    j["title"] = s_.title;
    j["target"] = target_name(opts_.target);
    j["inputs"] = nlohmann::ordered_json::array({"iResolution", "iTime", "iMouse", "iFrame"});
    j["parameters"] = jparams;
    j["lights"] = jlights;
    meta = j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";  // invalid UTF-8: U+FFFD
    return expand_template(std::string(*embedded_file("runtime_templates/scene.glsl")), ta);
}

CompileResult SceneCompiler::run() {
    CompileResult res;
    size_t before = d_.error_count();
    auto clock = std::chrono::steady_clock::now();
    auto lap = [&](const char* name) {
        auto now = std::chrono::steady_clock::now();
        res.pass_ms.push_back({name, std::chrono::duration<double, std::milli>(now - clock).count()});
        clock = now;
    };
    for (const auto& m : s_.modules) {
        // A document's blocks with one name are already joined into one module.
        lib_.add(m);
    }
    std::vector<InstancePlan> plans(s_.instances.size());
    std::map<std::string, int> counts;
    std::set<std::string> names;
    for (const auto& inst : s_.instances)
        if (!inst.name.empty()) names.insert(inst.name);
    std::set<std::string> explicit_names = names;  // reserved first so generated names avoid them
    names.clear();
    for (size_t i = 0; i < s_.instances.size(); ++i) plan_instance(s_.instances[i], plans[i], counts, names, explicit_names);
    lap("parse + check + transforms");
    if (d_.error_count() != before) return res;
    for (auto& p : plans) {
        p.shape_fn = lower(p.shape);
        if (p.material) p.material_fn = lower(p.material);
    }
    for (auto& f : ir_.functions) ir::eliminate_common_subexpressions(f);  // shared values are one value for the analysis
    // Range analysis: guards where the math has a continuous limit, warnings where a slider can leave an
    // operation's domain. Module functions know their parameters' bounds; everything else is unknown.
    {
        std::map<int, std::vector<ir::ParamRange>> ranges;
        auto module_ranges = [](const CheckedModule& m, const std::vector<int>& inputs) {
            std::vector<ir::ParamRange> pr;
            for (size_t k = 0; k < m.params.size(); ++k) {
                const ParamInfo& p = m.params[k];
                if (std::find(inputs.begin(), inputs.end(), int(k)) != inputs.end()) {
                    pr.push_back(std::nullopt);
                    continue;
                }
                std::vector<ir::Interval> iv(size_t(p.type.components()));
                if (p.bounded)
                    for (size_t c = 0; c < iv.size(); ++c) iv[c] = {p.lo[c], p.hi[c]};
                pr.push_back(iv);
            }
            return pr;
        };
        for (const auto& p : plans) {
            ranges[p.shape_fn] = module_ranges(*p.shape, {p.query});
            if (p.material) {
                std::vector<int> inputs = {p.roles[0], p.roles[1], p.roles[2]};
                if (!s_.lights.empty())
                    for (const char* n : {"P_L", "C_L"})
                        if (int k = p.material->find_param(n); k >= 0) inputs.push_back(k);
                ranges[p.material_fn] = module_ranges(*p.material, inputs);
            }
            if (p.transform) ranges[p.transform_fn] = module_ranges(*p.transform, {});
        }
        size_t n_functions = ir_.functions.size();
        for (size_t fi = 0; fi < n_functions; ++fi) {
            std::vector<ir::ParamRange> pr(ir_.functions[fi].params.size(), std::nullopt);
            if (auto it = ranges.find(int(fi)); it != ranges.end()) pr = it->second;
            for (const auto& issue : ir::analyze_ranges(ir_, int(fi), pr, true)) {
                if (opts_.strict_ranges) d_.error(issue.span, issue.message + " (--strict-ranges)");
                else d_.warning(issue.span, issue.message);
            }
        }
        if (d_.error_count() != before) return res;
    }
    if (opts_.normals.value_or(s_.render.normals) == Normals::Analytic) {
        // One gradient function per shape module, derived from its IR.
        std::map<int, int> gradients;
        for (auto& p : plans) {
            auto it = gradients.find(p.shape_fn);
            if (it == gradients.end()) {
                std::string why;
                int g = ir::differentiate(ir_, p.shape_fn, p.query, p.shape->ast.name + "_gradient", &why);
                if (g < 0)
                    d_.warning(p.desc->type_span, fmt::format("no analytic normal for shape '{}' ({}): its normals use "
                                                              "tetrahedron differences", p.shape->ast.name, why));
                it = gradients.emplace(p.shape_fn, g).first;
            }
            p.gradient_fn = it->second;
        }
    }
    for (auto& f : ir_.functions) ir::eliminate_common_subexpressions(f);
    for (size_t f = 0; f < ir_.functions.size(); ++f) {
        std::string fault = ir::verify(ir_.functions[f], ir_);
        if (!fault.empty()) {
            res.exit_code = 3;
            res.internal = "internal compiler error: invalid IR (this is a bug in iqc): " + fault;
            return res;
        }
    }
    if (opts_.dump_ir) res.ir = ir::print(ir_);
    lap("lower + verify IR");
    std::string code = assemble(plans, res.meta);
    lap("GLSL backend + assembly");
    if (d_.error_count() != before) return res;
    // Fault injection for the test of the internal-error path: a shader glslang must reject.
    if (std::getenv("IQC_INJECT_GLSL_FAULT")) code += "\nthis line is not GLSL;\n";
    glsl::ValidationResult v =
        opts_.target == Target::Shadertoy ? glsl::validate_fragment(glsl::wrap_shadertoy(code), glsl::Profile::Es300)
        : opts_.target == Target::WebGL2  ? glsl::validate_fragment(code, glsl::Profile::Es300)
                                          : glsl::validate_fragment(code, glsl::Profile::Core330);
    lap("glslang validation");
    if (!v.ok) {
        res.exit_code = 3;
        res.internal = "internal compiler error: glslang rejected the generated shader (this is a bug in iqc; "
                       "nothing was written):\n" + v.log;
        return res;
    }
    res.code = std::move(code);
    res.exit_code = 0;
    res.uniform_defaults = uniform_defaults_;
    // The same scene in double precision, for references.
    auto model = std::make_shared<SceneModel>();
    model->ir = ir_;
    model->camera = s_.camera;
    model->render = s_.render;
    for (const auto& p : plans) {
        SceneModel::Instance in;
        in.shape_fn = p.shape_fn;
        in.query = p.query;
        for (size_t k = 0; k < p.shape->params.size(); ++k) in.args.push_back({p.shape->params[k].type, p.shape_values[k]});
        if (p.has_transform) {
            for (int k = 0; k < 9; ++k) in.linear[size_t(k)] = p.inv_linear[size_t(k)];
            for (int k = 0; k < 3; ++k) in.offset[size_t(k)] = p.inv_offset[size_t(k)];
            in.scale = p.scale;
        }
        in.scale /= p.shape->lipschitz;
        if (p.desc && p.desc->bound > 0) {
            in.bound = p.desc->bound;
            in.bound_margin = bound_margin_;
        }
        model->instances.push_back(std::move(in));
    }
    res.model = std::move(model);
    return res;
}

}  // namespace

const char* target_name(Target t) {
    switch (t) {
        case Target::Shadertoy: return "shadertoy";
        case Target::WebGL2: return "webgl2";
        case Target::GLSL330: return "glsl330";
    }
    return "?";
}

CompileResult compile_scene(const SceneDesc& scene, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts) {
    SceneCompiler c(scene, sm, diags, opts);
    return c.run();
}

CompileResult compile_file(const std::string& path, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts) {
    auto t0 = std::chrono::steady_clock::now();
    SceneDesc scene;
    if (!load_scene(path, sm, diags, scene)) return {};
    double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    CompileResult r = compile_scene(scene, sm, diags, opts);
    r.pass_ms.insert(r.pass_ms.begin(), {"read scene", load_ms});
    return r;
}

}  // namespace iqc
