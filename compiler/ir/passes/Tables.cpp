#include "ir/passes/Tables.h"

#include <cmath>
#include <map>
#include <optional>

#include <fmt/format.h>

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

// The smallest period P ≤ n / 2 of a table's entries (entry k equals entry k mod P exactly, every component), or
// 0: from the prefix function of the entries' sequence (Knuth, Morris & Pratt 1977), whose last border b gives
// the smallest period n - b.
long long period(const Global& g) {
    const long long n = g.type.count;
    const size_t per = size_t(std::max(1, g.type.element().components()));
    if (n < 4 || g.value.size() != size_t(n) * per) return 0;
    auto same = [&](long long i, long long j) {
        for (size_t c = 0; c < per; ++c)
            if (g.value[size_t(i) * per + c] != g.value[size_t(j) * per + c]) return false;
        return true;
    };
    std::vector<long long> border(size_t(n), 0);
    for (long long i = 1; i < n; ++i) {
        long long b = border[size_t(i - 1)];
        while (b > 0 && !same(i, b)) b = border[size_t(b - 1)];
        if (same(i, b)) ++b;
        border[size_t(i)] = b;
    }
    const long long P = n - border[size_t(n - 1)];
    return 2 * P <= n ? P : 0;
}

// Whether every use of global g's value is a read of one element (Index): then the table may change shape.
bool only_indexed(const Module& m, int g) {
    for (const Function& f : m.functions)
        for (const Instr& in : f.body)
            for (size_t a = 0; a < in.args.size(); ++a) {
                const Instr& arg = f.body[in.args[a]];
                if (arg.op == Op::Global && arg.aux == g && !(in.op == Op::Index && a == 0)) return false;
            }
    return true;
}

// Rebuilds every function that reads (Index) a global for which `picks(g)` holds: each such read becomes
// `rewrite(b, in)`'s value (in: the read, its operands already in the new function). Returns the reads rewritten.
template <class Picks, class Rewrite>
int rewrite_reads(Module& m, Picks picks, Rewrite rewrite) {
    int replaced = 0;
    for (auto& f : m.functions) {
        bool any = false;
        for (const Instr& in : f.body) any |= in.op == Op::Index && f.body[in.args[0]].op == Op::Global && picks(f.body[in.args[0]].aux);
        if (!any) continue;
        Function out = f;
        out.body.clear();
        Builder b(m, out);
        std::vector<ValueId> map(f.body.size());
        for (size_t i = 0; i < f.body.size(); ++i) {
            Instr in = f.body[i];
            for (ValueId& a : in.args) a = map[a];
            if (in.op == Op::Index && out.body[in.args[0]].op == Op::Global && picks(out.body[in.args[0]].aux)) {
                map[i] = rewrite(b, std::move(in));
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

int compress_periodic(Module& m, const std::map<int, std::optional<std::vector<Lattice>>>& fits) {
    // Periodic tables (entries that repeat every P members, as tilts cycling through 7 angles do) keep one period,
    // read at k mod P: llvmpipe's compile grows with the square of a code table's elements (100 tilted tori, a
    // vec2[100] -> vec2[7]: 486.9 -> 462.9 M instructions of compile and an 8×8 draw), and the modulo, by
    // multiplication (Builder::mod_by_constant), costs no more than the larger table's reads (frame 1.00×).
    std::map<int, long long> periods;
    for (size_t g = 0; g < m.globals.size(); ++g) {
        const Global& gl = m.globals[g];
        if (auto it = fits.find(int(g)); it != fits.end() && it->second) continue;  // arithmetic already
        if (gl.kind != Global::Kind::Constant || !gl.type.is_array() || gl.type.elem == Type::Integer) continue;
        if (long long P = period(gl); P > 0 && only_indexed(m, int(g))) periods[int(g)] = P;
    }
    if (periods.empty()) return 0;
    const int replaced = rewrite_reads(m, [&](int g) { return periods.count(g) > 0; }, [&](Builder& b, Instr in) {
        const int g = b.function().body[in.args[0]].aux;
        in.args[1] = b.mod_by_constant(in.args[1], periods[g], m.globals[size_t(g)].type.count);
        return b.function().add(std::move(in));
    });
    for (auto& f : m.functions)  // the globals' reads say their new length
        for (Instr& in : f.body)
            if (in.op == Op::Global && periods.count(in.aux)) in.type.count = int(periods[in.aux]);
    for (auto& [g, P] : periods) {
        Global& gl = m.globals[size_t(g)];
        const long long n = gl.type.count;
        gl.value.resize(size_t(P) * gl.value.size() / size_t(n));
        gl.type.count = int(P);
        gl.comment += fmt::format("{}one period of {} entries: member k's at k mod {}", gl.comment.empty() ? "" : " — ", n, P);
    }
    return replaced;
}

}  // namespace

int compress_tables(Module& m) {
    std::map<int, std::optional<std::vector<Lattice>>> fits;
    for (const auto& f : m.functions)
        for (const Instr& in : f.body)
            if (in.op == Op::Index && f.body[in.args[0]].op == Op::Global && !fits.count(f.body[in.args[0]].aux))
                fits[f.body[in.args[0]].aux] = fit_table(m.globals[size_t(f.body[in.args[0]].aux)]);
    const int replaced = rewrite_reads(m, [&](int g) { return fits.count(g) && fits[g].has_value(); }, [&](Builder& b, Instr in) {
        const int g = b.function().body[in.args[0]].aux;
        const auto& lat = *fits[g];
        const long long n = m.globals[size_t(g)].type.count;  // k ∈ [0, n): a read in range
        ValueId k = in.args[1];
        std::vector<ValueId> comps;
        for (const Lattice& l : lat) {
            ValueId v = 0;
            bool have = l.base != 0;
            if (have) v = b.scalar(l.base);
            for (const Term& t : l.terms) {
                ValueId q = b.div_by_constant(k, t.d, n);
                if (t.m) q = b.mod_by_constant(q, t.m, (n - 1) / t.d + 1);
                double a = have ? std::fabs(t.a) : t.a;  // after the first term, a - |a|q for a < 0
                ValueId term = a == 1 ? q : b.op(Op::Mul, {b.scalar(a), q});
                v = !have ? term : b.op(t.a < 0 ? Op::Sub : Op::Add, {v, term});
                have = true;
            }
            if (!have) v = b.scalar(0);
            if (b.type(v).kind == Type::Integer) v = b.op(Op::Add, {b.scalar(0), v});  // a real component
            comps.push_back(v);
        }
        return comps.size() == 1 ? comps[0] : b.construct(in.type, comps);
    });
    return replaced + compress_periodic(m, fits);
}

}  // namespace iqc::ir
