#include "sema/Builtins.h"

#include <algorithm>

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
double b_asinh(double x) { return std::asinh(x); }
double b_acosh(double x) { return std::acosh(x); }
double b_atanh(double x) { return std::atanh(x); }
double b_cot(double x) { return 1.0 / std::tan(x); }
double b_sec(double x) { return 1.0 / std::cos(x); }
double b_csc(double x) { return 1.0 / std::sin(x); }
double b_log2(double x) { return std::log2(x); }
double b_log10(double x) { return std::log10(x); }

// Other spellings of a built-in (I♥LA's trigonometry module accepts both).
struct Alias {
    const char* alias;
    const char* name;
};
const Alias kAliases[] = {{"arcsin", "asin"}, {"arccos", "acos"}, {"arctan", "atan"}, {"arsinh", "asinh"},
                          {"arcosh", "acosh"}, {"artanh", "atanh"}, {"trace", "tr"}};
}  // namespace

const std::vector<BuiltinInfo>& builtins() {
    static const std::vector<BuiltinInfo> table = {
        // name     import          signature          eval1    eval2    GLSL  reserved  matrices
        {"sin", "trigonometry", Sig::Elementwise1, b_sin, nullptr, "sin", true, true},
        {"cos", "trigonometry", Sig::Elementwise1, b_cos, nullptr, "cos", true, true},
        {"tan", "trigonometry", Sig::Elementwise1, b_tan, nullptr, "tan", true, true},
        {"asin", "trigonometry", Sig::Elementwise1, b_asin, nullptr, "asin", true, true},
        {"acos", "trigonometry", Sig::Elementwise1, b_acos, nullptr, "acos", true, true},
        {"atan", "trigonometry", Sig::Elementwise1, b_atan, nullptr, "atan", true, true},
        {"atan2", "trigonometry", Sig::Elementwise2, nullptr, b_atan2, "atan", true},
        {"sinh", "trigonometry", Sig::Elementwise1, b_sinh, nullptr, "sinh", true, true},
        {"cosh", "trigonometry", Sig::Elementwise1, b_cosh, nullptr, "cosh", true, true},
        {"tanh", "trigonometry", Sig::Elementwise1, b_tanh, nullptr, "tanh", true, true},
        {"asinh", "trigonometry", Sig::Elementwise1, b_asinh, nullptr, "asinh", false, true},
        {"acosh", "trigonometry", Sig::Elementwise1, b_acosh, nullptr, "acosh", false, true},
        {"atanh", "trigonometry", Sig::Elementwise1, b_atanh, nullptr, "atanh", false, true},
        {"cot", "trigonometry", Sig::Elementwise1, b_cot, nullptr, "1.0 / tan(#)", false, true},
        {"sec", "trigonometry", Sig::Elementwise1, b_sec, nullptr, "1.0 / cos(#)", false, true},
        {"csc", "trigonometry", Sig::Elementwise1, b_csc, nullptr, "1.0 / sin(#)", false, true},
        {"e", "trigonometry", Sig::Constant, nullptr, nullptr, "", false},  // Euler's number
        {"exp", "", Sig::Elementwise1, b_exp, nullptr, "exp", true},
        {"log", "", Sig::Elementwise1, b_log, nullptr, "log", true},
        {"ln", "", Sig::Elementwise1, b_log, nullptr, "log", true},
        {"log_2", "", Sig::Elementwise1, b_log2, nullptr, "log2", false},           // log_2(x), log₂(x)
        {"log_10", "", Sig::Elementwise1, b_log10, nullptr, "(log(#) * 0.4342944819032518)", false},  // log_10(x)
        {"sqrt", "", Sig::Elementwise1, b_sqrt, nullptr, "sqrt", true},
        {"abs", "", Sig::Elementwise1, b_abs, nullptr, "abs", true},
        {"floor", "", Sig::Elementwise1, b_floor, nullptr, "floor", true},
        {"ceil", "", Sig::Elementwise1, b_ceil, nullptr, "ceil", true},
        {"sign", "", Sig::Elementwise1, b_sign, nullptr, "sign", true},
        {"fract", "", Sig::Elementwise1, b_fract, nullptr, "fract", true},
        // GLSL's round() leaves halves to the implementation; the evaluator rounds them up, and so does this.
        {"round", "", Sig::Elementwise1, b_round, nullptr, "floor(# + 0.5)", true},
        {"mod", "", Sig::Elementwise2, nullptr, b_mod, "mod", true},
        {"pow", "", Sig::Elementwise2, nullptr, b_pow, "pow", true},
        {"step", "", Sig::Elementwise2, nullptr, b_step, "step", true},
        {"min", "", Sig::Nary, nullptr, b_min, "min", true},
        {"max", "", Sig::Nary, nullptr, b_max, "max", true},
        {"clamp", "", Sig::Clamp, nullptr, nullptr, "clamp", true},
        {"smoothstep", "", Sig::Clamp, nullptr, nullptr, "smoothstep", true},  // (edge0, edge1, x)
        {"mix", "", Sig::Mix, nullptr, nullptr, "mix", true},
        {"length", "", Sig::Length, nullptr, nullptr, "length", true},
        {"normalize", "", Sig::Normalize, nullptr, nullptr, "normalize", true},
        // I♥LA's linearalgebra module: lowered to the IR's own operations.
        {"tr", "linearalgebra", Sig::Trace, nullptr, nullptr, "", false},
        {"det", "linearalgebra", Sig::Det, nullptr, nullptr, "", false},
        {"inv", "linearalgebra", Sig::Inverse, nullptr, nullptr, "", false},
        {"diag", "linearalgebra", Sig::Diag, nullptr, nullptr, "", false},
        {"vec", "linearalgebra", Sig::Vec, nullptr, nullptr, "", false},
        {"rank", "linearalgebra", Sig::Unsupported, nullptr, nullptr, "", false},
        {"null", "linearalgebra", Sig::Unsupported, nullptr, nullptr, "", false},
        {"orth", "linearalgebra", Sig::Unsupported, nullptr, nullptr, "", false},
    };
    return table;
}

