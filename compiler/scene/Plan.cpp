#include "scene/Plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <map>
#include <set>

#include "ir/Eval.h"
#include "ir/Lower.h"
#include "sema/Hints.h"
#include "source/Limits.h"

namespace iqc {

using namespace conventions;

bool InstancePlan::lit_by(int param, bool shading, bool ambient) const {
    if (!material || param < 0) return false;
    const ParamInfo& p = material->params[size_t(param)];
    if (p.type != Type::vector(3)) return false;
    if (p.name == kLightPosition || p.name == kLightColor) return shading;
    return p.name == kAmbientColor && ambient;
}

bool InstancePlan::binds_footprint() const {
    if (!material) return false;
    int k = material->find_param(kFootprint);
    return k >= 0 && material->params[size_t(k)].type == Type::vector(3);
}

bool InstancePlan::per_light(bool shading) const {
    return material && lit_by(material->find_param(kLightPosition), shading);
}

namespace {

std::string join_values(const std::vector<double>& v) {
    if (v.size() == 1) return fmt::format("{}", v[0]);
    return fmt::format("({})", fmt::join(v, ", "));
}

// Largest and smallest singular values of a 3×3 matrix (row-major): square roots of the extreme eigenvalues of
// LᵀL (Jacobi).
std::pair<double, double> singular_values3(const std::vector<double>& L) {
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
    return {std::sqrt(std::max({a[0][0], a[1][1], a[2][2], 0.0})), std::sqrt(std::max(std::min({a[0][0], a[1][1], a[2][2]}), 0.0))};
}

// Largest singular value of a 3×3 matrix (row-major).
double spectral_norm3(const std::vector<double>& L) { return singular_values3(L).first; }

// σ_max/σ_min of a 4×4 affine map's linear part (row-major), at most 10⁶ (a map through a singular moment).
double condition_number(const std::vector<double>& w) {
    auto [hi, lo] = singular_values3({w[0], w[1], w[2], w[4], w[5], w[6], w[8], w[9], w[10]});
    return hi <= 1e6 * lo ? std::max(1.0, hi / lo) : 1e6;
}

bool uses_inputs(const ir::Module& m, int fn) {
    for (const ir::Instr& in : m.functions[size_t(fn)].body) {
        if (in.op == ir::Op::Input) return true;
        if ((in.op == ir::Op::Call || in.op == ir::Op::Loop) && uses_inputs(m, in.aux)) return true;
    }
    return false;
}

struct Planner {
    const SceneDesc& s;
    ModuleLibrary& lib;
    SourceManager& sm;
    Diagnostics& d;
    bool strict_ranges = false;  // --strict-ranges: a value outside its slider bounds is an error

    std::set<const CheckedModule*> warned_footprint_;

