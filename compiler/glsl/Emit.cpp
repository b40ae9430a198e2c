#include "glsl/Emit.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fmt/format.h>
#include <functional>
#include <set>

#include "ir/Schedule.h"
#include "sema/Builtins.h"

namespace iqc::glsl {

using ir::Instr;
using ir::Op;
using ir::ValueId;

std::string type_name(const Type& t, std::string* why) {
    auto fail = [&](std::string w) {
        if (why) *why = std::move(w);
        return std::string();
    };
    switch (t.kind) {
        case Type::Scalar: return "float";
        case Type::Integer: return "int";
        case Type::Bool: return "bool";
        case Type::Vector:
            if (t.rows > 4) return fail(fmt::format("{} is larger than GLSL's largest vector (vec4)", t.str()));
            return fmt::format("vec{}", t.rows);
        case Type::Matrix:
            // A row vector (1×n) is a vecN: GLSL's v * M already treats v as a row.
            if (t.rows == 1) {
                if (t.cols > 4) return fail(fmt::format("{} is larger than GLSL's largest vector (vec4)", t.str()));
                return fmt::format("vec{}", t.cols);
            }
            if (t.rows > 4 || t.cols > 4)
                return fail(fmt::format("{} is larger than GLSL's largest matrix (mat4)", t.str()));
            if (t.rows == t.cols) return fmt::format("mat{}", t.rows);
            return fmt::format("mat{}x{}", t.cols, t.rows);  // GLSL: columns x rows
        case Type::Array: return type_name(t.element(), why);
        default: return fail("invalid type");
    }
}

std::string float_literal(double v) {
    if (std::isnan(v)) return "(0.0 / 0.0)";
    if (std::isinf(v)) return v > 0 ? "1.0e38" : "-1.0e38";
    float f = static_cast<float>(v);
    if (std::isinf(f)) return f > 0 ? "1.0e38" : "-1.0e38";  // beyond float's range (a folded 1e30 * 1e30), as ∞
    if (f == 0.0f) f = 0.0f;  // no "-0.0"
    std::string s = fmt::format("{}", f);
    size_t e = s.find_first_of("eE");
    std::string mant = e == std::string::npos ? s : s.substr(0, e);
    std::string exp = e == std::string::npos ? "" : s.substr(e);
    if (mant.find('.') == std::string::npos) mant += ".0";
    return mant + exp;
}

std::string texture_fetch(const GlobalStorage& s, const Type& t, const std::string& k, bool k_const) {
    auto texel = [&](int col) {
        std::string i = s.texels == 1 ? k : fmt::format("{} * {}", s.texels, k_const ? k : "(" + k + ")");
        if (s.texel + col != 0) i = k == "0" ? std::to_string(s.texel + col) : fmt::format("{} + {}", s.texel + col, i);
        return fmt::format("iqc_fetch({})", i);
    };
    if (t.kind == Type::Integer) return fmt::format("int({}.x)", texel(0));  // stored as an exact float (< 2^24)
    if (t.is_scalar()) return texel(0) + ".x";
    if (t.is_vector()) return texel(0) + "." + std::string("xyzw", size_t(t.rows));
    std::vector<std::string> cols;
    for (int c = 0; c < t.cols; ++c) cols.push_back(texel(c) + "." + std::string("xyzw", size_t(t.rows)));
    return fmt::format("{}({})", type_name(t), fmt::join(cols, ", "));
}

namespace {

// The components of a value of type t (not an array) as GLSL constructor arguments, column-major.
std::vector<std::string> constructor_args(const Type& t, const std::vector<double>& v, size_t base,
                                          const std::function<std::string(double)>& lit) {
    std::vector<std::string> parts;
    if (t.is_matrix() && t.rows > 1) {
        for (int c = 0; c < t.cols; ++c)
            for (int r = 0; r < t.rows; ++r) parts.push_back(lit(v[base + size_t(r * t.cols + c)]));
    } else {
        for (int k = 0; k < std::max(1, t.components()); ++k) parts.push_back(lit(v[base + size_t(k)]));
    }
    return parts;
}

std::string single(const Type& t, const std::vector<double>& v, size_t base, bool compact) {
    if (t.kind == Type::Integer) return fmt::format("{}", static_cast<long long>(std::llround(v[base])));
    if (t.kind == Type::Bool) return v[base] != 0 ? "true" : "false";
    if (t.is_scalar()) return float_literal(v[base]);
    std::string tn = type_name(t);
    if (t.is_matrix() && t.rows == t.cols && !compact) {  // x·I: matN(x)
        bool diagonal = true;
        for (int r = 0; r < t.rows; ++r)
            for (int c = 0; c < t.cols; ++c)
                diagonal &= r == c ? v[base + size_t(r * t.cols + c)] == v[base] : v[base + size_t(r * t.cols + c)] == 0;
        if (diagonal) return fmt::format("{}({})", tn, float_literal(v[base]));
    }
    auto lit = [&](double x) {
        if (!compact) return float_literal(x);
        float f = static_cast<float>(x);
        if (f == std::floor(f) && std::fabs(f) < 1e7f) return fmt::format("{}", static_cast<long long>(f));
        std::string s = float_literal(x);
        if (s.rfind("0.", 0) == 0) s = s.substr(1);
        else if (s.rfind("-0.", 0) == 0) s = "-" + s.substr(2);
        return s;
    };
    std::vector<std::string> parts = constructor_args(t, v, base, lit);
    if (t.is_vector()) {
        bool same = true;
        for (auto& p : parts) same &= p == parts[0];
        if (same) return fmt::format("{}({})", tn, parts[0]);
    }
    return fmt::format("{}({})", tn, fmt::join(parts, compact ? "," : ", "));
}

std::string any_constant(const Type& t, const std::vector<double>& v, bool compact) {
    if (!t.is_array()) return single(t, v, 0, compact);
    Type e = t.element();
    size_t n = size_t(std::max(1, e.components()));
    std::vector<std::string> items;
    for (int k = 0; k < t.count; ++k) items.push_back(single(e, v, size_t(k) * n, compact));
    return fmt::format("{}[{}]({})", type_name(e), t.count, fmt::join(items, compact ? "," : ", "));
}

}  // namespace

std::string constant(const Type& t, const std::vector<double>& v) { return any_constant(t, v, false); }
std::string compact_constant(const Type& t, const std::vector<double>& v) { return any_constant(t, v, true); }

const std::string& Emitter::function_name(int fn) {
    auto it = names_.find(fn);
    if (it != names_.end()) return it->second;
    const ir::Function& f = m_.functions[size_t(fn)];
    return names_[fn] = globals_.unique(f.glsl_name.empty() ? f.name : f.glsl_name);
}

void Emitter::set_function_name(int fn, const std::string& name) {
    globals_.reserve(name);
    names_[fn] = name;
}

std::vector<int> Emitter::closure(const std::vector<int>& roots) const {
    std::vector<int> order;
    std::set<int> seen;
    std::function<void(int)> visit = [&](int fn) {
        if (seen.count(fn)) return;
        seen.insert(fn);
        std::function<void(int)> scan = [&](int g) {
            for (const Instr& in : m_.functions[size_t(g)].body) {
                if (in.op == Op::Call) visit(in.aux);
                if (in.op == Op::Loop) scan(in.aux);  // bodies are emitted inline, their callees are not
            }
        };
        scan(fn);
        order.push_back(fn);
    };
    for (int r : roots) visit(r);
    return order;
}

namespace {

const char* kSwizzle = "xyzw";
// A loop of more trips than kLoopTripsRolled runs ceil(trips / kLoopTripsRolled) iterations per trip, at
// most kMaxUnroll (see FunctionEmitter::loop: llvmpipe's limit of 65,535 loop iterations per invocation).
constexpr long long kLoopTripsRolled = 64;
constexpr long long kMaxUnroll = 16;

namespace {
constexpr double kSumLoopBudget = 48;  // rolled sums' loop iterations per call of a root where the calls are unknown
constexpr double kLoopIterations = 60000;  // of llvmpipe's 65,535 per invocation, for the IR's loops
constexpr double kMaxOtherUnroll = 32;     // iterations per trip of a loop other than a rolled sum's, at most

// Iterations per trip by default: long loops run ceil(trips / kLoopTripsRolled) per trip, at most kMaxUnroll.
int default_unroll(long long trips) {
    return trips > kLoopTripsRolled ? int(std::min<long long>(kMaxUnroll, (trips + kLoopTripsRolled - 1) / kLoopTripsRolled)) : 1;
}

// A loop's constant trip count (hi - lo + 1), or -1.
long long loop_trips(const ir::Function& f, const ir::Instr& in) {
    const ir::Instr& hi = f.body[in.args[0]];
    if (hi.op != ir::Op::Const || hi.data.empty() || in.data.empty()) return -1;
    return std::llround(hi.data[0]) - std::llround(in.data[0]) + 1;
}
}  // namespace

}  // namespace

int Emitter::unroll_of(int body_fn, long long trips) const {
    auto it = unroll_.find(body_fn);
    return int(std::min<long long>(trips, it != unroll_.end() ? it->second : default_unroll(trips)));
}

void Emitter::limit_loop_iterations(const std::vector<int>& roots, double evaluations) {
    // Loop iterations per call: (all loops, rolled sums' loops), with the unrolling chosen so far.
    // `guess`: the trips counted for a loop whose bound is known only when running (kLoopTripsRolled; 1 for the
    // iterations surely made).
    std::map<std::pair<int, long long>, std::pair<double, double>> memo;
    std::function<std::pair<double, double>(int, long long)> count = [&](int fn, long long guess) -> std::pair<double, double> {
        if (auto it = memo.find({fn, guess}); it != memo.end()) return it->second;
        memo[{fn, guess}] = {0, 0};  // (no recursion in the IR; a guard all the same)
        const ir::Function& f = m_.functions[size_t(fn)];
        double all = 0, sums = 0;
        for (const ir::Instr& in : f.body) {
            if (in.op == ir::Op::Call) {
                auto [a, s] = count(in.aux, guess);
                all += a, sums += s;
            } else if (in.op == ir::Op::Loop) {
                long long trips = loop_trips(f, in);
                if (trips <= 0) trips = guess;
                const double iterations = std::ceil(double(trips) / unroll_of(in.aux, trips));
                auto [a, s] = count(in.aux, guess);
                all += iterations + double(trips) * a;
                sums += (m_.functions[size_t(in.aux)].rolled_sum ? iterations : 0) + double(trips) * s;
            }
        }
        return memo[{fn, guess}] = {all, sums};
    };
    // iqc_prepare runs once per pixel (ir/passes/Hoist.h: the sums that read nothing of the query point), the
    // other roots at each of the pixel's evaluations.
    double sums = 0, others = 0, once = 0;
    for (int r : roots) {
        auto [a, s] = count(r, kLoopTripsRolled);
        if (m_.functions[size_t(r)].name == ir::names::kPrepare) {
            once = a;
            continue;
        }
        sums = std::max(sums, s);
        others = std::max(others, a - s);
    }
    const double per_evaluation = evaluations > 0 ? std::max(0.0, kLoopIterations - once) / evaluations : 0;
    const double budget = evaluations > 0 ? std::max(0.0, per_evaluation - others) : kSumLoopBudget;
    // The other loops (a group's members, a recurrence) of a root whose iterations surely made (loops of unknown
    // bounds once) pass the budget alone run their share of it: a group of 60 members marched with 2,048 steps
    // made 123,000 and drew blocks (trial76, N2). Each is unrolled up to kMaxOtherUnroll iterations a trip (the code
    // grows with it: beyond, the loop keeps that many).
    std::vector<double> other_ratio(m_.functions.size(), 1.0);
    bool others_over = false;
    for (int r : roots) {
        if (evaluations <= 0 || m_.functions[size_t(r)].name == ir::names::kPrepare) continue;
        auto [a, s] = count(r, 1);
        if (a - s <= per_evaluation) continue;
        others_over = true;
        std::vector<char> mine(m_.functions.size(), 0);
        ir::mark_reachable(m_, r, mine);
        for (size_t fn = 0; fn < mine.size(); ++fn)
            if (mine[fn]) other_ratio[fn] = std::min(other_ratio[fn], per_evaluation / (a - s));
    }
    if (sums <= budget && !others_over) return;
    // Each rolled sum's loop runs `ratio` of its iterations (at least one trip: fully unrolled), those the
    // evaluations run (iqc_prepare's, once per pixel, stay loops).
    const double ratio = sums > budget ? budget / sums : 1;
    std::vector<char> reached(m_.functions.size(), 0);
    for (int r : roots)
        if (m_.functions[size_t(r)].name != ir::names::kPrepare) ir::mark_reachable(m_, r, reached);
    for (size_t fn = 0; fn < m_.functions.size(); ++fn) {
        if (!reached[fn]) continue;
        for (const ir::Instr& in : m_.functions[fn].body) {
            if (in.op != ir::Op::Loop) continue;
            const bool rolled = m_.functions[size_t(in.aux)].rolled_sum;
            const double r = rolled ? ratio : other_ratio[fn];
            long long trips = loop_trips(m_.functions[fn], in);
            if (trips <= 0 || r >= 1) continue;
            const double iterations = std::ceil(double(trips) / default_unroll(trips));
            const double fewer = std::max(1.0, std::floor(iterations * r));
            const double unroll = std::ceil(double(trips) / fewer);
            unroll_[in.aux] = int(std::min<double>(double(trips), rolled ? unroll : std::max<double>(default_unroll(trips), std::min<double>(unroll, kMaxOtherUnroll))));
        }
    }
}

namespace {

constexpr int kSwizzleSize = 4;  // GLSL's widest vector; a larger IR vector has no GLSL type (already reported)

// Statement text (a formula as written) for a `//` comment: one line, nothing that could end the comment.
std::string one_line(const std::string& s) { return comment_text(s); }

constexpr int kMaxInlineDepth = 32;  // deepest expression emitted inline (then a variable)

struct FunctionEmitter {
    const ir::Module& m;
    const ir::Function& f;
    Emitter& em;
    Diagnostics& diags;
    Namer locals;
    ir::Schedule sched;
    std::vector<int> uses;
    std::vector<char> eager;       // a select's value operand that calls a function (iqc_distance_of): a statement first
    std::vector<int> depth;        // nesting of the value's expression as emitted (0: in a variable)
    std::vector<std::string> var;  // GLSL variable holding the value, if materialised
    std::map<ValueId, std::vector<std::string>> loop_states;  // a Loop's state variables
    bool failed = false;

