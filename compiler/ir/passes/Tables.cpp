#include "ir/passes/Tables.h"

#include <cmath>
#include <map>
#include <optional>

#include "ir/Builder.h"

namespace iqc::ir {

namespace {

struct Term {
    double a = 0;       // coefficient
    long long d = 1;    // divisor
    long long m = 0;    // modulus (0: none, the last level)
};

struct Lattice {
    double base = 0;
    std::vector<Term> terms;
};

bool close(double x, double y) { return std::fabs(x - y) <= 1e-9 * std::max(1.0, std::max(std::fabs(x), std::fabs(y))); }

double value(const Lattice& l, long long k) {
    double v = l.base;
    for (const Term& t : l.terms) v += t.a * double(t.m ? (k / t.d) % t.m : k / t.d);
    return v;
}

// The lattice of s[k] = values[k * stride + offset], k < n, if there is one with at most 4 terms.
std::optional<Lattice> fit(const std::vector<double>& values, size_t stride, size_t offset, long long n) {
    auto s = [&](long long k) { return values[size_t(k) * stride + offset]; };
    Lattice l;
    l.base = s(0);
    long long d = 1;  // entries of the current level are s[j·d]
    while (d < n) {
        long long count = (n + d - 1) / d;  // entries at this level
        // The level's value at j: s[j·d] minus the terms found so far.
        auto level = [&](long long j) {
            double v = s(j * d);
            for (const Term& t : l.terms) v -= t.a * double((j * d / t.d) % t.m);
            return v - l.base;
        };
        double step = count > 1 ? level(1) - level(0) : 0;
        long long run = 1;
        while (run < count && close(level(run), step * double(run))) ++run;
        if (run >= count) {  // the rest is linear in j
            if (step != 0) l.terms.push_back({step, d, 0});
            break;
        }
        if (run < 2) return std::nullopt;  // no regular run to repeat
        if (step != 0) l.terms.push_back({step, d, run});
        if (l.terms.size() > 4) return std::nullopt;
        d *= run;
    }
    for (long long k = 0; k < n; ++k)
        if (!close(value(l, k), s(k))) return std::nullopt;
    return l;
}

// Lattices for every component of a table, or nothing when one does not fit.
std::optional<std::vector<Lattice>> fit_table(const Global& g) {
    if (g.kind != Global::Kind::Constant || !g.type.is_array() || g.type.count < 2) return std::nullopt;
    // Tables of ℤ (a hierarchy's child and member indices) stay tables: the arithmetic built here is real,
    // and their values index further tables (a real index has no IntDiv or IntMod).
    if (g.type.elem == Type::Integer) return std::nullopt;
    size_t per = size_t(std::max(1, g.type.element().components()));
    std::vector<Lattice> out;
    for (size_t c = 0; c < per; ++c) {
        auto l = fit(g.value, per, c, g.type.count);
        if (!l) return std::nullopt;
        out.push_back(*l);
    }
    return out;
}

}  // namespace

int compress_tables(Module& m) {
    std::map<int, std::optional<std::vector<Lattice>>> fits;
    int replaced = 0;
    for (auto& f : m.functions) {
        bool any = false;
        for (const Instr& in : f.body)
            if (in.op == Op::Index && f.body[in.args[0]].op == Op::Global) {
                int g = f.body[in.args[0]].aux;
                if (!fits.count(g)) fits[g] = fit_table(m.globals[size_t(g)]);
                any |= fits[g].has_value();
            }
        if (!any) continue;
        Function out = f;
        out.body.clear();
        Builder b(m, out);
        std::vector<ValueId> map(f.body.size());
        for (size_t i = 0; i < f.body.size(); ++i) {
            Instr in = f.body[i];
            for (ValueId& a : in.args) a = map[a];
            if (in.op == Op::Index && out.body[in.args[0]].op == Op::Global && fits[out.body[in.args[0]].aux]) {
                const auto& lat = *fits[out.body[in.args[0]].aux];
                ValueId k = in.args[1];
                std::vector<ValueId> comps;
                for (const Lattice& l : lat) {
                    ValueId v = 0;
                    bool have = l.base != 0;
                    if (have) v = b.scalar(l.base);
                    for (const Term& t : l.terms) {
                        ValueId q = t.d == 1 ? k : b.op(Op::IntDiv, {k, b.integer(t.d)});
                        if (t.m) q = b.op(Op::IntMod, {q, b.integer(t.m)});
                        double a = have ? std::fabs(t.a) : t.a;  // after the first term, a - |a|q for a < 0
                        ValueId term = a == 1 ? q : b.op(Op::Mul, {b.scalar(a), q});
                        v = !have ? term : b.op(t.a < 0 ? Op::Sub : Op::Add, {v, term});
                        have = true;
                    }
                    if (!have) v = b.scalar(0);
                    if (b.type(v).kind == Type::Integer) v = b.op(Op::Add, {b.scalar(0), v});  // a real component
                    comps.push_back(v);
                }
                map[i] = comps.size() == 1 ? comps[0] : b.construct(in.type, comps);
                ++replaced;
                continue;
            }
            map[i] = out.add(std::move(in));
        }
        out.result = map[f.result];
        for (auto& [name, v] : out.outputs) v = map[v];
        f = std::move(out);
    }
    return replaced;
}

}  // namespace iqc::ir