    bool apply_overrides(const std::vector<ParamOverride>& ovs, const CheckedModule& m, const char* role,
                         const std::vector<int>& bound, std::vector<std::vector<double>>& values) {
        bool ok = true;
        for (const auto& ov : ovs) {
            int pi = m.find_param(ov.name);
            std::vector<std::string> cands;
            for (size_t i = 0; i < m.params.size(); ++i)
                if (std::find(bound.begin(), bound.end(), int(i)) == bound.end()) cands.push_back(m.params[i].name);
            bool accept = false;
            auto key = pi < 0 ? match_key(ov.name, cands, &accept) : std::nullopt;  // theta for θ; kd → k_d
            if (accept) pi = m.find_param(*key);
            if (pi < 0) {
                auto& e = d.error(ov.span, fmt::format("{} '{}' has no parameter '{}'", role, m.ast.name, ov.name));
                if (key) Diagnostics::note(e, ov.span, fmt::format("did you mean '{}'?", *key));
                else if (auto sug = did_you_mean(ov.name, cands)) Diagnostics::note(e, ov.span, fmt::format("did you mean '{}'?", *sug));
                else if (!cands.empty()) Diagnostics::note(e, ov.span, fmt::format("its parameters are: {}", fmt::join(cands, ", ")));
                ok = false;
                continue;
            }
            if (std::find(bound.begin(), bound.end(), pi) != bound.end()) {
                d.error(ov.span, fmt::format("'{}' is bound by the renderer and cannot be set", ov.name));
                ok = false;
                continue;
            }
            const ParamInfo& p = m.params[size_t(pi)];
            // A sequence's elements as rows: x = [[1, 0, 0], [0, 1, 0]] for x_i ∈ ℝ³ (a trial's override in this form
            // was "'x' is ℝ³[2] but the value is 2 rows of 3"; only a string "{(1, 0, 0), (0, 1, 0)}" was taken).
            const bool element_rows = ov.rows > 0 && p.type.is_array() && !p.type.element().is_matrix() &&
                                      std::max(1, p.type.element().components()) == ov.cols;
            if (p.type.is_array() && int(ov.value.size()) != p.type.components() &&
                int(ov.value.size()) % std::max(1, p.type.element().components()) == 0) {
                d.error(ov.span, fmt::format("'{}' is a sequence of {} elements ({}); this value has {}", ov.name, p.type.count,
                                             p.type.str(), int(ov.value.size()) / std::max(1, p.type.element().components())));
                ok = false;
                continue;
            }
            if (ov.rows > 0 && !element_rows && !(p.type.is_matrix() && p.type.rows == ov.rows && p.type.cols == ov.cols)) {
                d.error(ov.span, fmt::format("'{}' is {} but the value is {} row{} of {}", ov.name, p.type.str(), ov.rows,
                                             ov.rows == 1 ? "" : "s", ov.cols));
                ok = false;
                continue;
            }
            if (int(ov.value.size()) != p.type.components()) {
                d.error(ov.span, fmt::format("'{}' is {} but the value has {} component{}", ov.name, p.type.str(),
                                             ov.value.size(), ov.value.size() == 1 ? "" : "s"));
                ok = false;
                continue;
            }
            if (p.type.kind == Type::Integer && ov.value[0] != std::floor(ov.value[0])) {
                d.error(ov.span, fmt::format("'{}' is ℤ, but the value {} is not a whole number", ov.name, ov.value[0]));
                ok = false;
                continue;
            }
            if (p.type.kind == Type::Integer && !limits::is_int32(ov.value[0])) {
                d.error(ov.span, fmt::format("'{}' is ℤ, but the value {} is not a 32-bit integer (a shader's int: "
                                             "-2147483648 … 2147483647)", ov.name, ov.value[0]));
                ok = false;
                continue;
            }
            // Range analysis proves its guards within the slider bounds only: past them a division by the value or
            // a root of it may be NaN at every point (a vesica of width 0). Under --strict-ranges that is an error,
            // as the analysis' own warnings are.
            if (int i = p.outside_bounds(ov.value); i >= 0) {
                std::string msg = p.outside_bounds_message(ov.value, i, ov.name);
                if (strict_ranges) {
                    d.error(ov.span, msg + ", where range analysis proves nothing (--strict-ranges)");
                    ok = false;
                } else {
                    d.warning(ov.span, msg);
                }
            }
            values[size_t(pi)] = ov.value;
        }
        return ok;
    }