    FunctionEmitter(const ir::Module& mod, const ir::Function& fn, Emitter& e, Diagnostics& d, const Namer& globals)
        : m(mod), f(fn), em(e), diags(d), locals(&globals) {}

    std::string type_of(const Type& t, Span span) {
        std::string why;
        std::string n = type_name(t, &why);
        if (n.empty() && !failed) {
            diags.error(span, fmt::format("cannot generate GLSL: {}", why));
            failed = true;
        }
        return n.empty() ? "float" : n;
    }

    const ir::Function& callee(const Instr& in) const { return m.functions[size_t(in.aux)]; }

    // Whether operand k of `in` is read as a GLSL int (else a ℤ operand is converted with float()).
    bool wants_int(const Instr& in, size_t k) const {
        bool int_result = in.type.kind == Type::Integer;
        switch (in.op) {
            case Op::Index: return k == 1;
            case Op::Switch: return k == 0 || int_result;
            case Op::Compare: return f.body[in.args[0]].type.kind == Type::Integer && f.body[in.args[1]].type.kind == Type::Integer;
            case Op::Add: case Op::Sub: case Op::Mul: case Op::Neg: case Op::Copy: case Op::IntDiv: case Op::IntMod:
                return int_result;
            case Op::Select: case Op::If: return k >= 1 && int_result;
            case Op::Call: return callee(in).params[k].type.kind == Type::Integer;
            case Op::Loop: return k == 0 || callee(in).params[k].type.kind == Type::Integer;
            default: return false;
        }
    }

