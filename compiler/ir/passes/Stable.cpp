#include "ir/passes/Stable.h"

#include "ir/Builder.h"
#include "ir/passes/Inline.h"

#include <algorithm>
#include <map>
#include <optional>
#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

// A longer unrolled sum is left as written. (A ∑ over 32 or more sequence elements is a loop on targets with
// uniforms, over 256 on Shadertoy: ir/Lower.cpp; a loop of exponentials is rewritten as loops, below. A trial's
// smooth union of 17 points, -k log ∑ e^(-d_i/k), was 0/0 far from the points when the limit was 16.)
constexpr size_t kMaxTerms = 256;

bool is_builtin(const Instr& in, const char* name) {
    return in.op == Op::Builtin && std::string_view(builtin(in.aux).name) == name;
}

bool is_scalar_const(const Instr& in, double v) {
    return in.op == Op::Const && in.type.is_scalar() && in.data.size() == 1 && in.data[0] == v;
}

// A logarithm's factor against the natural one: log, ln 1; log_2 1/ln 2; log_10 1/ln 10 (0: no logarithm).
// Quilez's exact exponential smooth minimum is written -k log₂(2^(-a/k) + 2^(-b/k)) (a trial's: not stabilised,
// nothing drawn from 14 units out).
double log_factor(const Instr& in) {
    if (!in.type.is_scalar()) return 0;
    if (is_builtin(in, "log") || is_builtin(in, "ln")) return 1;
    if (is_builtin(in, "log_2")) return 1 / std::log(2.0);
    if (is_builtin(in, "log_10")) return 1 / std::log(10.0);
    return 0;
}

// The leaves of the tree of scalar Adds under `v` (v itself when it is no Add); false past kMaxTerms. A tree
// of at most kMaxTerms leaves is at most kMaxTerms deep, so a longer chain (an unrolled ∑ of a million terms)
// stops there instead of recursing a million levels.
bool sum_terms(const std::vector<Instr>& body, ValueId v, std::vector<ValueId>& out, size_t depth = 0) {
    const Instr& in = body[v];
    if (in.op == Op::Add && in.type.is_scalar() && body[in.args[0]].type.is_scalar() && body[in.args[1]].type.is_scalar())
        return depth < kMaxTerms && sum_terms(body, in.args[0], out, depth + 1) && sum_terms(body, in.args[1], out, depth + 1);
    out.push_back(v);
    return out.size() <= kMaxTerms;
}

// Whether scalar value v of f is known positive: a constant > 0, or a parameter whose bounds are all > 0 (a slider
// β ∈ [1.5, 10]).
bool positive(const Function& f, const std::vector<Instr>& body, ValueId v) {
    const Instr& in = body[v];
    if (in.op == Op::Param && size_t(in.aux) < f.param_bounds.size()) {  // (a sequence's too: every element > 0)
        const ValueBounds& pb = f.param_bounds[size_t(in.aux)];
        return !pb.input && !pb.lo.empty() && std::all_of(pb.lo.begin(), pb.lo.end(), [](double lo) { return lo > 0; });
    }
    if (!in.type.is_scalar()) return false;
    if (in.op == Op::Const) return in.data.size() == 1 && in.data[0] > 0;
    return false;
}


// Whether `t` is an exponential: e^x, or c^x for a base c > 0 other than 1 (e^(x ln c)): a constant, or a slider whose
// bounds are > 0 (a trial's β^(-k d), β ∈ [1.5, 10]: not stabilised, nothing drawn from 14 units).
bool exponential(const Function& f, const std::vector<Instr>& body, const Instr& t) {
    if (is_builtin(t, "exp")) return t.type.is_scalar();
    if (!is_builtin(t, "pow") || !t.type.is_scalar() || t.args.size() != 2) return false;
    const Instr& base = body[t.args[0]];
    if (base.op == Op::Const) return base.data.size() == 1 && base.data[0] > 0 && base.data[0] != 1;
    return positive(f, body, t.args[0]);
}

// A term of a sum of exponentials: (∏ weights) · e^(∑_j c_j x_j + shift), the exponentials' products, quotients and
// powers taken together (e^a e^b, 1/e^x, (e^x)², √(e^x)) and constant positive factors taken into the shift (e^x/2:
// e^(x − ln 2)); other factors are weights, each multiplying or dividing (w_i e^x).
struct ExpTerm {
    std::vector<std::pair<ValueId, double>> parts;  // (an exponential instruction, its power c_j)
    double shift = 0;
    std::vector<std::pair<ValueId, bool>> weights;  // (value, divides)
    bool plain() const { return parts.size() == 1 && parts[0].second == 1 && shift == 0 && weights.empty(); }
};