std::optional<int> find_builtin(std::string_view name) {
    for (const Alias& a : kAliases)
        if (name == a.alias) name = a.name;
    const auto& t = builtins();
    for (size_t i = 0; i < t.size(); ++i)
        if (name == t[i].name) return int(i);
    return std::nullopt;
}

std::vector<std::string> known_names() {
    std::vector<std::string> v;
    for (const auto& b : builtins())
        if (b.reserved) v.push_back(b.name);
    v.push_back("time");
    v.push_back("mouse");
    return v;
}

const std::vector<std::string>& builtin_modules() {
    static const std::vector<std::string> modules = {"trigonometry", "linearalgebra"};
    return modules;
}

bool is_builtin_module(std::string_view name) {
    const auto& m = builtin_modules();
    return std::find(m.begin(), m.end(), name) != m.end();
}

bool is_power_function(std::string_view name) {
    auto b = find_builtin(name);
    return b && std::string_view(builtin(*b).module) == "trigonometry" && builtin(*b).sig == Sig::Elementwise1;
}

std::vector<std::string> builtin_module_names(std::string_view module) {
    std::vector<std::string> v;
    for (const auto& b : builtins())
        if (module == b.module) v.push_back(b.name);
    for (const Alias& a : kAliases)
        if (module == builtin(*find_builtin(a.name)).module) v.push_back(a.alias);
    return v;
}

BuiltinCheck check_builtin(int id, const std::vector<Type>& args, std::string_view name) {
    BuiltinInfo b = builtin(id);
    std::string spelled(name.empty() ? std::string_view(b.name) : name);
    b.name = spelled.c_str();
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
    auto square = [&](size_t i) {
        if (!args[i].is_matrix() || args[i].rows != args[i].cols) {
            r.error = fmt::format("'{}' needs a square matrix, not {}", b.name, args[i].str());
            r.bad_arg = int(i);
            return false;
        }
        return true;
    };
    switch (b.sig) {
        case Sig::Elementwise1:
            if (!need(1)) break;
            if (b.matrices && args[0].is_matrix()) r.type = args[0];
            else if (numeric_vec(0)) r.type = args[0].kind == Type::Integer ? Type::scalar() : args[0];
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
        case Sig::Constant:
            r.error = fmt::format("'{}' is a number, not a function", b.name);
            break;
        case Sig::Trace:
        case Sig::Det:
            if (need(1) && square(0)) r.type = Type::scalar();
            break;
        case Sig::Inverse:
            if (need(1) && square(0)) r.type = args[0];
            break;
        case Sig::Diag:
            if (!need(1)) break;
            if (args[0].is_vector()) r.type = Type::matrix(args[0].rows, args[0].rows);
            else if (args[0].is_matrix() && args[0].rows == args[0].cols) r.type = Type::vector(args[0].rows);
            else {
                r.error = fmt::format("'diag' needs a vector (the diagonal of a new matrix) or a square matrix (to take "
                                      "its diagonal), not {}", args[0].str());
                r.bad_arg = 0;
            }
            break;
        case Sig::Vec:
            if (!need(1)) break;
            if (args[0].is_matrix()) r.type = Type::vector(args[0].rows * args[0].cols);
            else {
                r.error = fmt::format("'vec' needs a matrix, not {}", args[0].str());
                r.bad_arg = 0;
            }
            break;
        case Sig::Unsupported:
            r.error = spelled == "rank"
                          ? std::string("'rank' is not supported: it needs a numerical decomposition with a tolerance")
                          : fmt::format("'{}' is not supported: the size of its result depends on the values, and iqc's "
                                        "types have fixed sizes", b.name);
            break;
    }
    return r;
}

}  // namespace iqc