    // Whether every component of a real value is an integer (where int(x) is ⌊x⌋ and FloorInt needs no floor):
    // constants with integer components, floor and ceil, and clamp, min, max, abs and components of such values.
    // (A lattice's cell range is clamp(ceil(...), 0, n - 1): its int(floor()) cost llvmpipe's compile ~1%.)
    bool integral(ValueId v, int depth = 0) {
        const Instr& in = f.body[v];
        if (depth > 8) return false;
        switch (in.op) {
            case Op::Const:
                return std::all_of(in.data.begin(), in.data.end(), [](double x) { return std::isfinite(x) && x == std::floor(x); });
            case Op::Extract: case Op::Copy:
                return integral(in.args[0], depth + 1);
            case Op::Builtin: {
                const std::string n = builtin(in.aux).name;
                if (n == "floor" || n == "ceil") return true;
                if (n != "clamp" && n != "min" && n != "max" && n != "abs") return false;
                for (ValueId a : in.args)
                    if (!integral(a, depth + 1)) return false;
                return true;
            }
            default: return false;
        }
    }

    // Whether the value is simple enough to repeat rather than give a variable.
    bool trivial(ValueId v) const {
        const Instr& in = f.body[v];
        return in.op == Op::Param || in.op == Op::Input || in.op == Op::Member || in.op == Op::Global ||
               (in.op == Op::Const && (in.type.is_scalar() || in.type.kind == Type::Bool));
    }

    // A value used more than once gets a variable when recomputing it would cost real work (a call, a
    // square root, ...) or repeat long text; cheap ones such as `P_L - p` stay inline for readability
    // (the driver's own CSE removes the repeat).
    bool worth_a_variable(ValueId v) {
        const Instr& in = f.body[v];
        switch (in.op) {
            case Op::Call: case Op::Inverse: case Op::Det: case Op::Dot: case Op::Cross: case Op::Select:
                return true;
            case Op::Builtin: {
                std::string n = builtin(in.aux).name;
                if (n != "abs" && n != "min" && n != "max" && n != "floor" && n != "ceil" && n != "sign") return true;
                break;
            }
            default: break;
        }
        return expr(v).size() > 40;
    }

    bool compound(ValueId v) const {
        if (!var[v].empty()) return false;
        const Instr& in = f.body[v];
        switch (in.op) {
            case Op::Add: case Op::Sub: case Op::Mul: case Op::Div: case Op::Hadamard: case Op::Compare: case Op::IntDiv:
            case Op::IntMod:
            case Op::And: case Op::Or: case Op::Select: case Op::Neg:
                return true;
            case Op::Const: return in.type.is_scalar() && in.data[0] < 0;
            default: return false;
        }
    }

    // s where v is the integer constant 2^s (s in [0, 30]), else -1.
    int power_of_two(ValueId v) const {
        const Instr& in = f.body[v];
        if (in.op != Op::Const || in.type.kind != Type::Integer || in.data.size() != 1) return -1;
        const double x = in.data[0];
        for (int s = 0; s <= 30; ++s)
            if (x == double(1LL << s)) return s;
        return -1;
    }