bool exp_term(const Function& f, const std::vector<Instr>& body, ValueId t, ExpTerm& out, int depth = 0) {
    const Instr& in = body[t];
    if (exponential(f, body, in)) {
        out = ExpTerm{};
        out.parts = {{t, 1.0}};
        return true;
    }
    if (depth > 6 || !in.type.is_scalar() || in.args.empty()) return false;
    for (ValueId a : in.args)
        if (!body[a].type.is_scalar()) return false;
    auto const_positive = [&](ValueId v) { return body[v].op == Op::Const && body[v].data.size() == 1 && body[v].data[0] > 0; };
    if ((in.op == Op::Mul || in.op == Op::Div) && in.args.size() == 2) {
        const double sign = in.op == Op::Div ? -1 : 1;
        ExpTerm a, b;
        const bool ea = exp_term(f, body, in.args[0], a, depth + 1), eb = exp_term(f, body, in.args[1], b, depth + 1);
        if (!ea && !eb) return false;
        out = ExpTerm{};
        if (ea) {
            out = std::move(a);
        } else if (const_positive(in.args[0])) {
            out.shift += std::log(body[in.args[0]].data[0]);
        } else {
            out.weights.push_back({in.args[0], false});
        }
        if (eb) {
            for (auto [e, c] : b.parts) out.parts.push_back({e, sign * c});
            out.shift += sign * b.shift;
            for (auto [w, divides] : b.weights) out.weights.push_back({w, sign < 0 ? !divides : divides});
        } else if (const_positive(in.args[1])) {
            out.shift += sign * std::log(body[in.args[1]].data[0]);
        } else {
            out.weights.push_back({in.args[1], sign < 0});
        }
        return true;
    }
    // (e^x)^q = e^(q x), √(e^x) = e^(x/2): of a term without weights
    const bool power = is_builtin(in, "pow") && in.args.size() == 2 && body[in.args[1]].op == Op::Const && body[in.args[1]].data.size() == 1;
    if (power || (is_builtin(in, "sqrt") && in.args.size() == 1)) {
        const double q = power ? body[in.args[1]].data[0] : 0.5;
        ExpTerm a;
        if (!exp_term(f, body, in.args[0], a, depth + 1) || !a.weights.empty()) return false;
        out = std::move(a);
        for (auto& part : out.parts) part.second *= q;
        out.shift *= q;
        return true;
    }
    return false;
}

// Builds, with b, the exponent of term t in base e (x of e^x; y ln c of c^y; times each part's power, plus the
// shift), `at` mapping the term's values to the function being built.
template <class At>
ValueId exponent_of(Builder& b, const std::vector<Instr>& body, const ExpTerm& t, At at) {
    ValueId sum = ValueId(-1);
    for (auto [part, c] : t.parts) {
        const Instr& e = body[part];
        ValueId x;
        if (is_builtin(e, "exp")) {
            x = at(e.args[0]);
        } else if (body[e.args[0]].op == Op::Const) {
            x = b.op(Op::Mul, {at(e.args[1]), b.scalar(std::log(body[e.args[0]].data[0]))});
        } else {
            x = b.op(Op::Mul, {at(e.args[1]), b.builtin("log", {at(e.args[0])})});
        }
        if (c == -1) x = b.op(Op::Neg, {x});
        else if (c != 1) x = b.op(Op::Mul, {x, b.scalar(c)});
        sum = sum == ValueId(-1) ? x : b.op(Op::Add, {sum, x});
    }
    return t.shift == 0 ? sum : b.op(Op::Add, {sum, b.scalar(t.shift)});
}

// e^(x − hi) times t's weights.
template <class At>
ValueId weighted(Builder& b, const ExpTerm& t, ValueId e, At at) {
    for (const auto& [w, divides] : t.weights) e = b.op(divides ? Op::Div : Op::Mul, {e, at(w)});
    return e;
}

// The exponent that competes for the shift m (the largest): x, or, where a weight is not known positive (a slider's,
// which may be 0), x only where the weights' product is > 0, else the float minimum: a weight of 0 on the largest
// term made the shifted sum 0, ln 0 = -∞, a hole through the wall behind a blob turned off (a trial's, stop 54).
// `kind` Ne: the exponent a term is shifted by in the sum, the float minimum where its weight is 0 (0·e^(x − m) of an
// x above m overflowed to 0·∞ = NaN).
template <class At>
ValueId competing(Builder& b, const Function& f, const std::vector<Instr>& body, const ExpTerm& t, ValueId x, At at,
                  CompareKind kind = CompareKind::Gt) {
    bool known = true;
    for (const auto& [w, divides] : t.weights) known = known && positive(f, body, w);
    if (known) return x;
    const ValueId w = t.weights.size() == 1 ? at(t.weights[0].first) : weighted(b, t, b.scalar(1), at);  // (1/w: w's sign)
    return b.op(Op::Select, {b.compare(kind, w, b.scalar(0)), x, b.scalar(-3.4028234663852886e38)});
}

