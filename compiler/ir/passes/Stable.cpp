#include "ir/passes/Stable.h"

#include "ir/Builder.h"
#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

constexpr size_t kMaxTerms = 16;  // a longer sum is left as written (and so is its cost)

bool is_builtin(const Instr& in, const char* name) {
    return in.op == Op::Builtin && std::string_view(builtin(in.aux).name) == name;
}

bool is_scalar_const(const Instr& in, double v) {
    return in.op == Op::Const && in.type.is_scalar() && in.data.size() == 1 && in.data[0] == v;
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

}  // namespace

std::vector<StableRewrite> rewrite_unstable_forms(Module& m) {
    std::vector<StableRewrite> fired;
    for (Function& f : m.functions) {
        std::vector<Instr> old = std::move(f.body);
        f.body.clear();
        f.body.reserve(old.size());
        std::vector<ValueId> map(old.size());
        Builder b(m, f);
        for (size_t i = 0; i < old.size(); ++i) {
            const Instr& in = old[i];
            ValueId made = ValueId(-1);
            std::string what;
            if (in.type.is_scalar() && (is_builtin(in, "log") || is_builtin(in, "ln"))) {
                // log-sum-exp: every term of the argument's sum is e^(something).
                std::vector<ValueId> terms;
                if (sum_terms(old, in.args[0], terms) && terms.size() >= 2) {
                    bool all_exp = true;
                    for (ValueId t : terms) all_exp &= is_builtin(old[t], "exp");
                    if (all_exp) {
                        std::vector<ValueId> xs;
                        for (ValueId t : terms) xs.push_back(map[old[t].args[0]]);
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
                        made = b.op(Op::Add, {hi, b.builtin("log", {sum})});
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
                fired.push_back({in.span, what, f.name});
                continue;
            }
            Instr copy = in;
            for (ValueId& a : copy.args) a = map[a];
            map[i] = f.add(std::move(copy));
        }
        f.result = map[f.result];
        for (auto& [name, v] : f.outputs) v = map[v];
    }
    return fired;
}

}  // namespace iqc::ir