    // Operand k of `in` as its consumer reads it: `paren` puts a compound expression in parentheses.
    std::string arg(const Instr& in, size_t k, bool paren) {
        ValueId v = in.args[k];
        const Type& t = f.body[v].type;
        bool want = wants_int(in, k);
        if (t.kind == Type::Integer && !want) {
            const Instr& c = f.body[v];
            // An integer constant read as a float is a float literal (`0.0`, not `float(0)`).
            if (c.op == Op::Const && c.data.size() == 1 && var[v].empty()) {
                std::string lit = float_literal(c.data[0]);
                return paren && c.data[0] < 0 ? "(" + lit + ")" : lit;
            }
            return "float(" + expr(v) + ")";
        }
        if (want && t.kind == Type::Scalar) return "int(" + expr(v) + ")";
        std::string s = expr(v);
        return paren && compound(v) ? "(" + s + ")" : s;
    }

    // Component k of a vector: `.x` … `.w`, or `[k]` past GLSL's four (only reached after a type error).
    std::string component(ValueId v, int k) {
        return k < kSwizzleSize ? postfix_base(v) + "." + kSwizzle[k] : fmt::format("{}[{}]", postfix_base(v), k);
    }

    // A value as something `.x` or `[i]` may follow.
    std::string postfix_base(ValueId v) {
        std::string s = expr(v);
        const Instr& in = f.body[v];
        if (!var[v].empty() || in.op == Op::Param || in.op == Op::Builtin || in.op == Op::Call || in.op == Op::Construct ||
            in.op == Op::Dot || in.op == Op::Cross || in.op == Op::Transpose || in.op == Op::Inverse || in.op == Op::Global ||
            in.op == Op::Index || in.op == Op::Element || in.op == Op::At)
            return s;
        return "(" + s + ")";
    }

    const GlobalStorage* storage(int g) const {
        const auto* s = em.storage();
        return s && size_t(g) < s->size() ? &(*s)[size_t(g)] : nullptr;
    }

    std::string global(const Instr& in) {
        const GlobalStorage* s = storage(in.aux);
        // (a global GLSL cannot declare, a sequence of matrices past mat4 that a module's function now reads in
        // place: the error where its parameter is declared, as for the parameter it was)
        if (in.type.is_array()) type_of(in.type, in.span);
        // A plain parameter in the data texture (targets without uniform blocks): its texels.
        if (s && s->kind == GlobalStorage::Kind::Texture && !in.type.is_array()) return fetch(s, in.type, "0", true, in.span);
        // An array in the data texture read whole (a module's sequence parameter passed on as one value): the
        // function the declarations define for it gathers its elements.
        if (s && s->kind == GlobalStorage::Kind::Texture) return s->name + "()";
        return s ? s->name : identifier(m.globals[size_t(in.aux)].name);
    }

    // array[k]: an array's element, or from the data texture (one texel per vector, per matrix column).
    std::string index(const Instr& in) {
        const Instr& a = f.body[in.args[0]];
        const GlobalStorage* s = a.op == Op::Global ? storage(a.aux) : nullptr;
        std::string k = arg(in, 1, false);
        if (!s || s->kind != GlobalStorage::Kind::Texture) return postfix_base(in.args[0]) + "[" + k + "]";
        return fetch(s, in.type, k, f.body[in.args[1]].op == Op::Const, in.span);
    }

    // Element k (an int expression; `k_const` when a literal) of type t stored in the data texture at s.
    std::string fetch(const GlobalStorage* s, const Type& t, const std::string& k, bool k_const, const Span& span) {
        if (t.is_matrix() && t.rows > 1 && type_of(t, span).empty()) return "0.0";
        return texture_fetch(*s, t, k, k_const);
    }

    // An array's declarator after the name (`vec3 P[3]`); empty for other types.
    static std::string array_suffix(const Type& t) { return t.is_array() ? fmt::format("[{}]", t.count) : ""; }

    std::string construct(const Instr& in, ValueId v) {
        auto plain = [&](size_t i) { return arg(in, i, false); };
        std::string tn = type_of(in.type, in.span);
        if (in.type.is_array()) {  // a sequence's elements: vec3[3](a, b, c)
            std::vector<std::string> items;
            for (size_t i = 0; i < in.args.size(); ++i) items.push_back(plain(i));
            return fmt::format("{}{}({})", tn, array_suffix(in.type), fmt::join(items, ", "));
        }
        // A real number from one integer: float(n), once (the operand reads as a float already).
        if (in.type == Type::scalar() && in.args.size() == 1) return plain(0);
        // vec3(x, x, x) -> vec3(x)
        bool same = in.args.size() > 1;
        for (ValueId x : in.args) same &= (x == in.args[0]);
        if (same && f.body[in.args[0]].type.is_scalar() && in.type.is_vector()) return fmt::format("{}({})", tn, plain(0));
        // (p_1, p_3) -> p.xz
        if (in.type.is_vector()) {
            bool swz = true;
            ValueId src = 0;
            std::string sel;
            for (size_t i = 0; i < in.args.size() && swz; ++i) {
                const Instr& x = f.body[in.args[i]];
                if (x.op != Op::Extract || !f.body[x.args[0]].type.is_vector() || !var[in.args[i]].empty() ||
                    x.aux >= kSwizzleSize) {
                    swz = false;
                    break;
                }
                if (i == 0) src = x.args[0];
                else if (x.args[0] != src) swz = false;
                sel += kSwizzle[x.aux];
            }
            if (swz) return postfix_base(src) + "." + sel;
        }
        (void)v;
        // Components of one matrix operand: its upper-left block (mat3(M)) or a column's first rows (M[c].xyz).
        if (in.args.size() == size_t(in.type.components()) && !in.args.empty()) {
            const Instr& e0 = f.body[in.args[0]];
            ValueId src = e0.op == Op::Extract ? e0.args[0] : ValueId(-1);
            const Type* st = src != ValueId(-1) ? &f.body[src].type : nullptr;
            bool ok = st && st->is_matrix() && st->rows == st->cols && st->rows > 1;
            std::vector<int> at;
            for (size_t i = 0; ok && i < in.args.size(); ++i) {
                const Instr& x = f.body[in.args[i]];
                ok = x.op == Op::Extract && x.args[0] == src && var[in.args[i]].empty();
                if (ok) at.push_back(x.aux);
            }
            if (ok && in.type.is_matrix() && in.type.rows == in.type.cols && in.type.rows < st->rows) {
                bool block = true;
                for (int r = 0; r < in.type.rows; ++r)
                    for (int c = 0; c < in.type.cols; ++c) block &= at[size_t(r * in.type.cols + c)] == r * st->cols + c;
                if (block) return fmt::format("{}({})", tn, expr(src));
            }
            if (ok && in.type.is_vector() && in.type.rows < st->rows) {
                int col = at[0] % st->cols;
                bool column = true;
                for (int r = 0; r < in.type.rows; ++r) column &= at[size_t(r)] == r * st->cols + col;
                if (column) return fmt::format("{}[{}].{}", postfix_base(src), col, std::string(kSwizzle, size_t(in.type.rows)));
            }
        }
        std::vector<std::string> args;
        if (in.type.is_matrix() && in.type.rows > 1) {
            bool rows = true;
            for (ValueId a : in.args) rows &= f.body[a].type == Type::vector(in.type.cols);
            if (rows && int(in.args.size()) == in.type.rows && in.type.cols > 1) {
                // Whole rows: a matrix with them as columns, transposed.
                for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                Type cols_as_rows = Type::matrix(in.type.cols, in.type.rows);
                return fmt::format("transpose({}({}))", type_of(cols_as_rows, in.span), fmt::join(args, ", "));
            }
            // Row-major components (scalars, or vectors' components) -> GLSL's column-major constructor.
            std::vector<std::string> comps;
            for (size_t i = 0; i < in.args.size(); ++i) {
                const Type& t = f.body[in.args[i]].type;
                if (t.is_scalar()) comps.push_back(plain(i));
                else
                    for (int k = 0; k < t.components(); ++k) comps.push_back(component(in.args[i], k));
            }
            for (int c = 0; c < in.type.cols; ++c)
                for (int r = 0; r < in.type.rows; ++r) args.push_back(comps[size_t(r * in.type.cols + c)]);
        } else {
            for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
        }
        return fmt::format("{}({})", tn, fmt::join(args, ", "));
    }