// A rolled ∑ of exponential terms (a Loop whose body adds a term to its one state, the term not reading the state).
std::optional<ExpTerm> rolled_exp_sum(const Function& body) {
    if (body.outputs.size() != 1 || !body.body[body.outputs[0].second].type.is_scalar()) return std::nullopt;
    auto e = accumulated_term(body, 0);
    ExpTerm t;
    if (!e || !exp_term(body, body.body, *e, t)) return std::nullopt;
    return t;
}

// Whether the weights of a rolled ∑'s term are known positive: each unweighted, or an element of a sequence the loop
// captures from f whose bounds are > 0 (w_i ∈ [0.1, 2]).
bool rolled_weights_positive(const Module& m, const Function& f, const std::vector<Instr>& body, const Instr& loop) {
    const Function& lb = m.functions[size_t(loop.aux)];
    auto t = accumulated_term(lb, 0);
    ExpTerm e;
    if (!t || !exp_term(lb, lb.body, *t, e)) return false;
    for (const auto& [w, divides] : e.weights) {
        const Instr& wi = lb.body[w];
        if (wi.op != Op::Index || lb.body[wi.args[0]].op != Op::Param) return false;
        const size_t j = size_t(lb.body[wi.args[0]].aux);  // (body parameter j is the loop's operand j)
        if (j >= loop.args.size() || !positive(f, body, loop.args[j])) return false;
    }
    return true;
}

// The state parameter (the running sum, parameter 1) of a loop body.
ValueId state_param(const Function& body) {
    for (size_t i = 0; i < body.body.size(); ++i)
        if (body.body[i].op == Op::Param && body.body[i].aux == 1) return ValueId(i);
    return ValueId(-1);
}

// The bodies of the two loops that replace a rolled log-sum-exp: the running maximum of the exponents x, and the sum of
// (weights) e^(x − hi) with hi a capture (the last parameter).
std::pair<Function, Function> split_exp_sum(const Module& m, const Function& body, const ExpTerm& t) {
    auto same = [](ValueId v) { return v; };
    Function hi = body, shifted = body;
    hi.name += ".max";
    hi.glsl_name = hi.name;
    {
        Builder b(m, hi);
        ValueId v = b.builtin("max", {state_param(hi), competing(b, body, body.body, t, exponent_of(b, body.body, t, same), same)});
        hi.outputs = {{"hi", v}};
        hi.result = v;
    }
    shifted.name += ".shifted";
    shifted.glsl_name = shifted.name;
    {
        Builder b(m, shifted);
        const ValueId state = state_param(shifted);
        ValueId h = b.param("hi", Type::scalar());
        ValueId x = competing(b, body, body.body, t, exponent_of(b, body.body, t, same), same, CompareKind::Ne);
        ValueId v = b.op(Op::Add, {state, weighted(b, t, b.builtin("exp", {b.op(Op::Sub, {x, h})}), same)});
        shifted.outputs = {{"sum", v}};
        shifted.result = v;
    }
    return {std::move(hi), std::move(shifted)};
}

// The rolled ∑ that a value is, where it is one of exponential terms: a Member of a Loop starting at 0.
const Instr* rolled_loop(const std::vector<Instr>& body, ValueId v) {
    const Instr& a = body[v];
    if (a.op != Op::Member || a.aux != 0 || body[a.args[0]].op != Op::Loop) return nullptr;
    const Instr& loop = body[a.args[0]];
    if (loop.args.size() < 2 || !is_scalar_const(body[loop.args[1]], 0)) return nullptr;
    return &loop;
}

// log(v) as ∑_j c_j log(v_j): the argument of a logarithm taken apart at products, quotients, powers and square roots
// (log(S/4) = log S − log 4, log(1/S) = −log S, log(√S) = ½ log S, log(S²) = 2 log S), where each part is a sum of
// exponential terms (`lse` accepts it: a log-sum-exp) or known positive (a constant, a positive slider, an
// exponential), so that the identity holds wherever the original is defined. False where any part is neither, or where
// no part is a sum. A trial's (stop 54) -ln(∑_i e^(-k d_i)/4)/k, 0.5(e^a + e^b), -ln(t/48)/k through a local
// function, 1/e^(k t), ln(1/∑): none stabilised, nothing drawn from 14 units.
struct LogPiece {
    ValueId v;
    double c;
    bool sum;  // a sum of exponential terms (else a positive value)
};

