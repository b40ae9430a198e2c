#include "ir/passes/Stable.h"

#include "ir/Builder.h"
#include "ir/passes/Inline.h"

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

// Whether `t` is an exponential: e^x, or c^x for a constant c > 0 (e^(x ln c)).
bool exponential(const std::vector<Instr>& body, const Instr& t) {
    if (is_builtin(t, "exp")) return true;
    return is_builtin(t, "pow") && t.type.is_scalar() && t.args.size() == 2 && body[t.args[0]].op == Op::Const &&
           body[t.args[0]].data.size() == 1 && body[t.args[0]].data[0] > 0 && body[t.args[0]].data[0] != 1;
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

// A rolled ∑ of exponentials (a Loop whose body adds e^x to its one state, x not reading the state): x's value in
// the body, else none.
std::optional<ValueId> rolled_exp_sum(const Function& body) {
    if (body.outputs.size() != 1 || !body.body[body.outputs[0].second].type.is_scalar()) return std::nullopt;
    auto e = accumulated_term(body, 0);
    if (!e || !is_builtin(body.body[*e], "exp")) return std::nullopt;
    return body.body[*e].args[0];
}

// The state parameter (the running sum, parameter 1) of a loop body.
ValueId state_param(const Function& body) {
    for (size_t i = 0; i < body.body.size(); ++i)
        if (body.body[i].op == Op::Param && body.body[i].aux == 1) return ValueId(i);
    return ValueId(-1);
}

// The bodies of the two loops that replace a rolled log-sum-exp: the running maximum of x, and the sum of
// e^(x − hi) with hi a capture (the last parameter).
std::pair<Function, Function> split_exp_sum(const Module& m, const Function& body, ValueId x) {
    Function hi = body, shifted = body;
    hi.name += ".max";
    hi.glsl_name = hi.name;
    {
        Builder b(m, hi);
        ValueId v = b.builtin("max", {state_param(hi), x});
        hi.outputs = {{"hi", v}};
        hi.result = v;
    }
    shifted.name += ".shifted";
    shifted.glsl_name = shifted.name;
    {
        Builder b(m, shifted);
        const ValueId state = state_param(shifted);
        ValueId h = b.param("hi", Type::scalar());
        ValueId v = b.op(Op::Add, {state, b.builtin("exp", {b.op(Op::Sub, {x, h})})});
        shifted.outputs = {{"sum", v}};
        shifted.result = v;
    }
    return {std::move(hi), std::move(shifted)};
}

using Splits = std::map<int, std::pair<int, int>>;

// Rewrites f's unstable forms (the rolled sums of `split` by their replacement loops); returns how many fired, and
// appends them to `fired` (when given). Reads no other function: a copy of f may be tried.
size_t rewrite_function(const Module& m, Function& f, const Splits& split, std::vector<StableRewrite>* fired);

// Which functions compute a logarithm or an exponential, themselves or in what they call or loop over.
std::vector<char> log_or_exp_functions(const Module& m) {
    std::vector<char> marked(m.functions.size(), 0);
    for (size_t i = 0; i < m.functions.size(); ++i)
        for (const Instr& in : m.functions[i].body)
            if (log_factor(in) != 0 || exponential(m.functions[i].body, in)) marked[i] = 1;
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

// A logarithm of a rolled ∑ (a Loop starting at 0) whose term is a call of `local` (the loop body's term, not yet
// inlined): where a log-sum-exp spans a module's local functions.
bool log_of_rolled_call(const Module& m, const Function& f, const std::vector<char>& local) {
    for (const Instr& in : f.body) {
        if (log_factor(in) == 0 || f.body[in.args[0]].op != Op::Member) continue;
        const Instr& loop = f.body[f.body[in.args[0]].args[0]];
        if (loop.op != Op::Loop || loop.args.size() < 2 || !is_scalar_const(f.body[loop.args[1]], 0)) continue;
        const Function& body = m.functions[size_t(loop.aux)];
        auto t = accumulated_term(body, 0);
        if (t && body.body[*t].op == Op::Call && local[size_t(body.body[*t].aux)]) return true;
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
        for (size_t j = 0; j < m.functions.size(); ++j) {
            local[j] = bearing[j] && j != i && module_of(m.functions[j].name) == own && m.functions[j].name != own;
        }
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
    // The rolled sums' bodies whose term is a local call: that call inlined (the body's own exponential shows).
    for (int bi : rolled_bodies) {
        const Function& body = m.functions[size_t(bi)];
        auto t = accumulated_term(body, 0);
        if (!t || body.body[*t].op != Op::Call) continue;
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
        std::vector<std::pair<int, ValueId>> found;
        for (const Function& f : m.functions)
            for (const Instr& in : f.body) {
                if (!in.type.is_scalar() || !(is_builtin(in, "log") || is_builtin(in, "ln"))) continue;
                const Instr& a = f.body[in.args[0]];
                if (a.op != Op::Member || a.aux != 0 || f.body[a.args[0]].op != Op::Loop) continue;
                const Instr& loop = f.body[a.args[0]];
                if (split.count(loop.aux) || loop.args.size() < 2) continue;
                const Instr& init = f.body[loop.args[1]];
                if (init.op != Op::Const || init.data.size() != 1 || init.data[0] != 0) continue;
                if (auto x = rolled_exp_sum(m.functions[size_t(loop.aux)])) {
                    split[loop.aux] = {-1, -1};
                    found.push_back({loop.aux, *x});
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
            const Instr* member = in.args.empty() ? nullptr : &old[in.args[0]];
            const bool rolled = in.type.is_scalar() && (is_builtin(in, "log") || is_builtin(in, "ln")) && member->op == Op::Member &&
                                member->aux == 0 && old[member->args[0]].op == Op::Loop && split.count(old[member->args[0]].aux) &&
                                split.at(old[member->args[0]].aux).first >= 0 && old[old[member->args[0]].args[1]].op == Op::Const;
            if (rolled) {
                // log ∑_i e^(x_i), a loop: hi = max_i x_i in one loop, then hi + log ∑_i e^(x_i − hi) in another (one
                // term is e^0 = 1: the sum is at least 1).
                const Instr loop = f.body[map[member->args[0]]];  // (a copy: already rebuilt, its arguments are new values)
                auto [max_fn, sum_fn] = split.at(old[member->args[0]].aux);
                Instr l1 = loop;
                l1.aux = max_fn;
                l1.args[1] = b.scalar(-3.4028234663852886e38);
                l1.name.clear();
                ValueId hi_loop = f.add(std::move(l1));
                Instr mh;
                mh.op = Op::Member;
                mh.type = Type::scalar();
                mh.args = {hi_loop};
                ValueId hi = f.add(mh);
                Instr l2 = loop;
                l2.aux = sum_fn;
                l2.args.push_back(hi);
                l2.name.clear();
                ValueId sum_loop = f.add(std::move(l2));
                Instr ms = mh;
                ms.args = {sum_loop};
                ValueId sum = b.builtin("max", {f.add(ms), b.scalar(1)});
                made = b.op(Op::Add, {hi, b.builtin("log", {sum})});
                what = "log-sum-exp";
            } else if (log_factor(in) != 0) {
                // log-sum-exp: every term of the argument's sum is e^(something) (or c^(something): in base e, and the
                // result times log_factor for log₂ and log₁₀).
                const double base = log_factor(in);
                // The exponent of an exponential term in base e (built where it is c^y: y ln c).
                auto exponent = [&](const Instr& t) {
                    if (is_builtin(t, "exp")) return map[t.args[0]];
                    return b.op(Op::Mul, {map[t.args[1]], b.scalar(std::log(old[t.args[0]].data[0]))});
                };
                auto in_base = [&](ValueId v) { return base == 1 ? v : b.op(Op::Mul, {v, b.scalar(base)}); };
                std::vector<ValueId> terms;
                // Weighted terms w·e^x (soft blobs: -ln(∑_i w_i e^(-k d_i))/k was +∞ at every pixel 12 units out, a trial's):
                // m + log(∑_i w_i e^(x_i − m)), exact for any weights (no floor of 1 on the sum: a weight may be below 1).
                // One term: log(e^x) = x, log(w e^x) = x + log w (a sequence of one point, stop 52).
                std::vector<ValueId> ws, xs_w;
                bool weighted = sum_terms(old, in.args[0], terms) && !terms.empty();
                for (ValueId t : terms) {  // (the form first: nothing is built where it is not one)
                    const Instr& ti = old[t];
                    weighted = weighted && (exponential(old, ti) || (ti.op == Op::Mul && ti.type.is_scalar() && ti.args.size() == 2 &&
                                                                     (exponential(old, old[ti.args[0]]) || exponential(old, old[ti.args[1]]))));
                }
                for (ValueId t : terms) {
                    if (!weighted) break;
                    const Instr& ti = old[t];
                    if (exponential(old, ti)) {
                        ws.push_back(ValueId(-1));
                        xs_w.push_back(ValueId(-1));
                    } else {
                        const int e = exponential(old, old[ti.args[0]]) ? 0 : 1;
                        ws.push_back(map[ti.args[size_t(1 - e)]]);
                        xs_w.push_back(ValueId(-1));
                    }
                }
                bool any_weight = false;
                for (ValueId w : ws) any_weight = any_weight || w != ValueId(-1);
                if (weighted && (any_weight || terms.size() == 1)) {
                    for (size_t k = 0; k < terms.size(); ++k) {
                        const Instr& ti = old[terms[k]];
                        xs_w[k] = exponent(exponential(old, ti) ? ti : old[ti.args[exponential(old, old[ti.args[0]]) ? 0 : 1]]);
                    }
                    ValueId hi = xs_w[0];
                    for (size_t k = 1; k < xs_w.size(); ++k) hi = b.builtin("max", {hi, xs_w[k]});
                    if (terms.size() == 1) {
                        made = in_base(ws[0] == ValueId(-1) ? hi : b.op(Op::Add, {hi, b.builtin("log", {ws[0]})}));
                    } else {
                        ValueId sum = ValueId(-1);
                        for (size_t k = 0; k < xs_w.size(); ++k) {
                            ValueId e = b.builtin("exp", {b.op(Op::Sub, {xs_w[k], hi})});
                            if (ws[k] != ValueId(-1)) e = b.op(Op::Mul, {ws[k], e});
                            sum = sum == ValueId(-1) ? e : b.op(Op::Add, {sum, e});
                        }
                        made = in_base(b.op(Op::Add, {hi, b.builtin("log", {sum})}));
                    }
                    what = "log-sum-exp";
                } else if (terms.size() >= 2 && !any_weight && weighted) {
                    bool all_exp = true;
                    for (ValueId t : terms) all_exp &= exponential(old, old[t]);
                    if (all_exp) {
                        std::vector<ValueId> xs;
                        for (ValueId t : terms) xs.push_back(exponent(old[t]));
                        ValueId hi = xs[0];
                        for (size_t k = 1; k < xs.size(); ++k) hi = b.builtin("max", {hi, xs[k]});
                        ValueId sum = 0;
                        if (xs.size() == 2) {
                            // max(a, b) + log(1 + e^(-|a - b|)): the sum is in [1, 2] for interval
                            // arithmetic too, so the Lipschitz pass can bound the gradient.
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
                        made = in_base(b.op(Op::Add, {hi, b.builtin("log", {sum})}));
                        what = "log-sum-exp";
                    }
                }
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