    // A constant matrix (a Const, or a Constant global: an instance's world → object map) times a vector, row
    // by row where the matrix has zeros or ±1 entries: vec3(p.x, c * p.y + s * p.z, ...). LLVM without
    // fast-math keeps 0·x (it is not 0 for x = ∞ or NaN) and the matrix product computes every entry: a plate
    // turned about x took 9 multiplications for 4, twice a scene evaluation in a grazing ray's 128 steps.
    // Only where the vector is a name (it is read once per row); "" where it does not apply.
    std::string sparse_product(const Instr& in) {
        const Type& lt = f.body[in.args[0]].type;
        const Type& rt = f.body[in.args[1]].type;
        if (!lt.is_matrix() || lt.rows < 2 || lt.cols < 2 || !rt.is_vector() || rt.rows != lt.cols || in.type.kind == Type::Integer) return "";
        const Instr& mi = f.body[in.args[0]];
        const std::vector<double>* M = nullptr;
        if (mi.op == Op::Const) M = &mi.data;
        else if (mi.op == Op::Global && m.globals[size_t(mi.aux)].kind == ir::Global::Kind::Constant && !m.globals[size_t(mi.aux)].type.is_array())
            M = &m.globals[size_t(mi.aux)].value;
        if (!M || M->size() != size_t(lt.rows * lt.cols)) return "";
        int dense = 0;
        for (double x : *M) dense += x != 0 && x != 1 && x != -1;
        if (dense == lt.rows * lt.cols) return "";
        std::string v = arg(in, 1, false);
        if (v.empty() || std::isdigit(static_cast<unsigned char>(v[0])) ||
            !std::all_of(v.begin(), v.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }))
            return "";
        std::vector<std::string> rows;
        for (int r = 0; r < lt.rows; ++r) {
            std::string row;
            for (int c = 0; c < lt.cols; ++c) {
                double x = (*M)[size_t(r * lt.cols + c)];
                if (x == 0) continue;
                std::string comp = v + "." + "xyzw"[c];
                std::string term = x == 1 ? comp : x == -1 ? "-" + comp : float_literal(x) + " * " + comp;
                if (row.empty()) row = term;
                else if (term[0] == '-') row += " - " + term.substr(1);
                else row += " + " + term;
            }
            rows.push_back(row.empty() ? "0.0" : row);
        }
        return fmt::format("vec{}({})", lt.rows, fmt::join(rows, ", "));
    }