    bool plan_transform(const InstanceDesc& inst, InstancePlan& plan) {
        if (!inst.transform) return true;
        const ModuleSource& src = *inst.transform;
        bool blank = true;
        for (auto& r : src.ranges)
            for (char c : sm.text(src.file).substr(r.begin, r.end - r.begin)) blank &= (c == ' ' || c == '\n' || c == '\t' || c == '\r');
        if (blank) return true;  // "" is the identity
        std::shared_ptr<CheckedModule> m = lib.parse_check(src, plan.name + ".transform", true);
        if (!m->ok) return false;
        if (!m->ret) {
            d.error(src.where, "a transform must end with a matrix expression such as T(X)⋅`R_x`(r)");
            return false;
        }
        if (m->primary_type != Type::matrix(4, 4)) {
            d.error(m->ret->value->span, fmt::format("a transform must be a 4×4 matrix, but this is {}", m->primary_type.str()));
            return false;
        }
        // Evaluated once here, at the parameters' values (the default the sliders start at).
        ir::Module scratch;
        LowerContext ctx{scratch, {}, {}};
        int fn = lower_module(*m, plan.name + ".transform", plan.name + "_transform", ctx);
        plan.transform_uses_inputs = uses_inputs(scratch, fn);
        std::vector<ir::Value> args;
        std::vector<std::string> settings;
        for (const auto& p : m->params) {
            args.push_back({p.type, p.value});
            settings.push_back(fmt::format("{} = {}", p.name, join_values(p.value)));
        }
        std::vector<double> v;
        try {
            v = ir::evaluate(scratch, fn, args).v;
        } catch (const ir::EvalLimit& limit) {
            d.error(limit.span, fmt::format("evaluating the transform would take more than {} steps", limits::kMaxEvalSteps));
            return false;
        }
        plan.transform_comment = std::string(sm.slice(m->ret->span));
        for (char& c : plan.transform_comment)
            if (c == '\n' || c == '\r') c = ' ';
        if (!settings.empty()) plan.transform_comment += fmt::format(" with {}", fmt::join(settings, ", "));
        for (double x : v)
            if (!std::isfinite(x)) {
                d.error(m->ret->value->span, "the transform evaluates to a matrix with non-finite entries");
                return false;
            }
        // The last row (0, 0, 0, 1); `where` names the moment or slider values when not the parameters' defaults.
        auto affine = [&](const std::vector<double>& w, const std::string& where) {
            if (std::fabs(w[12]) <= 1e-9 && std::fabs(w[13]) <= 1e-9 && std::fabs(w[14]) <= 1e-9 && std::fabs(w[15] - 1) <= 1e-9) return true;
            d.error(m->ret->value->span,
                    fmt::format("the transform's last row is ({}, {}, {}, {}){}, not (0, 0, 0, 1): only affine transforms are "
                                "supported{}", w[12], w[13], w[14], w[15], where.empty() ? "" : " at " + where,
                                where.empty() ? "" : ", at every moment and slider value (the shader never reads the last row, "
                                                     "and would draw it as if it were (0, 0, 0, 1))"));
            return false;
        };
        if (!affine(v, "")) return false;
        // A transform that moves (time, the mouse) or has sliders is inverted at run time as an affine map: its
        // last row is taken to be (0, 0, 0, 1) and never read. It must be so at other moments and slider values
        // too: [1 0 0 0; 0 1 0 0; 0 0 1 0; time 0 0 1], affine at time 0 only, was accepted and drew as if time
        // were 0 (a new user's trial, stop 38). Checked at six moments, the sliders at their ends in turn.
        // The same samples give the largest condition number the map reaches (the step cap's growth: a scale that
        // thins with time, S((0.55 + 0.5 sin(time), 1, 1)), or with a slider, was sized at time 0 and at the
        // slider's default, and its rays stopped short at other moments: a trial's funnel of sky at time 10.1).
        // Moving maps are sampled over the first 32 seconds too, every 0.25 s (not a proof: a map can thin
        // between samples or later; `max_steps` in [render] sets the cap outright).
        bool sliders = false;
        for (const auto& p : m->params) sliders |= p.bounded;
        double sampled_cond = 1;
        if (plan.transform_uses_inputs || sliders) {
            std::vector<double> moments = {0.37, 1, 2.5, 10, 41.3, 117};
            if (plan.transform_uses_inputs)
                for (int q = 1; q <= 128; ++q) moments.push_back(0.25 * q);
            for (int k = 0; k < int(moments.size()); ++k) {
                ir::EvalInputs in;
                in.time = moments[size_t(k)];
                in.mouse[0] = 0.13 + 0.15 * (k % 6);
                in.mouse[1] = 0.91 - 0.15 * (k % 6);
                std::vector<ir::Value> at;
                std::vector<std::string> where;
                if (plan.transform_uses_inputs) where.push_back(fmt::format("time = {:g}, mouse = ({:g}, {:g})", in.time, in.mouse[0], in.mouse[1]));
                for (const auto& p : m->params) {
                    std::vector<double> x = p.bounded ? (k % 2 ? p.hi : p.lo) : p.value;
                    if (p.bounded) where.push_back(fmt::format("{} = {}", p.name, join_values(x)));
                    at.push_back({p.type, x});
                }
                std::vector<double> w;
                try {
                    w = ir::evaluate(scratch, fn, at, in).v;
                } catch (const ir::EvalLimit&) {
                    break;  // (the default's evaluation fit the budget: these differ only in values)
                }
                bool finite = true;
                for (double x : w) finite &= std::isfinite(x);
                if (!finite) continue;  // a singular moment (a scale through 0): the run time copes
                if (!affine(w, fmt::format("{}", fmt::join(where, ", ")))) return false;
                sampled_cond = std::max(sampled_cond, condition_number(w));
            }
        }
        // Invertible when the linear part L is: its condition number ‖L‖_F·‖L⁻¹‖_F, L⁻¹ = adj(L)/det(L) (cofactors),
        // at most 10¹² (past that, neither the inverse nor float32 arithmetic with it means anything).
        const double a = v[0], b = v[1], c = v[2], e = v[4], f = v[5], g = v[6], h = v[8], i = v[9], j = v[10];
        const double cof[9] = {f * j - g * i, -(e * j - g * h), e * i - f * h, -(b * j - c * i), a * j - c * h,
                               -(a * i - b * h), b * g - c * f, -(a * g - c * e), a * f - b * e};
        const double det = a * cof[0] + b * cof[1] + c * cof[2];
        double nl = 0, na = 0;
        for (int k : {0, 1, 2, 4, 5, 6, 8, 9, 10}) nl += v[size_t(k)] * v[size_t(k)];
        for (double x : cof) na += x * x;
        const double cond = std::sqrt(nl) * std::sqrt(na) / std::fabs(det);
        if (det == 0 || !std::isfinite(cond)) {
            d.error(m->ret->value->span, "the transform is singular (it flattens space and has no inverse)");
            return false;
        }
        if (cond > 1e12) {
            d.error(m->ret->value->span, fmt::format("the transform is too badly conditioned to invert: its condition number is "
                                                     "{:.2g} (at most 10¹²: float32 keeps 7 digits)", cond));
            return false;
        }
        bool singular = false;
        std::vector<double> inv = ir::mat_inverse(v, 4, &singular);
        if (singular) {
            // Gauss-Jordan's pivot test is relative to the largest entry, the homogeneous 1 included: a uniform
            // scale of 10²⁰ fails it. The adjugate's inverse, then: [L⁻¹, −L⁻¹t].
            inv.assign(16, 0.0);
            for (int r = 0; r < 3; ++r) {
                for (int k = 0; k < 3; ++k) inv[size_t(4 * r + k)] = cof[3 * k + r] / det;
                inv[size_t(4 * r + 3)] = -(inv[size_t(4 * r)] * v[3] + inv[size_t(4 * r + 1)] * v[7] + inv[size_t(4 * r + 2)] * v[11]);
            }
            inv[15] = 1;
        }
        plan.has_transform = true;
        plan.inv_linear = {inv[0], inv[1], inv[2], inv[4], inv[5], inv[6], inv[8], inv[9], inv[10]};
        plan.inv_offset = {inv[3], inv[7], inv[11]};
        double norm = spectral_norm3(plan.inv_linear);
        plan.scale = std::fabs(norm - 1) < 1e-9 ? 1.0 : 1.0 / norm;
        // ‖L⁻¹‖‖L‖, the spectral condition number: 1 for rotations and uniform scales, σ_max/σ_min for S((0.05, 1, 1)).
        plan.step_shortening = std::max({1.0, norm * spectral_norm3({a, b, c, e, f, g, h, i, j}), sampled_cond});
        if (plan.step_shortening < 1 + 1e-9) plan.step_shortening = 1;
        // What the shader computes with — the inverse, its offset and the scale — must be float32 numbers: past
        // 3.4·10³⁸ they were clamped, below 1.2·10⁻³⁸ flushed to 0 or denormal (S((10⁶⁰, …)) drew everything
        // inside the shape; T((3e38, …))⋅T((3e38, …)) moved it silently).
        // Products of rounding's coefficients (cos(π/2) = 6·10⁻¹⁷ in R_y(π)⋅R_x(π/2)⋅R_z(π) with a scale) fall below
        // float32's range beside entries near 1: they are 0 (10²⁰ times smaller than the map's largest entry, they
        // move nothing a float can tell), not an error. A map whose entries are all that small still is one.
        double largest = 0;
        for (double x : plan.inv_linear) largest = std::max(largest, std::fabs(x));
        for (double o : plan.inv_offset) largest = std::max(largest, std::fabs(o));
        auto flush = [&](double& x) {
            if (x != 0 && std::fabs(x) < 1.2e-38 && std::fabs(x) <= 1e-20 * largest) x = 0;
        };
        for (double& x : plan.inv_linear) flush(x);
        for (double& x : plan.inv_offset) flush(x);
        std::vector<double> used = plan.inv_linear;
        used.insert(used.end(), plan.inv_offset.begin(), plan.inv_offset.end());
        used.push_back(plan.scale);
        for (double x : used)
            if (std::fabs(x) > 3.4e38 || (x != 0 && std::fabs(x) < 1.2e-38)) {
                d.error(m->ret->value->span, fmt::format("the transform leaves float32's range, which shaders compute in: its "
                                                         "inverse holds {:.3g} (float32 keeps magnitudes from 1.2e-38 to 3.4e38)", x));
                return false;
            }
        // Nor may the object-space points of the scene's reach (max_dist around the camera) square past float32's
        // range: lengths of them would be ∞ (a uniform scale of 10⁻²⁰ put ∞ in every pixel's distance).
        double reach = s.render.max_dist;
        for (double c : s.camera.position) reach += std::fabs(c);
        double far = norm * reach;
        for (double o : plan.inv_offset) far += std::fabs(o);
        if (far > 1e19) {
            d.error(m->ret->value->span, fmt::format("the transform maps the scene's reach (max_dist {} around the camera) to object "
                                                     "coordinates up to {:.3g}, whose squares overflow float32: scale it less",
                                                     s.render.max_dist, far));
            return false;
        }
        plan.transform = std::move(m);
        return true;
    }