template <class Lse>
bool log_pieces(const Function& f, const std::vector<Instr>& body, ValueId v, double c, std::vector<LogPiece>& out, const Lse& lse,
                int depth = 0) {
    const Instr& in = body[v];
    // (a part of a product, quotient, power or root must be > 0 for log(S·T) = log S + log T: a sum with a weight that
    // may be negative may be too; the whole argument may be any sum)
    if (lse(v, depth > 0)) {
        out.push_back({v, c, true});
        return true;
    }
    if (is_scalar_const(in, 1)) return true;  // (log 1 = 0: 1/S)
    if (positive(f, body, v) || exponential(f, body, in)) {
        out.push_back({v, c, false});
        return true;
    }
    if (depth > 6 || !in.type.is_scalar() || in.args.empty()) return false;
    for (ValueId a : in.args)
        if (!body[a].type.is_scalar()) return false;
    if ((in.op == Op::Mul || in.op == Op::Div) && in.args.size() == 2)
        return log_pieces(f, body, in.args[0], c, out, lse, depth + 1) &&
               log_pieces(f, body, in.args[1], in.op == Op::Div ? -c : c, out, lse, depth + 1);
    // (a power of a sum: the sum is > 0, so log(S^q) = q log S for any q)
    if (is_builtin(in, "pow") && body[in.args[1]].op == Op::Const && body[in.args[1]].data.size() == 1 && lse(in.args[0], true)) {
        out.push_back({in.args[0], c * body[in.args[1]].data[0], true});
        return true;
    }
    if (is_builtin(in, "sqrt") && lse(in.args[0], true)) {
        out.push_back({in.args[0], 0.5 * c, true});
        return true;
    }
    return false;
}

// The terms of a sum piece: the rolled ∑ itself, or the leaves of its tree of Adds (each a term or a rolled ∑).
std::vector<ValueId> piece_terms(const std::vector<Instr>& body, ValueId v) {
    std::vector<ValueId> ids;
    if (rolled_loop(body, v)) ids = {v};
    else sum_terms(body, v, ids);
    return ids;
}

// Whether value v of f is a sum (of up to kMaxTerms leaves) whose every term is an exponential term, or a rolled ∑
// that `rolled` accepts.
template <class Rolled>
bool exp_sum(const Function& f, const std::vector<Instr>& body, ValueId v, const Rolled& rolled) {
    if (const Instr* loop = rolled_loop(body, v)) return rolled(*loop);
    std::vector<ValueId> terms;
    if (!sum_terms(body, v, terms) || terms.empty()) return false;
    if (terms.size() == 1 && body[v].op != Op::Add) {
        // (one term alone is a sum only with a weight: w e^x; a bare e^x is a positive part, log(e^x) = x)
        ExpTerm t;
        return exp_term(f, body, v, t) && !t.plain();
    }
    for (ValueId t : terms) {
        ExpTerm e;
        const Instr* loop = rolled_loop(body, t);
        if (loop ? !rolled(*loop) : !exp_term(f, body, t, e)) return false;
    }
    return true;
}

using Splits = std::map<int, std::pair<int, int>>;

// Whether every weight of the sum at v (its exponential terms') is known positive: the sum is then > 0. Rolled ∑s are
// `rolled_positive`'s to judge.
template <class Rolled>
bool positive_sum(const Function& f, const std::vector<Instr>& body, ValueId v, const Rolled& rolled_positive) {
    for (ValueId t : piece_terms(body, v)) {
        if (const Instr* loop = rolled_loop(body, t)) {
            if (!rolled_positive(*loop)) return false;
            continue;
        }
        ExpTerm e;
        if (!exp_term(f, body, t, e)) return false;
        for (const auto& [w, divides] : e.weights)
            if (!positive(f, body, w)) return false;
    }
    return true;
}

// Rewrites f's unstable forms (the rolled sums of `split` by their replacement loops); returns how many fired, and
// appends them to `fired` (when given). Reads no other function: a copy of f may be tried.
size_t rewrite_function(const Module& m, Function& f, const Splits& split, std::vector<StableRewrite>* fired);

// Which functions compute a logarithm or an exponential, themselves or in what they call or loop over.
std::vector<char> log_or_exp_functions(const Module& m) {
    std::vector<char> marked(m.functions.size(), 0);
    for (size_t i = 0; i < m.functions.size(); ++i)
        for (const Instr& in : m.functions[i].body)
            if (log_factor(in) != 0 || exponential(m.functions[i], m.functions[i].body, in)) marked[i] = 1;
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t i = 0; i < m.functions.size(); ++i)
            for (const Instr& in : m.functions[i].body)
                if (!marked[i] && (in.op == Op::Call || in.op == Op::Loop) && marked[size_t(in.aux)]) marked[i] = changed = true;
    }
    return marked;
}

// A module's own name: "blob" of "blob", "blob.s" and "blob.sum_i" (its local functions and loop bodies).
std::string_view module_of(const std::string& name) { return std::string_view(name).substr(0, name.find('.')); }