    std::string expr(ValueId v) {
        if (!var[v].empty()) return var[v];
        const Instr& in = f.body[v];
        auto a = [&](size_t i) { return arg(in, i, true); };
        auto plain = [&](size_t i) { return arg(in, i, false); };
        switch (in.op) {
            case Op::Const: return constant(in.type, in.data);
            case Op::Param: return var[v];
            case Op::Input: return in.aux == 0 ? "iTime" : "(iMouse.xy / iResolution.xy)";
            case Op::Member: return loop_states.at(in.args[0]).at(size_t(in.aux));
            case Op::Loop: case Op::If: case Op::Switch: return "/* statement */";
            case Op::Global: return global(in);
            case Op::Index: return index(in);
            case Op::Copy: return plain(0);
            case Op::Add: return a(0) + " + " + a(1);
            case Op::Sub: return a(0) + " - " + a(1);
            // IntDiv/IntMod take operands >= 0: by a power of two, a shift and a mask (the same value; no
            // rounding toward zero to correct for, which a signed `/` by a constant costs).
            case Op::IntDiv:
                if (int s = power_of_two(in.args[1]); s >= 0) return s == 0 ? plain(0) : a(0) + " >> " + std::to_string(s);
                return a(0) + " / " + a(1);
            case Op::IntMod:
                if (int s = power_of_two(in.args[1]); s >= 0) return s == 0 ? "0" : a(0) + " & " + std::to_string((1LL << s) - 1);
                return a(0) + " % " + a(1);
            case Op::FloorInt: return integral(in.args[0]) ? "int(" + plain(0) + ")" : "int(floor(" + plain(0) + "))";
            case Op::Mul: {
                const Type& lt = f.body[in.args[0]].type;
                const Type& rt = f.body[in.args[1]].type;
                bool lrow = lt.is_matrix() && lt.rows == 1, rrow = rt.is_matrix() && rt.rows == 1;
                if (lrow && rt.is_vector()) return fmt::format("dot({}, {})", plain(0), plain(1));  // row · column
                if (lt.is_vector() && rrow) return fmt::format("outerProduct({}, {})", plain(0), plain(1));
                if (std::string s = sparse_product(in); !s.empty()) return s;
                return a(0) + " * " + a(1);
            }
            case Op::Div: {
                // By a constant: times its reciprocal. llvmpipe keeps a division by a constant a division (LLVM
                // without fast-math), several times a multiplication's latency in every march step (the
                // Lipschitz factor): sine_terrain's frame 6% faster. The result may differ by an ulp.
                const Instr& den = f.body[in.args[1]];
                if (den.op == Op::Const && den.type.kind == Type::Scalar && in.type.kind != Type::Integer && den.data.size() == 1) {
                    double c = den.data[0], r = 1.0 / c;
                    if (std::isfinite(c) && c != 0 && std::fabs(r) >= 1e-30 && std::fabs(r) <= 1e30 && r > 0)
                        return a(0) + " * " + float_literal(r);
                }
                return a(0) + " / " + a(1);
            }
            case Op::Neg: return "-" + a(0);
            case Op::Hadamard:
                if (in.type.is_matrix() && in.type.rows > 1) return fmt::format("matrixCompMult({}, {})", plain(0), plain(1));
                return a(0) + " * " + a(1);
            case Op::Dot: return fmt::format("dot({}, {})", plain(0), plain(1));
            case Op::Cross: return fmt::format("cross({}, {})", plain(0), plain(1));
            case Op::Transpose: {
                const Type& at = f.body[in.args[0]].type;
                if (at.is_vector() || (at.is_matrix() && at.rows == 1)) return expr(in.args[0]);  // column <-> row: the same vecN
                // The transpose of a matrix built from rows is the matrix with them as columns.
                const Instr& src = f.body[in.args[0]];
                if (var[in.args[0]].empty() && src.op == Op::Construct && at.is_matrix() && int(src.args.size()) == at.rows) {
                    bool rows = true;
                    for (ValueId x : src.args) rows &= f.body[x].type == Type::vector(at.cols);
                    if (rows) {
                        std::vector<std::string> cols;
                        for (size_t k = 0; k < src.args.size(); ++k) cols.push_back(arg(src, k, false));
                        return fmt::format("{}({})", type_of(in.type, in.span), fmt::join(cols, ", "));
                    }
                }
                return fmt::format("transpose({})", plain(0));
            }
            case Op::Inverse: return fmt::format("inverse({})", plain(0));
            case Op::Det: return fmt::format("determinant({})", plain(0));
            case Op::Builtin: {
                std::vector<std::string> args;
                for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                // A template such as `1.0 / tan(#)`: # is the (parenthesised) argument.
                std::string spelling = builtin(in.aux).glsl;
                if (size_t at = spelling.find('#'); at != std::string::npos) return spelling.replace(at, 1, a(0));
                return fmt::format("{}({})", spelling, fmt::join(args, ", "));
            }
            case Op::Construct: return construct(in, v);
            case Op::Extract: {
                const Type& st = f.body[in.args[0]].type;
                if (st.is_vector() || (st.is_matrix() && st.rows == 1)) return component(in.args[0], in.aux);
                return fmt::format("{}[{}][{}]", postfix_base(in.args[0]), in.aux % st.cols, in.aux / st.cols);
            }
            case Op::Column: return fmt::format("{}[{}]", postfix_base(in.args[0]), in.aux);
            case Op::Element: return fmt::format("{}[{}]", postfix_base(in.args[0]), in.aux);
            case Op::At: {  // indices rounded and clamped, as the evaluator does
                const Type& st = f.body[in.args[0]].type;
                auto index = [&](size_t k, int n) {
                    if (f.body[in.args[k]].type.kind == Type::Integer) return fmt::format("clamp({}, 0, {})", expr(in.args[k]), n - 1);
                    return fmt::format("clamp(int(floor({} + 0.5)), 0, {})", expr(in.args[k]), n - 1);
                };
                if (st.is_matrix())  // GLSL indexes columns first
                    return fmt::format("{}[{}][{}]", postfix_base(in.args[0]), index(2, st.cols), index(1, st.rows));
                return fmt::format("{}[{}]", postfix_base(in.args[0]), index(1, st.is_array() ? st.count : st.rows));
            }
            case Op::Row: {
                const Type& st = f.body[in.args[0]].type;
                if (st.rows == 1) return expr(in.args[0]);
                std::vector<std::string> parts;
                std::string base = postfix_base(in.args[0]);
                for (int c = 0; c < st.cols; ++c) parts.push_back(fmt::format("{}[{}][{}]", base, c, in.aux));
                return fmt::format("{}({})", type_of(in.type, in.span), fmt::join(parts, ", "));
            }
            case Op::Compare: {
                static const char* ops[] = {"==", "!=", "<", "<=", ">", ">="};
                return fmt::format("{} {} {}", a(0), ops[in.aux], a(1));
            }
            case Op::And: return a(0) + " && " + a(1);
            case Op::Or: return a(0) + " || " + a(1);
            case Op::Select: return fmt::format("{} ? {} : {}", a(0), a(1), a(2));
            case Op::Call: {
                std::vector<std::string> args;
                for (size_t i = 0; i < in.args.size(); ++i) args.push_back(plain(i));
                return fmt::format("{}({})", em.function_name(in.aux), fmt::join(args, ", "));
            }
        }
        return "0.0";
    }

    // Schedules what `roots` need and counts uses.
    void analyze(const std::vector<ValueId>& roots) {
        size_t n = f.body.size();
        sched = ir::schedule(f, roots);
        uses.assign(n, 0);
        depth.assign(n, 0);
        var.assign(n, "");
        for (ValueId r : roots) uses[r]++;
        for (size_t i = 0; i < n; ++i)
            if (sched.live(ValueId(i)))
                for (ValueId a : f.body[i].args) uses[a]++;
        // GLSL's ?: computes only the chosen operand: a call inline there becomes a branch around the inlined
        // body in the driver (Mesa keeps it one, where a select of two values is flattened). The instances'
        // distances IfConvert's dispatch selects by id (iqc_distance_of, each cheap) cost llvmpipe's compile more
        // inline in the ?: chain than the if-chain they replaced (grazing plane 341.4 -> 344.9 M instructions; in
        // statements 334.2 M). Elsewhere a call in a select stays inline: a piecewise `{ f(p) if ‖p‖ < 2; ... }`
        // over a costly f is a bound its author wrote, and the GPU skips f where no pixel of a group takes it.
        eager.assign(n, 0);
        if (f.name != ir::names::kDistanceOf) return;
        // Whether v's expression, where emitted inline (a value read once), calls a function (a select inside
        // it has its own call operands computed first).
        auto calls = [&](auto& self, ValueId v, int depth) -> bool {
            const Instr& in = f.body[v];
            if (in.op == Op::Call) return true;
            if (depth == 0 || in.op == Op::If || in.op == Op::Switch || in.op == Op::Loop || in.op == Op::Select) return false;
            for (ValueId a : in.args)
                if (uses[a] == 1 && self(self, a, depth - 1)) return true;
            return false;
        };
        for (size_t i = 0; i < n; ++i)
            if (sched.live(ValueId(i)) && f.body[i].op == Op::Select)
                for (size_t k = 1; k < 3; ++k)
                    if (calls(calls, f.body[i].args[k], 8)) eager[f.body[i].args[k]] = 1;
    }

