#include "ir/passes/Linear.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace iqc::ir {

namespace {

constexpr size_t kMaxTerms = 8;

// c + Σ coef·atom, atoms in increasing order (values of the old body).
struct Form {
    std::vector<std::pair<ValueId, double>> terms;
    double c = 0;
    size_t written = 0;  // terms the value's own expression names (a + d - a: 3)
};

Form combine(const Form& x, const Form& y, double sy) {
    Form r;
    r.c = x.c + sy * y.c;
    size_t i = 0, j = 0;
    while (i < x.terms.size() || j < y.terms.size()) {
        if (j == y.terms.size() || (i < x.terms.size() && x.terms[i].first < y.terms[j].first)) {
            r.terms.push_back(x.terms[i++]);
        } else if (i == x.terms.size() || y.terms[j].first < x.terms[i].first) {
            r.terms.push_back({y.terms[j].first, sy * y.terms[j].second});
            ++j;
        } else {
            double k = x.terms[i].second + sy * y.terms[j].second;
            if (k != 0) r.terms.push_back({x.terms[i].first, k});
            ++i, ++j;
        }
    }
    r.written = x.written + y.written;
    return r;
}

Form scaled(const Form& x, double s) {
    Form r = x;
    r.c *= s;
    for (auto& t : r.terms) t.second *= s;
    if (s == 0) r.terms.clear();
    return r;
}

}  // namespace

int cancel_linear_terms(Function& f) {
    const size_t n = f.body.size();
    std::vector<std::optional<Form>> form(n);
    std::vector<Instr> old = std::move(f.body);
    f.body.clear();
    std::vector<ValueId> remap(n);
    int rewritten = 0;
    auto push = [&](Instr in) {
        f.body.push_back(std::move(in));
        return ValueId(f.body.size() - 1);
    };
    auto scalar_const = [&](double v) {
        Instr in;
        in.op = Op::Const;
        in.type = Type::scalar();
        in.data = {v};
        return push(std::move(in));
    };
    auto binary = [&](Op op, ValueId a, ValueId b) {
        Instr in;
        in.op = op;
        in.type = Type::scalar();
        in.args = {a, b};
        return push(std::move(in));
    };
    // The terms of a form (without its constant) as new values; kNone when there are none.
    constexpr ValueId kNone = ValueId(-1);
    auto emit_terms = [&](const Form& x) {
        ValueId sum = kNone;
        for (const auto& [atom, k] : x.terms) {
            ValueId v = remap[atom];
            if (k == -1 && sum != kNone) {
                sum = binary(Op::Sub, sum, v);
                continue;
            }
            if (k == -1) {
                Instr neg;
                neg.op = Op::Neg;
                neg.type = Type::scalar();
                neg.args = {v};
                v = push(std::move(neg));
            } else if (k != 1) {
                v = binary(Op::Mul, scalar_const(k), v);
            }
            sum = sum == kNone ? v : binary(Op::Add, sum, v);
        }
        return sum;
    };
    for (size_t i = 0; i < n; ++i) {
        Instr in = old[i];
        for (ValueId& a : in.args) a = remap[a];
        const Instr& o = old[i];
        auto fa = [&](size_t k) -> const std::optional<Form>& { return form[o.args[k]]; };
        std::optional<Form> r;
        if (o.op == Op::Extract && o.name.empty() && old[o.args[0]].op == Op::Construct && old[o.args[0]].type.is_vector() &&
            size_t(o.aux) < old[o.args[0]].args.size() && old[old[o.args[0]].args[size_t(o.aux)]].type == o.type) {
            // a component of a vector built from scalars: that scalar itself
            ValueId part = old[o.args[0]].args[size_t(o.aux)];
            remap[i] = remap[part];
            form[i] = form[part];
            ++rewritten;
            continue;
        }
        if (o.type.kind == Type::Scalar) {
            if (o.op == Op::Const && o.data.size() == 1 && std::isfinite(o.data[0])) {
                r = Form{{}, o.data[0], 0};
            } else if ((o.op == Op::Add || o.op == Op::Sub) && fa(0) && fa(1)) {
                r = combine(*fa(0), *fa(1), o.op == Op::Add ? 1.0 : -1.0);
            } else if ((o.op == Op::Neg || o.op == Op::Copy) && fa(0)) {
                r = scaled(*fa(0), o.op == Op::Neg ? -1.0 : 1.0);
            } else if (o.op == Op::Mul && fa(0) && fa(1) && (fa(0)->terms.empty() || fa(1)->terms.empty())) {
                bool first = fa(0)->terms.empty();
                r = scaled(first ? *fa(1) : *fa(0), first ? fa(0)->c : fa(1)->c);
            } else if (o.op == Op::Div && fa(0) && fa(1) && fa(1)->terms.empty() && fa(1)->c != 0 && std::isfinite(1 / fa(1)->c)) {
                r = scaled(*fa(0), 1 / fa(1)->c);
            }
            if (r && (r->terms.size() > kMaxTerms || !std::isfinite(r->c))) r.reset();
        }
        if (r && r->terms.size() < r->written) {
            // Terms cancelled or merged: the canonical sum replaces the expression as written.
            ValueId v = emit_terms(*r);
            if (r->c != 0 || v == kNone) v = v == kNone ? scalar_const(r->c) : binary(Op::Add, v, scalar_const(r->c));
            if (!o.name.empty()) {
                Instr copy;
                copy.op = Op::Copy;
                copy.type = Type::scalar();
                copy.args = {v};
                copy.name = o.name;
                copy.source = o.source;
                copy.span = o.span;
                v = push(std::move(copy));
            }
            remap[i] = v;
            r->written = r->terms.size();
            form[i] = r;
            ++rewritten;
            continue;
        }
        if (o.op == Op::Compare && fa(0) && fa(1) && old[o.args[0]].type.kind == Type::Scalar &&
            old[o.args[1]].type.kind == Type::Scalar) {
            Form d = combine(*fa(0), *fa(1), -1.0);
            if (d.terms.size() < d.written && d.terms.size() <= kMaxTerms && std::isfinite(d.c)) {
                // x ⋚ y as (x - y without its constant) ⋚ -constant
                ValueId lhs = emit_terms(d);
                if (lhs == kNone) lhs = scalar_const(0);
                in.args = {lhs, scalar_const(d.c == 0 ? 0.0 : -d.c)};
                remap[i] = push(std::move(in));
                ++rewritten;
                continue;
            }
        }
        if (!r) r = Form{{{ValueId(i), 1.0}}, 0, 1};  // a term of its own
        else r->written = std::min(r->written, std::max<size_t>(r->terms.size(), 1));
        form[i] = r;
        remap[i] = push(std::move(in));
    }
    f.result = remap[f.result];
    for (auto& [name, v] : f.outputs) v = remap[v];
    return rewritten;
}

}  // namespace iqc::ir