    const CheckedModule* module(const std::string& name, Span span, ast::ModuleKind kind) {
        const char* what = kind == ast::ModuleKind::Shape ? "shape" : "material";
        const CheckedModule* m = lib.get(name, span);
        if (!m) {
            auto& e = d.error(span, fmt::format("unknown {} '{}'", what, name));
            if (auto sug = did_you_mean(name, lib.names())) Diagnostics::note(e, span, fmt::format("did you mean '{}'?", *sug));
            return nullptr;
        }
        if (m->ast.kind != kind) {
            d.error(span, fmt::format("'{}' is not a {} (its module does not start with '{}')", name, what, what));
            return nullptr;
        }
        return m->ok ? m : nullptr;
    }

    // The module checked for the sequence lengths an instance's overrides give (x = 3 points where the module's
    // default has 2): a variant of its own (ModuleLibrary::variant), else the module itself.
    // Null where the lengths cannot be: two sequences of one index given different lengths, or one past iqc's size
    // limit (an error at the override: a trial's were located in the module and said the default's length was the
    // only one allowed).
    const CheckedModule* sized(const CheckedModule* m, const std::string& name, const std::vector<ParamOverride>& ovs) {
        std::map<std::string, int> lengths;
        std::map<std::string, const ParamOverride*> given;
        std::set<std::string> overridden;  // (every sequence the instance sets, of the module's length or another)
        for (const auto& ov : ovs) {
            const int pi = m->find_param(ov.name);
            if (pi < 0) continue;
            const Type& t = m->params[size_t(pi)].type;
            if (t.is_array()) overridden.insert(m->params[size_t(pi)].name);
            const int n = std::max(1, t.is_array() ? t.element().components() : 1);
            if (t.is_array() && !ov.value.empty() && int(ov.value.size()) != t.components() && int(ov.value.size()) % n == 0) {
                if (ov.value.size() > size_t(limits::kMaxComponents)) {
                    d.error(ov.span, fmt::format("'{}' would have {} elements ({} components): iqc allows at most {} components in "
                                                 "a sequence", ov.name, ov.value.size() / size_t(n), ov.value.size(), limits::kMaxComponents));
                    return nullptr;
                }
                lengths[m->params[size_t(pi)].name] = int(ov.value.size()) / n;
                given[m->params[size_t(pi)].name] = &ov;
            }
        }
        if (lengths.empty()) return m;
        // Sequences indexed by one letter have one length: each overridden one against the others (given or default).
        for (const auto& [seq, n] : lengths) {
            const ParamInfo& p = m->params[size_t(m->find_param(seq))];
            for (const ParamInfo& q : m->params) {
                if (q.name == seq || q.seq_index.empty() || q.seq_index != p.seq_index || !q.type.is_array()) continue;
                auto other = lengths.find(q.name);
                const int nq = other != lengths.end() ? other->second : q.type.count;
                if (nq == n) continue;
                const bool set_here = overridden.count(q.name) > 0;
                const std::string fix = set_here ? "give both one length"
                                                 : fmt::format("give '{}' {} element{} too", q.name, n, n == 1 ? "" : "s");
                d.error(given[seq]->span, fmt::format("'{}' has {} element{} here, but '{}' has {}{}: sequences indexed by {} have one "
                                                      "length; {}", seq, n, n == 1 ? "" : "s", q.name, nq,
                                                      set_here ? " here" : " (its default)", p.seq_index, fix));
                return nullptr;
            }
        }
        const CheckedModule* v = lib.variant(name, lengths);
        return v && v->ok ? v : m;  // (a variant that fails to check has said why; the override's error follows)
    }