// A logarithm of a rolled ∑ (a Loop starting at 0) whose body calls `local` (the loop body's term, or part of it, not
// yet inlined): where a log-sum-exp spans a module's local functions.
bool log_of_rolled_call(const Module& m, const Function& f, const std::vector<char>& local) {
    auto local_term = [&](ValueId v, bool) {
        const Instr* loop = rolled_loop(f.body, v);
        if (!loop) return false;
        const Function& body = m.functions[size_t(loop->aux)];
        if (!accumulated_term(body, 0)) return false;
        for (const Instr& in : body.body)
            if (in.op == Op::Call && local[size_t(in.aux)]) return true;
        return false;
    };
    for (const Instr& in : f.body) {
        std::vector<LogPiece> pieces;
        if (log_factor(in) == 0 || !log_pieces(f, f.body, in.args[0], 1, pieces, local_term)) continue;
        for (const LogPiece& piece : pieces)
            if (piece.sum) return true;
    }
    return false;
}

// A log-sum-exp written through a module's local functions, -ln(t)/k of ∑ e^(-k d_i) as s(∑_i g(d_i)) (a trial's:
// nothing drawn from 14 units, 14,400 NaN-distance pixels at 160x90): the calls of the module's own functions that
// compute a logarithm or an exponential are inlined where that shows a form the rewrites take (in a rolled ∑'s body
// too), and nowhere else (the emitted code keeps its functions). Functions of other modules are not inlined: each
// stabilises its own forms.
void inline_split_forms(Module& m) {
    const std::vector<char> bearing = log_or_exp_functions(m);
    std::vector<int> rolled_bodies;
    for (size_t i = 0; i < m.functions.size(); ++i) {
        const Function& f = m.functions[i];
        const std::string_view own = module_of(f.name);
        std::vector<char> local(m.functions.size(), 0);
        bool calls = false;
        for (size_t j = 0; j < m.functions.size(); ++j)
            local[j] = bearing[j] && j != i && module_of(m.functions[j].name) == own && m.functions[j].name != own;
        for (const Instr& in : f.body) calls = calls || (in.op == Op::Call && local[size_t(in.aux)]);
        if (!calls) continue;
        Function g = inline_calls_except(m, f, [&](const Function& c) { return !local[size_t(&c - m.functions.data())]; });
        Function tried = g, before = f;
        const bool rolled = log_of_rolled_call(m, g, local) && !log_of_rolled_call(m, f, local);
        if (rolled || rewrite_function(m, tried, {}, nullptr) > rewrite_function(m, before, {}, nullptr)) {
            for (const Instr& in : g.body)
                if (in.op == Op::Loop) rolled_bodies.push_back(in.aux);
            m.functions[i] = std::move(g);
        }
    }
    // The rolled sums' bodies that call the module's functions: those calls inlined (the body's own exponential
    // shows, w_i g(d_i) with g(t) = e^(-k t) too).
    for (int bi : rolled_bodies) {
        const Function& body = m.functions[size_t(bi)];
        if (!accumulated_term(body, 0)) continue;
        const std::string_view own = module_of(body.name);
        m.functions[size_t(bi)] = inline_calls_except(m, body, [&](const Function& c) {
            const size_t j = size_t(&c - m.functions.data());
            return !(bearing[j] && module_of(c.name) == own && c.name != own);
        });
    }
}

}  // namespace

std::vector<StableRewrite> rewrite_unstable_forms(Module& m) {
    inline_split_forms(m);
    std::vector<StableRewrite> fired;
    // Rolled sums of exponentials under a log: their two replacement bodies, made first (functions are added
    // to the module here, not while a function is being rebuilt), by the original body's index.
    std::map<int, std::pair<int, int>> split;
    {
        std::vector<std::pair<int, ExpTerm>> found;
        for (const Function& f : m.functions)
            for (const Instr& in : f.body) {
                std::vector<LogPiece> pieces;
                auto rolled_term = [&](const Instr& loop) { return rolled_exp_sum(m.functions[size_t(loop.aux)]).has_value(); };
                auto weights_positive = [&](const Instr& loop) { return rolled_weights_positive(m, f, f.body, loop); };
                auto lse = [&](ValueId v, bool need_positive) {
                    return exp_sum(f, f.body, v, rolled_term) && (!need_positive || positive_sum(f, f.body, v, weights_positive));
                };
                if (log_factor(in) == 0 || !log_pieces(f, f.body, in.args[0], 1, pieces, lse)) continue;
                for (const LogPiece& piece : pieces) {
                    if (!piece.sum) continue;
                    for (ValueId t : piece_terms(f.body, piece.v)) {
                        const Instr* loop = rolled_loop(f.body, t);
                        if (!loop || split.count(loop->aux)) continue;
                        split[loop->aux] = {-1, -1};
                        found.push_back({loop->aux, *rolled_exp_sum(m.functions[size_t(loop->aux)])});
                    }
                }
            }
        for (auto [body, x] : found) {
            auto [hi, shifted] = split_exp_sum(m, m.functions[size_t(body)], x);
            m.functions.push_back(std::move(hi));
            m.functions.push_back(std::move(shifted));
            split[body] = {int(m.functions.size()) - 2, int(m.functions.size()) - 1};
        }
    }
    for (Function& f : m.functions) rewrite_function(m, f, split, &fired);
    return fired;
}