    // One statement per named value, shared costly value, loop and lazy choice of region `r`; `skip` is left
    // as an expression.
    std::string region(int r, const std::string& indent, ValueId skip) {
        std::string out;
        for (ValueId i : sched.regions[size_t(r)].instrs) {
            const Instr& in = f.body[i];
            if (in.op == Op::Param || in.op == Op::Member) continue;
            if (in.op == Op::Loop) {
                out += loop(i, indent);
                continue;
            }
            if (in.op == Op::If || in.op == Op::Switch) {
                out += lazy(i, indent);
                continue;
            }
            // A global array (a sequence parameter bound in place by the pass `arrays`, whose name the
            // parameter's was) is read where it is indexed: a local copy would load every element.
            if (in.op == Op::Global && in.type.is_array()) continue;
            bool named = !in.name.empty();
            // How deep this value's expression would nest: past kMaxInlineDepth it gets a variable, so no
            // expression (a min of 20,000 arguments, a piecewise of 5,000 cases) nests deeper than that in
            // the emitter's recursion or in the driver's parser.
            int d = 1;
            for (ValueId a : in.args)
                if (var[a].empty()) d = std::max(d, depth[a] + 1);
            depth[i] = d;
            bool deep = d > kMaxInlineDepth && i != skip;
            bool shared = uses[i] > 1 && !trivial(i) && (deep || worth_a_variable(i));
            if (i == skip && !named) continue;
            if (!named && !shared && !deep && !eager[i]) continue;
            if (in.op == Op::Construct && !named && in.type.is_vector()) {
                // A shared broadcast such as vec3(x) is cheap: keep it inline.
                bool same = true;
                for (ValueId x : in.args) same &= x == in.args[0];
                if (same) continue;
            }
            out += materialize(i, named ? in.name : "tmp", indent, named ? in.source : "");
        }
        return out;
    }

    std::string materialize(ValueId v, const std::string& name, const std::string& indent, const std::string& source) {
        const Instr& in = f.body[v];
        std::string value = expr(v);
        std::string vn = locals.unique(name);
        std::string out = fmt::format("{}{} {}{} = {};", indent, type_of(in.type, in.span), vn, array_suffix(in.type), value);
        if (!source.empty()) out += " // " + one_line(source);
        var[v] = vn;
        return out + "\n";
    }

    // One arm: what it needs, then the assignment of its value.
    std::string arm(ValueId v, size_t k, const std::string& vn, const std::string& indent) {
        const Instr& in = f.body[v];
        std::string out = region(sched.arms[v][k], indent, in.args[k]);
        return out + fmt::format("{}{} = {};\n", indent, vn, arg(in, k, false));
    }

    // A lazy choice: If as if/else, Switch as flat ifs (one per case, no nesting).
    std::string lazy(ValueId v, const std::string& indent) {
        const Instr& in = f.body[v];
        std::string vn = locals.unique(in.name.empty() ? "tmp" : in.name);
        // (a choice of arrays, a sequence parameter per instance: `vec3 tmp[2];`)
        std::string tn = type_of(in.type, in.span), decl = vn + array_suffix(in.type);
        std::string inner = indent + "    ";
        std::string out;
        std::string comment = in.source.empty() ? "" : " // " + one_line(in.source);
        if (in.op == Op::If) {
            out += fmt::format("{}{} {};{}\n{}if ({}) {{\n", indent, tn, decl, comment, indent, arg(in, 0, false));
            out += arm(v, 1, vn, inner);
            out += indent + "} else {\n" + arm(v, 2, vn, inner) + indent + "}\n";
            var[v] = vn;
            return out;
        }
        std::string sel = arg(in, 0, true);
        auto cond = [&](int k) {
            long long lo = std::llround(in.data[size_t(2 * k)]), hi = std::llround(in.data[size_t(2 * k + 1)]);
            if (hi == lo + 1) return fmt::format("{} == {}", sel, lo);
            return fmt::format("{} >= {} && {} < {}", sel, lo, sel, hi);
        };
        int cases = ir::switch_cases(in);
        std::string fallback = region(sched.arms[v][1], inner, in.args[1]);
        // Nothing to compute first, and the default safe to compute for any selector: it is the initial value.
        auto computed = [&](ValueId x) { return !var[x].empty(); };
        if (fallback.empty() && ir::speculatable_expression(f.body, in.args[1], computed)) {
            out += fmt::format("{}{} {} = {};{}\n", indent, tn, decl, arg(in, 1, false), comment);
        } else {
            std::vector<std::string> any;
            for (int k = 0; k < cases; ++k) any.push_back("(" + cond(k) + ")");
            out += fmt::format("{}{} {};{}\n{}if (!({})) {{\n{}{}{} = {};\n{}}}\n", indent, tn, decl, comment, indent,
                               fmt::join(any, " || "), fallback, inner, vn, arg(in, 1, false), indent);
        }
        for (int k = 0; k < cases; ++k) {
            std::string body = arm(v, size_t(2 + k), vn, inner);
            if (body.find('\n') == body.size() - 1)  // one line: `if (c) x = y;`
                out += fmt::format("{}if ({}) {}", indent, cond(k), body.substr(inner.size()));
            else
                out += fmt::format("{}if ({}) {{\n{}{}}}\n", indent, cond(k), body, indent);
        }
        var[v] = vn;
        return out;
    }