    bool plan(const InstanceDesc& inst, InstancePlan& plan) {
        plan.desc = &inst;
        plan.shape = module(inst.type, inst.type_span, ast::ModuleKind::Shape);
        if (!plan.shape) return false;
        plan.shape = sized(plan.shape, inst.type, inst.shape_params);
        if (!plan.shape) return false;
        plan.query = plan.shape->roles.empty() ? -1 : plan.shape->roles[0];
        if (plan.query < 0) return false;  // the checker reported it
        bool ok = true;
        for (auto& p : plan.shape->params) plan.shape_values.push_back(p.value);
        ok &= apply_overrides(inst.shape_params, *plan.shape, "shape", {plan.query}, plan.shape_values);
        if (!inst.material.empty()) {
            plan.material = module(inst.material, inst.material_span, ast::ModuleKind::Material);
            if (!plan.material) return false;
            plan.material = sized(plan.material, inst.material, inst.material_params);
            if (!plan.material) return false;
            for (auto& p : plan.material->params) plan.material_values.push_back(p.value);
            // The footprint w_P (ℝ³) is the renderer's, like p, N̂ and I; under another type it is an ordinary
            // parameter, which a writer of w_P most likely did not mean: a warning.
            std::vector<int> bound = plan.material->roles;
            if (int fp = plan.material->find_param(kFootprint); fp >= 0) {
                const ParamInfo& w = plan.material->params[size_t(fp)];
                if (w.type == Type::vector(3)) bound.push_back(fp);
                else if (warned_footprint_.insert(plan.material).second)
                    d.warning(inst.material_span, fmt::format("material '{}' has a parameter '{}' of type {}: the renderer binds "
                                                              "the pixel's footprint only to a '{}' in ℝ³, so this one is an "
                                                              "ordinary parameter", inst.material, kFootprint, w.type.str(), kFootprint));
            }
            ok &= apply_overrides(inst.material_params, *plan.material, "material", bound, plan.material_values);
        } else if (!inst.material_params.empty()) {
            d.error(inst.material_params.front().span, "'material_params' needs a 'material'");
            ok = false;
        }
        ok &= plan_transform(inst, plan);
        return ok;
    }
};

}  // namespace

bool plan_instances(const SceneDesc& scene, ModuleLibrary& lib, SourceManager& sm, Diagnostics& d,
                    std::vector<InstancePlan>& plans, bool strict_ranges) {
    size_t before = d.error_count();
    Planner planner{scene, lib, sm, d, strict_ranges, {}};
    plans.assign(scene.instances.size(), {});
    // Explicit names first, so that generated ones (`<type>_<n>`) avoid them.
    std::map<std::string, Span> explicit_names;
    for (const auto& inst : scene.instances) {
        if (inst.name.empty()) continue;
        auto [it, fresh] = explicit_names.emplace(inst.name, inst.name_span);
        if (!fresh) {
            auto& e = d.error(inst.name_span, fmt::format("two instances are named '{}'", inst.name));
            Diagnostics::note(e, it->second, "the other one");
        }
    }
    std::set<std::string> taken;
    for (const auto& [n, span] : explicit_names) taken.insert(n);
    std::map<std::string, int> counts;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const InstanceDesc& inst = scene.instances[i];
        InstancePlan& p = plans[i];
        if (!inst.name.empty()) {
            p.name = inst.name;
        } else {
            do p.name = fmt::format("{}_{}", inst.type, ++counts[inst.type]);
            while (taken.count(p.name));
            taken.insert(p.name);
        }
        planner.plan(inst, p);
    }
    // Blends name instances: each at most once, in one blend.
    std::map<std::string, size_t> by_name;
    std::vector<std::string> names;
    for (size_t i = 0; i < plans.size(); ++i) {
        by_name[plans[i].name] = i;
        names.push_back(plans[i].name);
    }
    std::map<size_t, Span> blended;
    for (size_t b = 0; b < scene.blends.size(); ++b)
        for (const auto& [name, span] : scene.blends[b].shapes) {
            auto it = by_name.find(name);
            if (it == by_name.end()) {
                auto& e = d.error(span, fmt::format("no instance is named '{}'", name));
                if (auto s = did_you_mean(name, names)) Diagnostics::note(e, span, fmt::format("did you mean '{}'?", *s));
                continue;
            }
            if (auto [at, fresh] = blended.emplace(it->second, span); !fresh) {
                auto& e = d.error(span, fmt::format("'{}' is already blended", name));
                Diagnostics::note(e, at->second, "here");
                continue;
            }
            plans[it->second].blend = int(b);
        }
    return d.error_count() == before;
}

}  // namespace iqc