namespace {

size_t rewrite_function(const Module& m, Function& f, const std::map<int, std::pair<int, int>>& split,
                        std::vector<StableRewrite>* fired) {
    size_t count = 0;
    {
        std::vector<Instr> old = std::move(f.body);
        f.body.clear();
        f.body.reserve(old.size());
        std::vector<ValueId> map(old.size());
        Builder b(m, f);
        for (size_t i = 0; i < old.size(); ++i) {
            const Instr& in = old[i];
            ValueId made = ValueId(-1);
            std::string what;
            auto at = [&](ValueId v) { return map[v]; };
            auto rolled_ok = [&](const Instr& loop) {
                auto it = split.find(loop.aux);
                return it != split.end() && it->second.first >= 0;
            };
            auto weights_positive = [&](const Instr& loop) { return rolled_weights_positive(m, f, old, loop); };
            auto lse = [&](ValueId v, bool need_positive) {
                return exp_sum(f, old, v, rolled_ok) && (!need_positive || positive_sum(f, old, v, weights_positive));
            };
            std::vector<LogPiece> pieces;
            bool stabilises = false;
            if (log_factor(in) != 0 && log_pieces(f, old, in.args[0], 1, pieces, lse)) {
                // (a value taken twice is one piece: log(S·S) = 2 log S)
                std::vector<LogPiece> merged;
                for (const LogPiece& piece : pieces) {
                    auto same = std::find_if(merged.begin(), merged.end(), [&](const LogPiece& o) { return o.v == piece.v; });
                    if (same != merged.end()) same->c += piece.c;
                    else merged.push_back(piece);
                }
                pieces.clear();
                for (const LogPiece& piece : merged)
                    if (piece.c != 0) pieces.push_back(piece);
                for (const LogPiece& piece : pieces) stabilises = stabilises || piece.sum || exponential(f, old, old[piece.v]);
            }
            // A ratio of sums of exponential terms, the softmax-weighted mean ∑_i d_i e^(x_i)/∑_j e^(x_j): both sums
            // times e^(-m), m the denominator's largest exponent (0/0 from 11 units, nothing drawn: a trial's, stop 54).
            std::vector<ValueId> num_ids, den_ids;
            std::vector<ExpTerm> num, den;
            auto exp_terms = [&](ValueId v, std::vector<ValueId>& ids, std::vector<ExpTerm>& out) {
                if (rolled_loop(old, v) || !sum_terms(old, v, ids) || ids.empty()) return false;
                out.resize(ids.size());
                for (size_t k = 0; k < ids.size(); ++k)
                    if (!exp_term(f, old, ids[k], out[k])) return false;
                return true;
            };
            const bool ratio = in.op == Op::Div && in.type.is_scalar() && old[in.args[1]].type.is_scalar() &&
                               exp_terms(in.args[1], den_ids, den) && den.size() >= 2 && exp_terms(in.args[0], num_ids, num);
            if (ratio) {
                ValueId hi = ValueId(-1);
                for (const ExpTerm& t : den) {
                    const ValueId c = competing(b, f, old, t, exponent_of(b, old, t, at), at);
                    hi = hi == ValueId(-1) ? c : b.builtin("max", {hi, c});
                }
                // (the denominator's terms of weight 0 shifted by the float minimum; the numerator's weights are the
                // values averaged, d_i, whose exponents are the denominator's)
                auto shifted = [&](const std::vector<ExpTerm>& terms, bool guard) {
                    ValueId sum = ValueId(-1);
                    for (const ExpTerm& t : terms) {
                        const ValueId x0 = exponent_of(b, old, t, at);
                        const ValueId x = guard ? competing(b, f, old, t, x0, at, CompareKind::Ne) : x0;
                        const ValueId e = weighted(b, t, b.builtin("exp", {b.op(Op::Sub, {x, hi})}), at);
                        sum = sum == ValueId(-1) ? e : b.op(Op::Add, {sum, e});
                    }
                    return sum;
                };
                const ValueId n = shifted(num, false), d = shifted(den, true);
                made = b.op(Op::Div, {n, d});
                what = "ratio of exponential sums";
            } else if (log_factor(in) != 0 && is_builtin(old[in.args[0]], "cosh") && old[in.args[0]].type.is_scalar()) {
                // log cosh x = |x| + log(1 + e^(-2|x|)) − ln 2 (the smooth |x|, log(cosh(k y))/k: cosh overflowed from
                // 14 units, a trial's, stop 54)
                const ValueId ax = b.builtin("abs", {map[old[in.args[0]].args[0]]});
                ValueId l = b.op(Op::Add, {ax, b.builtin("log", {b.op(Op::Add, {b.scalar(1), b.builtin("exp", {b.op(Op::Mul, {ax, b.scalar(-2)})})})})});
                l = b.op(Op::Sub, {l, b.scalar(std::log(2.0))});
                made = log_factor(in) == 1 ? l : b.op(Op::Mul, {l, b.scalar(log_factor(in))});
                what = "log cosh";
            } else if (stabilises) {
                // log-sum-exp: log of sums of exponential terms (times or over positive values), each sum in the shifted
                // form, in base e (times log_factor for log₂ and log₁₀).
                const double base = log_factor(in);
                auto in_base = [&](ValueId v) { return base == 1 ? v : b.op(Op::Mul, {v, b.scalar(base)}); };
                // log of one sum of exponential terms (a rolled one: two loops).
                // log of one sum of exponential terms, some of them rolled sums (loops: each two loops, the largest
                // exponent's and the shifted sum's, with one shift for the whole sum).
                auto sum_log = [&](ValueId v) -> ValueId {
                    const std::vector<ValueId> ids = piece_terms(old, v);
                    std::vector<ExpTerm> terms(ids.size());
                    std::vector<const Instr*> loops(ids.size(), nullptr);
                    bool any_weight = false, any_loop = false;
                    for (size_t k = 0; k < ids.size(); ++k) {
                        if ((loops[k] = rolled_loop(old, ids[k]))) {
                            any_loop = true;
                            const auto term = rolled_exp_sum(m.functions[size_t(loops[k]->aux)]);
                            any_weight = any_weight || !term || !term->weights.empty();
                        } else {
                            exp_term(f, old, ids[k], terms[k]);
                            any_weight = any_weight || !terms[k].weights.empty();
                        }
                    }
                    // The rolled ∑ at v run again with body `fn`, its first state replaced (`first`: the maximum's start)
                    // or a capture appended (the shift); its state's final value.
                    auto rerun = [&](ValueId v, int fn, ValueId first, ValueId capture) {
                        Instr l = f.body[map[old[v].args[0]]];  // (a copy: already rebuilt, its arguments are new values)
                        l.aux = fn;
                        if (first != ValueId(-1)) l.args[1] = first;
                        if (capture != ValueId(-1)) l.args.push_back(capture);
                        l.name.clear();
                        Instr member;
                        member.op = Op::Member;
                        member.type = Type::scalar();
                        member.args = {f.add(std::move(l))};
                        return f.add(member);
                    };
                    if (any_loop) {
                        // log ∑_i w_i e^(x_i), a loop: hi = max_i x_i in one loop, then hi + log ∑_i w_i e^(x_i − hi) in
                        // another (unweighted, one term is e^0 = 1: the sum is at least 1). Other terms beside the loop
                        // (a ring of 32 blobs and a core: a trial's, stop 54) share the shift.
                        std::vector<ValueId> xs(ids.size(), ValueId(-1));
                        ValueId hi = ValueId(-1);
                        for (size_t k = 0; k < ids.size(); ++k) {
                            ValueId c;
                            if (loops[k]) {
                                c = rerun(ids[k], split.at(loops[k]->aux).first, b.scalar(-3.4028234663852886e38), ValueId(-1));
                            } else {
                                xs[k] = exponent_of(b, old, terms[k], at);
                                c = competing(b, f, old, terms[k], xs[k], at);
                            }
                            hi = hi == ValueId(-1) ? c : b.builtin("max", {hi, c});
                        }
                        ValueId sum = ValueId(-1);
                        for (size_t k = 0; k < ids.size(); ++k) {
                            ValueId e;
                            if (loops[k]) {
                                e = rerun(ids[k], split.at(loops[k]->aux).second, ValueId(-1), hi);
                            } else {
                                const ValueId x = competing(b, f, old, terms[k], xs[k], at, CompareKind::Ne);
                                e = weighted(b, terms[k], b.builtin("exp", {b.op(Op::Sub, {x, hi})}), at);
                            }
                            sum = sum == ValueId(-1) ? e : b.op(Op::Add, {sum, e});
                        }
                        if (!any_weight) sum = b.builtin("max", {sum, b.scalar(1)});
                        return b.op(Op::Add, {hi, b.builtin("log", {sum})});
                    }
                    std::vector<ValueId> xs, cs;
                    for (const ExpTerm& t : terms) {
                        xs.push_back(exponent_of(b, old, t, at));
                        cs.push_back(terms.size() > 1 ? competing(b, f, old, t, xs.back(), at) : xs.back());
                    }
                    ValueId hi = cs[0];
                    for (size_t k = 1; k < cs.size(); ++k) hi = b.builtin("max", {hi, cs[k]});
                    if (any_weight || terms.size() == 1) {
                        // Weighted terms w·e^x (soft blobs: -ln(∑_i w_i e^(-k d_i))/k was +∞ at every pixel 12 units out, a
                        // trial's): m + log(∑_i w_i e^(x_i − m)), exact for any weights (no floor of 1 on the sum: a weight
                        // may be below 1). One term: log(w e^x) = x + log w.
                        if (terms.size() == 1) {
                            const ExpTerm& t = terms[0];
                            if (t.weights.empty()) return hi;
                            ValueId w = t.weights.size() == 1 && !t.weights[0].second ? at(t.weights[0].first) : weighted(b, t, b.scalar(1), at);
                            return b.op(Op::Add, {hi, b.builtin("log", {w})});
                        }
                        ValueId sum = ValueId(-1);
                        for (size_t k = 0; k < xs.size(); ++k) {
                            const ValueId x = competing(b, f, old, terms[k], xs[k], at, CompareKind::Ne);
                            ValueId e = weighted(b, terms[k], b.builtin("exp", {b.op(Op::Sub, {x, hi})}), at);
                            sum = sum == ValueId(-1) ? e : b.op(Op::Add, {sum, e});
                        }
                        return b.op(Op::Add, {hi, b.builtin("log", {sum})});
                    }
                    ValueId sum = 0;
                    if (xs.size() == 2) {
                        // max(a, b) + log(1 + e^(-|a - b|)): the sum is in [1, 2] for interval arithmetic too, so the
                        // Lipschitz pass can bound the gradient.
                        ValueId gap = b.builtin("abs", {b.op(Op::Sub, {xs[0], xs[1]})});
                        sum = b.op(Op::Add, {b.scalar(1), b.builtin("exp", {b.op(Op::Neg, {gap})})});
                    } else {
                        for (size_t k = 0; k < xs.size(); ++k) {
                            ValueId e = b.builtin("exp", {b.op(Op::Sub, {xs[k], hi})});
                            sum = k == 0 ? e : b.op(Op::Add, {sum, e});
                        }
                        // One term is e^0 = 1: the sum is at least 1, which intervals learn from the max.
                        sum = b.builtin("max", {sum, b.scalar(1)});
                    }
                    return b.op(Op::Add, {hi, b.builtin("log", {sum})});
                };
                ValueId total = ValueId(-1);
                for (const LogPiece& piece : pieces) {
                    ValueId l;
                    if (piece.sum) {
                        l = sum_log(piece.v);
                    } else if (exponential(f, old, old[piece.v])) {
                        ExpTerm t;
                        t.parts = {{piece.v, 1.0}};
                        l = exponent_of(b, old, t, at);
                    } else {
                        l = b.builtin("log", {map[piece.v]});
                    }
                    if (piece.c == -1) l = b.op(Op::Neg, {l});
                    else if (piece.c != 1) l = b.op(Op::Mul, {l, b.scalar(piece.c)});
                    total = total == ValueId(-1) ? l : b.op(Op::Add, {total, l});
                }
                made = in_base(total);
                what = "log-sum-exp";
            } else if (in.type.is_scalar() && is_builtin(in, "sqrt")) {
                // hypot: a sum of 2 to 4 squares.
                std::vector<ValueId> terms;
                if (sum_terms(old, in.args[0], terms) && terms.size() >= 2 && terms.size() <= 4) {
                    bool squares = true;
                    for (ValueId t : terms)
                        squares &= old[t].op == Op::Mul && old[t].args[0] == old[t].args[1] && old[old[t].args[0]].type.is_scalar();
                    if (squares) {
                        std::vector<ValueId> xs;
                        for (ValueId t : terms) xs.push_back(map[old[t].args[0]]);
                        made = b.builtin("length", {b.construct(Type::vector(int(xs.size())), xs)});
                        what = "hypot";
                    }
                }
            } else if (in.op == Op::Sub && in.type.is_scalar() && is_scalar_const(old[in.args[0]], 1) &&
                       is_builtin(old[in.args[1]], "cos") && old[in.args[1]].type.is_scalar()) {
                // 1 - cos x = 2 sin²(x/2)
                ValueId x = map[old[in.args[1]].args[0]];
                ValueId s = b.builtin("sin", {b.op(Op::Mul, {x, b.scalar(0.5)})});
                made = b.op(Op::Mul, {b.scalar(2), b.op(Op::Mul, {s, s})});
                what = "1 - cos";
            }
            if (made != ValueId(-1)) {
                Instr& r = f.body[made];
                r.name = in.name;
                r.source = in.source;
                r.span = in.span;
                map[i] = made;
                ++count;
                if (fired) fired->push_back({in.span, what, f.name});
                continue;
            }
            Instr copy = in;
            for (ValueId& a : copy.args) a = map[a];
            map[i] = f.add(std::move(copy));
        }
        f.result = map[f.result];
        for (auto& [name, v] : f.outputs) v = map[v];
    }
    return count;
}

}  // namespace

}  // namespace iqc::ir
