#include "sema/Builtins.h"

#include <cmath>
#include <fmt/format.h>

namespace iqc {

namespace {
double b_sign(double x) { return x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0; }
double b_fract(double x) { return x - std::floor(x); }
double b_round(double x) { return std::floor(x + 0.5); }  // halves round up, the same in GLSL (below)
double b_mod(double x, double y) { return x - y * std::floor(x / y); }  // GLSL's mod
double b_step(double edge, double x) { return x < edge ? 0.0 : 1.0; }
double b_min(double a, double b) { return std::fmin(a, b); }
double b_max(double a, double b) { return std::fmax(a, b); }
double b_pow(double a, double b) { return std::pow(a, b); }
double b_atan2(double y, double x) { return std::atan2(y, x); }
double b_sqrt(double x) { return std::sqrt(x); }
double b_abs(double x) { return std::fabs(x); }
double b_exp(double x) { return std::exp(x); }
double b_log(double x) { return std::log(x); }
double b_floor(double x) { return std::floor(x); }
double b_ceil(double x) { return std::ceil(x); }
double b_sin(double x) { return std::sin(x); }
double b_cos(double x) { return std::cos(x); }
double b_tan(double x) { return std::tan(x); }
double b_asin(double x) { return std::asin(x); }
double b_acos(double x) { return std::acos(x); }
double b_atan(double x) { return std::atan(x); }
double b_sinh(double x) { return std::sinh(x); }
double b_cosh(double x) { return std::cosh(x); }
double b_tanh(double x) { return std::tanh(x); }
}  // namespace

const std::vector<BuiltinInfo>& builtins() {
    static const std::vector<BuiltinInfo> table = {
        // name     import          signature          eval1    eval2    GLSL
        {"sin", "trigonometry", Sig::Elementwise1, b_sin, nullptr, "sin"},
        {"cos", "trigonometry", Sig::Elementwise1, b_cos, nullptr, "cos"},
        {"tan", "trigonometry", Sig::Elementwise1, b_tan, nullptr, "tan"},
        {"asin", "trigonometry", Sig::Elementwise1, b_asin, nullptr, "asin"},
        {"acos", "trigonometry", Sig::Elementwise1, b_acos, nullptr, "acos"},
        {"atan", "trigonometry", Sig::Elementwise1, b_atan, nullptr, "atan"},
        {"atan2", "trigonometry", Sig::Elementwise2, nullptr, b_atan2, "atan"},
        {"sinh", "trigonometry", Sig::Elementwise1, b_sinh, nullptr, "sinh"},
        {"cosh", "trigonometry", Sig::Elementwise1, b_cosh, nullptr, "cosh"},
        {"tanh", "trigonometry", Sig::Elementwise1, b_tanh, nullptr, "tanh"},
        {"exp", "", Sig::Elementwise1, b_exp, nullptr, "exp"},
        {"log", "", Sig::Elementwise1, b_log, nullptr, "log"},
        {"ln", "", Sig::Elementwise1, b_log, nullptr, "log"},
        {"sqrt", "", Sig::Elementwise1, b_sqrt, nullptr, "sqrt"},
        {"abs", "", Sig::Elementwise1, b_abs, nullptr, "abs"},
        {"floor", "", Sig::Elementwise1, b_floor, nullptr, "floor"},
        {"ceil", "", Sig::Elementwise1, b_ceil, nullptr, "ceil"},
        {"sign", "", Sig::Elementwise1, b_sign, nullptr, "sign"},
        {"fract", "", Sig::Elementwise1, b_fract, nullptr, "fract"},
        {"round", "", Sig::Elementwise1, b_round, nullptr, "round"},  // emitted as floor(x + 0.5)
        {"mod", "", Sig::Elementwise2, nullptr, b_mod, "mod"},
        {"pow", "", Sig::Elementwise2, nullptr, b_pow, "pow"},
        {"step", "", Sig::Elementwise2, nullptr, b_step, "step"},
        {"min", "", Sig::Nary, nullptr, b_min, "min"},
        {"max", "", Sig::Nary, nullptr, b_max, "max"},
        {"clamp", "", Sig::Clamp, nullptr, nullptr, "clamp"},
        {"smoothstep", "", Sig::Clamp, nullptr, nullptr, "smoothstep"},  // (edge0, edge1, x)
        {"mix", "", Sig::Mix, nullptr, nullptr, "mix"},
        {"length", "", Sig::Length, nullptr, nullptr, "length"},
        {"normalize", "", Sig::Normalize, nullptr, nullptr, "normalize"},
    };
    return table;
}

std::optional<int> find_builtin(std::string_view name) {
    const auto& t = builtins();
    for (size_t i = 0; i < t.size(); ++i)
        if (name == t[i].name) return int(i);
    return std::nullopt;
}

std::vector<std::string> known_names() {
    std::vector<std::string> v;
    for (const auto& b : builtins()) v.push_back(b.name);
    v.push_back("time");
    v.push_back("mouse");
    return v;
}

bool is_builtin_module(std::string_view name) { return name == "trigonometry"; }

BuiltinCheck check_builtin(int id, const std::vector<Type>& args) {
    const BuiltinInfo& b = builtin(id);
    BuiltinCheck r;
    auto need = [&](size_t n) {
        if (args.size() != n) {
            r.error = fmt::format("'{}' takes {} argument{}, not {}", b.name, n, n == 1 ? "" : "s", args.size());
            return false;
        }
        return true;
    };
    auto numeric_vec = [&](size_t i) {
        if (!(args[i].is_scalar() || args[i].is_vector())) {
            r.error = fmt::format("'{}' needs a scalar or a vector, not {}", b.name, args[i].str());
            r.bad_arg = int(i);
            return false;
        }
        return true;
    };
    // Common type of operands where scalars broadcast: all vectors must have one size.
    auto common = [&](size_t from, size_t to) -> bool {
        Type t = Type::scalar();
        for (size_t i = from; i < to; ++i) {
            if (!numeric_vec(i)) return false;
            if (args[i].is_vector()) {
                if (t.is_vector() && t != args[i]) {
                    r.error = fmt::format("'{}' mixes {} and {}", b.name, t.str(), args[i].str());
                    r.bad_arg = int(i);
                    return false;
                }
                t = args[i];
            }
        }
        r.type = t;
        return true;
    };
    switch (b.sig) {
        case Sig::Elementwise1:
            if (need(1) && numeric_vec(0)) r.type = args[0].kind == Type::Integer ? Type::scalar() : args[0];
            break;
        case Sig::Elementwise2:
            if (need(2)) common(0, 2);
            break;
        case Sig::Nary:
            if (args.size() < 2) r.error = fmt::format("'{}' needs at least 2 arguments", b.name);
            else common(0, args.size());
            break;
        case Sig::Clamp:
        case Sig::Mix:
            if (need(3)) common(0, 3);
            break;
        case Sig::Length:
            if (need(1) && numeric_vec(0)) r.type = Type::scalar();
            break;
        case Sig::Normalize:
            if (need(1) && numeric_vec(0)) r.type = args[0];
            break;
    }
    return r;
}

}  // namespace iqc