    // A recurrence: its states as variables, then a for loop computing the next states.
    std::string loop(ValueId v, const std::string& indent) {
        const Instr& in = f.body[v];
        const ir::Function& body = m.functions[size_t(in.aux)];
        size_t states = body.outputs.size();
        std::string out;
        // Captured values are read every iteration: give costly ones a variable first.
        for (size_t k = states + 1; k < in.args.size(); ++k) {
            ValueId a = in.args[k];
            if (var[a].empty() && !trivial(a) && f.body[a].op != Op::Member &&
                !(f.body[a].op == Op::Global && f.body[a].type.is_array()))  // (a global array is read in place)
                out += materialize(a, "tmp", indent, "");
        }
        std::vector<std::string> names;
        for (size_t j = 0; j < states; ++j) {
            const Type& t = body.params[j + 1].type;
            std::string n = locals.unique(body.outputs[j].first);
            out += fmt::format("{}{} {}{} = {};\n", indent, type_of(t, in.span), n, array_suffix(t), arg(in, j + 1, false));
            names.push_back(n);
        }
        loop_states[v] = names;
        const Instr& hi = f.body[in.args[0]];
        long long lo = std::llround(in.data[0]);
        long long trips = hi.op == Op::Const ? std::llround(hi.data[0]) - lo + 1 : -1;
        std::string hi_text = hi.op == Op::Const ? std::to_string(std::llround(hi.data[0])) : arg(in, 0, hi.op == Op::Select);  // k <= (c ? a : b)
        // One iteration with index `kn`: the body's region, then the next states.
        auto iteration = [&](const std::string& kn, const std::string& inner) {
            FunctionEmitter be(m, body, em, diags, locals);
            std::vector<ValueId> roots;
            for (auto& o : body.outputs) roots.push_back(o.second);
            be.analyze(roots);
            for (size_t p = 0; p < body.body.size(); ++p) {
                const Instr& pi = body.body[p];
                if (pi.op != Op::Param) continue;
                if (pi.aux == 0) be.var[p] = kn;
                else if (size_t(pi.aux) <= states) be.var[p] = names[size_t(pi.aux) - 1];
                else be.var[p] = arg(in, size_t(pi.aux), true);
            }
            std::string text = be.region(0, inner, ValueId(-1));
            if (states == 1) {
                text += fmt::format("{}{} = {};\n", inner, names[0], be.expr(body.outputs[0].second));
            } else {
                std::vector<std::string> next;
                for (size_t j = 0; j < states; ++j) {
                    ValueId o = body.outputs[j].second;
                    if (be.var[o] == names[j]) {  // unchanged this iteration
                        next.push_back(names[j]);
                        continue;
                    }
                    next.push_back(be.locals.unique(names[j] + "_next"));
                    std::string src = one_line(body.body[o].source);
                    text += fmt::format("{}{} {} = {};{}\n", inner, type_of(body.body[o].type, in.span), next[j], be.expr(o),
                                        src.empty() ? "" : " // " + src);
                }
                for (size_t j = 0; j < states; ++j)
                    if (next[j] != names[j]) text += fmt::format("{}{} = {};\n", inner, names[j], next[j]);
            }
            failed |= be.failed;
            return text;
        };
        std::string comment = in.source.empty() ? "" : "  // " + one_line(in.source);
        std::string inner = indent + "    ";
        int unroll = trips > 0 ? em.unroll_of(in.aux, trips) : 1;
        if (unroll == 1) {
            std::string k = locals.unique(body.params[0].name);
            out += fmt::format("{}for (int {} = {}; {} <= {}; {}++) {{{}\n", indent, k, lo, k, hi_text, k, comment);
            out += iteration(k, inner);
            return out + indent + "}\n";
        }
        // A long loop runs `unroll` iterations per trip: llvmpipe ends a shader invocation after 65,535 loop
        // iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every loop), and a march of 128 steps over
        // 1,000 instances would pass it and draw garbage.
        std::string k0 = locals.unique(body.params[0].name + "0");
        out += fmt::format("{}for (int {} = {}; {} <= {}; {} += {}) {{{} (unrolled by {})\n", indent, k0, lo, k0, hi_text, k0,
                           unroll, comment.empty() ? "  //" : comment, unroll);
        std::string block = inner + "    ";
        for (int j = 0; j < unroll; ++j) {
            std::string k = locals.unique(body.params[0].name);
            std::string at = j == 0 ? k0 : fmt::format("{} + {}", k0, j);
            if (j == 0 || trips % unroll == 0) out += inner + "{\n";
            else out += fmt::format("{}if ({} <= {}) {{\n", inner, at, hi_text);
            out += fmt::format("{}int {} = {};\n", block, k, at);
            out += iteration(k, block);
            out += inner + "}\n";
        }
        return out + indent + "}\n";
    }

    std::vector<std::string> declare_params() {
        std::vector<std::string> params;
        for (size_t i = 0; i < f.params.size(); ++i) {
            std::string pn = locals.unique(f.params[i].name);
            Span where;  // the parameter's declaration, for a type GLSL lacks (ℝ¹⁰)
            for (size_t k = 0; k < f.body.size(); ++k)
                if (f.body[k].op == Op::Param && f.body[k].aux == int(i)) {
                    var[k] = pn;
                    where = f.body[k].span;
                }
            params.push_back(fmt::format("{} {}{}", type_of(f.params[i].type, where), pn, array_suffix(f.params[i].type)));
        }
        return params;
    }

    std::string run(const std::string& name, const std::string& comment) {
        analyze({f.result});
        std::string out;
        if (!comment.empty()) out += "// " + comment_text(comment) + "\n";
        std::vector<std::string> params = declare_params();
        out += fmt::format("{}{} {}({}) {{\n", type_of(f.result_type(), {}), array_suffix(f.result_type()), name,
                           fmt::join(params, ", "));
        out += region(0, "    ", f.result);
        const Instr& r = f.body[f.result];
        std::string rv = expr(f.result);
        out += fmt::format("    return {};", rv);
        if (r.name.empty() && !r.source.empty()) out += " // " + one_line(r.source);
        out += "\n}\n";
        return out;
    }

    std::string run_procedure(const std::string& name, const std::string& comment) {
        std::vector<ValueId> roots;
        for (const auto& o : f.outputs) roots.push_back(o.second);
        analyze(roots);
        std::string out;
        if (!comment.empty()) out += "// " + comment_text(comment) + "\n";
        out += fmt::format("void {}() {{\n", name);
        out += region(0, "    ", ValueId(-1));
        const auto index = m.global_index();
        for (const auto& [gname, v] : f.outputs) {
            auto g = index.find(gname);
            const GlobalStorage* s = g != index.end() ? storage(g->second) : nullptr;
            out += fmt::format("    {} = {};\n", s ? s->name : identifier(gname), expr(v));
        }
        return out + "}\n";
    }
};

}  // namespace

std::string Emitter::function(int fn, const std::string& comment) {
    const std::string& name = function_name(fn);
    FunctionEmitter fe(m_, m_.functions[size_t(fn)], *this, diags_, globals_);
    return fe.run(name, comment);
}

std::string Emitter::procedure(int fn, const std::string& comment) {
    const std::string& name = function_name(fn);
    FunctionEmitter fe(m_, m_.functions[size_t(fn)], *this, diags_, globals_);
    return fe.run_procedure(name, comment);
}

}  // namespace iqc::glsl
