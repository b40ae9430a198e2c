#include "ir/passes/Ranges.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <optional>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using limits::kFloatMax;
constexpr double kExpOverflow = 88.72283905206835;   // ln(kFloatMax)

enum GuardKind { kNone, kClampUnit, kNonNegative, kPowBase, kAtan2, kNormalize, kDivLength };

struct Range {
    std::vector<Interval> c;  // per component
    bool known = false;       // derived from constants and parameters only
    bool unit = false;        // a unit vector (normalize, v/‖v‖)
    bool nonzero = false;     // never 0 where it is read (under a condition x ≠ 0: `1/x if x ≠ 0`)
    // How far the shader's 32-bit value may lie outside `c` (each end, absolute) where the intervals are exact in
    // real arithmetic: rounding that a difference near 0 magnifies. s ≥ 0.03 ⇒ s/0.03 − 1 ≥ 0, but the shader's
    // s·33.333332 − 1 is −6e-8 at s = 0.03: a square root of it is NaN (a trial's, stop 52). 0 where the value's
    // sign is exact (a parameter, a constant, s − 0.03 with s ≥ 0.03: IEEE rounding is monotone, x·x, |x|).
    double tol = 0;
    bool rounded = false;     // computed with a rounding (not a parameter, a constant or a choice among them)
};

// The textbook interval rules are ir/Intervals.h's (a sum of opposite infinities is unbounded, not NaN).
using iv::add;
using iv::contains_zero;
using iv::hull;
using iv::mul;
using iv::neg;
Interval unknown() { return {}; }

std::string fmt_interval(Interval a) {
    auto n = [](double x) { return std::isinf(x) ? std::string(x > 0 ? "∞" : "-∞") : fmt::format("{:.4g}", x == 0 ? 0.0 : x); };
    return fmt::format("[{}, {}]", n(a.lo), n(a.hi));
}

// "it ranges over [a, b]", or "it is x" for a single value (a constant).
std::string ranges_over(Interval a) {
    if (a.lo == a.hi) return fmt::format("it is {:.4g}", a.lo);
    return "it ranges over " + fmt_interval(a);
}

Interval monotone(Interval a, double (*f)(double)) { return {f(a.lo), f(a.hi)}; }

// Float's relative rounding allowance: 8 units in the last place of a float (a few roundings of the operands).
constexpr double kFloatSlack = 0x1p-20;

double magnitude_finite(const Range& x) {
    double m = 0;
    for (const auto& c : x.c) {
        if (std::isfinite(c.lo)) m = std::max(m, std::fabs(c.lo));
        if (std::isfinite(c.hi)) m = std::max(m, std::fabs(c.hi));
    }
    return m;
}

struct Analyzer {
    const Module& m;
    const Function& f;
    std::vector<Range> r;
    std::vector<RangeIssue> issues;
    std::vector<char> underflows = {};  // per value: it can fall below the smallest normal float (a shader's 0)
    const std::vector<Range>* params = nullptr;  // a loop body's parameters, where one is analysed (accumulated)
    // Calls of functions whose parameters have no bounds of their own (a module's local functions, the standard
    // library's) are analysed with their arguments' ranges (eval's Op::Call): `g() = 1/s` with s ∈ [0, 1] warned of
    // nothing, also under --strict-ranges (a trial's, stop 52), and g(2)/g(1) was a division by anything. `depth`
    // nests them; `work` bounds the instructions all of one function's calls analyse (a shared budget).
    int depth = 0;
    long* work = nullptr;
    bool quiet = false;        // no warnings (a first pass for `plain`)
    bool narrowing = true;     // ranges under the conditions of choices (find_guards, facts)
    // Every value's range without conditions, where a condition compares with a value computed after the one it
    // guards (`1/w if w ≥ max(1e-5, 3e-5|x|)`: the case's value comes first): a quiet first pass, made when needed.
    std::vector<Range> plain = {};
    bool plain_made = false;
    const Range& plain_range(ValueId v) {
        if (!plain_made) {
            plain_made = true;
            Analyzer pre{m, f, {}, {}};
            pre.params = params;
            pre.depth = depth;
            pre.work = work;
            pre.quiet = true;
            pre.narrowing = false;
            pre.scan(nullptr);
            plain = std::move(pre.r);
        }
        return plain[v];
    }

    Range all_unknown(const Type& t) {
        Range x;
        x.c.assign(size_t(std::max(1, t.components())), unknown());
        return x;
    }
    Interval comp(ValueId v, size_t k) const {
        const auto& c = r[v].c;
        return c.size() == 1 ? c[0] : c[k];
    }
    bool known(const Instr& in) const {
        for (ValueId a : in.args)
            if (!r[a].known) return false;
        return true;
    }
    // Per instruction: whether the function's result or an output reads it (scan). The stable pass leaves the
    // forms it rewrote behind (log(e^a + e^b)'s e^a) until dead-code removal: their warnings would be false.
    std::vector<char> live = {};
    bool source_spans = false;  // the function has instructions of the source (scan): not IR text
    // Per instruction: the conditions (a truth value and which way) under which alone it is computed — it is
    // used only by one arm of an If or Select, or by values that are (find_guards). `1/s if s > 0.1` divides by
    // s ∈ (0.1, 1], not by s ∈ [-1, 1]: the division warned, a trial's (stop 51) `∑_(i for w_i > 0.5) 1/w_i` too.
    std::vector<std::vector<std::pair<ValueId, bool>>> guarded = {};
    bool unreachable = false;  // the instruction being scanned is under conditions its operands' ranges never meet

    // Fills `guarded`: for each arm of each If and Select, the values computed for that arm alone (every use is
    // the arm or such a value; the result and named outputs are uses outside) — reading back from the arm.
    void find_guards() {
        const size_t n = f.body.size();
        guarded.assign(n, {});
        std::vector<std::vector<ValueId>> users(n);
        std::vector<char> outside(n, 0);
        size_t choices = 0;
        for (size_t u = 0; u < n; ++u) {
            for (ValueId a : f.body[u].args) users[a].push_back(ValueId(u));
            choices += f.body[u].op == Op::If || f.body[u].op == Op::Select;
        }
        if (choices == 0 || double(choices) * double(n) > 2e7) return;  // (quadratic: a bound on the work)
        if (n > 0) outside[f.result] = 1;
        for (const auto& [name, v] : f.outputs) outside[v] = 1;
        std::vector<size_t> mark(n, 0);  // the cone of choice `stamp`: mark[v] == stamp
        size_t stamp = 0;
        for (size_t s = 0; s < n; ++s) {
            const Instr& choice = f.body[s];
            if ((choice.op != Op::If && choice.op != Op::Select) || choice.args.size() != 3) continue;
            for (size_t arm = 1; arm <= 2; ++arm) {
                const ValueId a = choice.args[arm];
                if (a == choice.args[3 - arm] || a == choice.args[0] || outside[a]) continue;
                ++stamp;
                bool any = false;
                for (size_t v = a + 1; v-- > 0;) {
                    if (outside[v] || users[v].empty()) continue;
                    bool inside = true;
                    for (ValueId u : users[v]) inside = inside && (v == a ? u == s : mark[u] == stamp);
                    if (!inside) continue;
                    mark[v] = stamp;
                    guarded[v].push_back({choice.args[0], arm == 1});
                    any = true;
                }
                (void)any;
            }
        }
    }

    // What `cond` being `truth` says of scalar values computed before instruction `at`: (value, interval) pairs.
    struct Fact {
        ValueId value;
        Interval within;
        bool nonzero;  // x ≠ 0 (within says nothing)
    };
    void facts(ValueId cond, bool truth, size_t at, std::vector<Fact>& out, int depth = 0) {
        if (depth > 8) return;
        const Instr& c = f.body[cond];
        if ((c.op == Op::And && truth) || (c.op == Op::Or && !truth)) {
            facts(c.args[0], truth, at, out, depth + 1);
            facts(c.args[1], truth, at, out, depth + 1);
            return;
        }
        if (c.op != Op::Compare || c.args.size() != 2) return;
        CompareKind k = CompareKind(c.aux);
        if (!truth) {
            static constexpr CompareKind negated[] = {CompareKind::Ne, CompareKind::Eq, CompareKind::Ge,
                                                      CompareKind::Gt, CompareKind::Le, CompareKind::Lt};
            k = negated[int(k)];
        }
        static constexpr CompareKind mirrored[] = {CompareKind::Eq, CompareKind::Ne, CompareKind::Gt,
                                                   CompareKind::Ge, CompareKind::Lt, CompareKind::Le};
        for (int side = 0; side < 2; ++side) {
            const ValueId t = c.args[size_t(side)], o = c.args[size_t(1 - side)];
            const CompareKind kk = side == 0 ? k : mirrored[int(k)];
            // (a constant may come after the instruction: `1/s if s > 0.1` computes 1/s before 0.1)
            // A value computed after the instruction has its plain range (plain_range).
            const Instr& other = f.body[o];
            const bool constant = other.op == Op::Const && other.data.size() == 1;
            if (t >= at || r[t].c.size() != 1) continue;
            const Range& bound = o < at ? r[o] : plain_range(o);
            if (!constant && bound.c.size() != 1) continue;
            const bool integer = f.body[t].type.kind == Type::Integer;
            const Interval b = constant ? Interval{other.data[0], other.data[0]} : bound.c[0];
            Interval x{-kInf, kInf};
            switch (kk) {
                // (an infinite end stays infinite: nextafter(∞) is the largest double, said as 1.798e+308)
                case CompareKind::Lt: x.hi = integer || !std::isfinite(b.hi) ? (std::isfinite(b.hi) ? std::ceil(b.hi) - 1 : b.hi) : std::nextafter(b.hi, -kInf); break;
                case CompareKind::Le: x.hi = b.hi; break;
                case CompareKind::Gt: x.lo = integer || !std::isfinite(b.lo) ? (std::isfinite(b.lo) ? std::floor(b.lo) + 1 : b.lo) : std::nextafter(b.lo, kInf); break;
                case CompareKind::Ge: x.lo = b.lo; break;
                case CompareKind::Eq: x = b; break;
                case CompareKind::Ne:
                    if (b.lo == 0 && b.hi == 0) out.push_back({t, x, true});
                    continue;
            }
            out.push_back({t, x, false});
        }
    }
    // A warning at an instruction that the result needs. In a function of the source, code a pass made (no span:
    // the stable pass's e^(x_i - max_j x_j), which is at most 1) is the pass's to keep in range: said at 1:1, a
    // trial's "exp of a value that can exceed 88.72" pointed at `shape`.
    void warn(const Instr& in, std::string msg) {
        if (quiet || unreachable || (source_spans && !in.span.valid())) return;
        const size_t i = size_t(&in - f.body.data());
        if (i < live.size() && !live[i]) return;
        issues.push_back({in.span, std::move(msg)});
    }

    Range builtin(const Instr& in) {
        const BuiltinInfo& b = iqc::builtin(in.aux);
        std::string n = b.name;
        Range x = all_unknown(in.type);
        x.known = known(in);
        size_t comps = size_t(std::max(1, in.type.components()));
        auto each = [&](auto fn) {
            for (size_t k = 0; k < comps; ++k) x.c[k] = fn(k);
        };
        if (n == "sin" || n == "cos") {
            // Exact on an interval: the ends and any extremum (multiples of π/2) inside it.
            bool is_sin = n == "sin";
            each([&](size_t k) { return iv::periodic(comp(in.args[0], k), is_sin); });
        } else if (n == "tan") {
            each([&](size_t k) {
                Interval a = comp(in.args[0], k);
                if (a.lo > -M_PI / 2 && a.hi < M_PI / 2) return Interval{std::tan(a.lo), std::tan(a.hi)};
                return unknown();
            });
        }
        else if (n == "tanh") each([&](size_t) { return Interval{-1, 1}; });
        else if (n == "smoothstep") each([&](size_t) { return Interval{0, 1}; });
        else if (n == "exp") each([&](size_t k) { return monotone(comp(in.args[0], k), [](double v) { return std::exp(v); }); });
        else if (n == "log" || n == "ln" || n == "log_2" || n == "log2" || n == "log_10" || n == "log10")
            // (a trial's, stop 54: ln β with β ∈ [1.5, 10] was [-∞, ∞], a divisor "that can be 0", and --strict-ranges
            // rejected the module)
            each([&](size_t k) {
                const double unit = n == "log_2" || n == "log2" ? 1 / std::log(2.0) : n == "log_10" || n == "log10" ? 1 / std::log(10.0) : 1;
                Interval a = comp(in.args[0], k);
                if (!(a.hi > 0)) return unknown();
                return Interval{a.lo > 0 ? unit * std::log(a.lo) : -kInf, unit * std::log(a.hi)};
            });
        else if (n == "pow")
            each([&](size_t k) {
                Interval b = comp(in.args[0], k), e = comp(in.args[1], k);
                if (!(b.lo >= 0)) return unknown();
                double c[4] = {std::pow(b.lo, e.lo), std::pow(b.lo, e.hi), std::pow(b.hi, e.lo), std::pow(b.hi, e.hi)};
                Interval r{kInf, -kInf};
                for (double v : c) {
                    if (std::isnan(v)) return unknown();
                    r.lo = std::min(r.lo, v);
                    r.hi = std::max(r.hi, v);
                }
                if (b.lo == 0 && e.lo < 0) r.hi = kInf;
                // (b^e is monotone in e for b on one side of 1 and in b for e of one sign: the corners bound it; else
                // b^e over b < 1 < b' or e < 0 < e' still lies between the corners' least and greatest and 1)
                if (b.lo < 1 && b.hi > 1) r = Interval{std::min(r.lo, 1.0), std::max(r.hi, 1.0)};
                if (e.lo < 0 && e.hi > 0) r = Interval{std::min(r.lo, 1.0), std::max(r.hi, 1.0)};
                return r;
            });
        else if (n == "abs")
            each([&](size_t k) {
                Interval a = comp(in.args[0], k);
                if (a.lo >= 0) return a;
                if (a.hi <= 0) return neg(a);
                return Interval{0, std::max(-a.lo, a.hi)};
            });
        else if (n == "sqrt") each([&](size_t k) {
            Interval a = comp(in.args[0], k);
            return Interval{std::sqrt(std::max(a.lo, 0.0)), std::sqrt(std::max(a.hi, 0.0))};
        });
        else if (n == "floor" || n == "ceil" || n == "round")
            each([&](size_t k) { Interval a = comp(in.args[0], k); return Interval{std::floor(a.lo), std::ceil(a.hi)}; });
        else if (n == "fract") each([&](size_t) { return Interval{0, 1}; });
        else if (n == "sign") each([&](size_t) { return Interval{-1, 1}; });
        else if (n == "min" || n == "max")
            each([&](size_t k) {
                Interval a = comp(in.args[0], k), c = comp(in.args[1], k);
                return n == "min" ? Interval{std::min(a.lo, c.lo), std::min(a.hi, c.hi)}
                                  : Interval{std::max(a.lo, c.lo), std::max(a.hi, c.hi)};
            });
        else if (n == "clamp")
            each([&](size_t k) {
                Interval a = comp(in.args[0], k), lo = comp(in.args[1], k), hi = comp(in.args[2], k);  // min(max(a, lo), hi)
                return Interval{std::min(std::max(a.lo, lo.lo), hi.lo), std::min(std::max(a.hi, lo.hi), hi.hi)};
            });
        else if (n == "length") {
            double lo2 = 0, hi2 = 0;
            for (size_t k = 0; k < r[in.args[0]].c.size(); ++k) {
                Interval a = comp(in.args[0], k);
                double m_lo = contains_zero(a) ? 0 : std::min(std::fabs(a.lo), std::fabs(a.hi));
                double m_hi = std::max(std::fabs(a.lo), std::fabs(a.hi));
                lo2 += m_lo * m_lo;
                hi2 += m_hi * m_hi;
            }
            x.c = {{std::sqrt(lo2), std::sqrt(hi2)}};
        } else if (n == "normalize") {
            each([&](size_t) { return Interval{-1, 1}; });
            x.unit = true;
        } else if (n == "atan" || n == "atan2") each([&](size_t) { return Interval{-M_PI, M_PI}; });
        else if (n == "asin") each([&](size_t) { return Interval{-M_PI / 2, M_PI / 2}; });
        else if (n == "acos") each([&](size_t) { return Interval{0, M_PI}; });
        return x;
    }

    // The interval of each component of a value with these bounds (an array: the hull over its elements).
    Range from_bounds(const Type& t, const ValueBounds& b, const std::vector<double>* value) {
        Range x = all_unknown(t.is_array() ? t.element() : t);
        if (b.input) return x;
        x.known = true;
        size_t n = x.c.size();
        if (!b.lo.empty() && b.lo.size() == n) {
            for (size_t k = 0; k < n; ++k) x.c[k] = {b.lo[k], b.hi[k]};
        } else if (t.is_array() && !b.lo.empty() && b.lo.size() % n == 0 && b.hi.size() == b.lo.size()) {  // every element's
            for (size_t k = 0; k < n; ++k) x.c[k] = {kInf, -kInf};
            for (size_t j = 0; j < b.lo.size(); ++j) x.c[j % n] = hull(x.c[j % n], {b.lo[j], b.hi[j]});
        } else if (value && !value->empty()) {
            for (size_t k = 0; k < n; ++k) x.c[k] = {kInf, -kInf};
            for (size_t j = 0; j < value->size(); ++j) x.c[j % n] = hull(x.c[j % n], {(*value)[j], (*value)[j]});
        }
        return x;
    }

    // A rolled ∑ (ir/Lower.cpp: a Loop of one state s ← s + t, t not reading s, a constant count n): s(0) + n·t,
    // t's range from the body analysed with the index over its range and the captures' ranges. As the unrolled
    // sum's, so a sum over 32 elements warns where one over 31 did (a trial: 1/∑_i w_i warned at 31, not at 32).
    std::optional<Range> accumulated(const Instr& loop) {
        const Function& body = m.functions[size_t(loop.aux)];
        if (body.outputs.size() != 1 || loop.args.size() < 2 || loop.data.empty()) return std::nullopt;
        const Instr& hi = f.body[loop.args[0]];
        if (hi.op != Op::Const || hi.data.size() != 1) return std::nullopt;
        const auto term_value = accumulated_term(body, 0);
        if (!term_value) return std::nullopt;
        const ValueId t = *term_value;
        const double first = loop.data[0], last = std::floor(hi.data[0] + 0.5);
        if (!(last >= first)) return std::nullopt;
        std::vector<Range> args;
        Range k;
        k.known = true;
        k.c = {{first, last}};
        args.push_back(k);
        for (size_t a = 1; a < loop.args.size(); ++a) args.push_back(r[loop.args[a]]);
        Analyzer sub{m, body, {}, {}};
        sub.params = &args;
        sub.depth = depth + 1;
        sub.work = work;
        sub.r.resize(body.body.size());
        sub.underflows.assign(body.body.size(), 0);
        for (size_t b = 0; b <= t; ++b) sub.r[b] = sub.eval(b);
        const Range& init = r[loop.args[1]];
        const Range& term = sub.r[t];
        if (init.c.size() != term.c.size()) return std::nullopt;
        Range x;
        x.known = init.known && term.known;
        const double n = last - first + 1;
        for (size_t q = 0; q < term.c.size(); ++q) x.c.push_back(add(init.c[q], mul(term.c[q], Interval{n, n})));
        return x;
    }

    // Every instruction's range, in order, with the warnings (the loop bodies' too, with their captures' ranges:
    // eval's Op::Loop) and, where `needs` is given, the guard each needs (kClampUnit…).
    void scan(std::vector<int>* needs_out) {
        r.assign(f.body.size(), {});
        underflows.assign(f.body.size(), 0);
        live.assign(f.body.size(), 0);
        source_spans = std::any_of(f.body.begin(), f.body.end(), [](const Instr& in) { return in.span.valid(); });
        if (!f.body.empty()) {
            live[f.result] = 1;
            for (const auto& [name, v] : f.outputs) live[v] = 1;
            for (size_t i = f.body.size(); i-- > 0;)
                if (live[i])
                    for (ValueId a : f.body[i].args) live[a] = 1;
        }
        std::vector<int> needs(f.body.size(), 0);
        std::vector<bool> beyond(f.body.size(), false);  // a value past the largest float wherever it is
        if (narrowing) find_guards();
        else guarded.assign(f.body.size(), {});
        std::vector<Fact> narrowed;
        std::vector<std::pair<ValueId, Range>> saved;
        for (size_t i = 0; i < f.body.size(); ++i) {
            const Instr& in = f.body[i];
            // Under its conditions: their operands' ranges narrowed for this instruction (restored after it).
            unreachable = false;
            narrowed.clear();
            saved.clear();
            for (const auto& [cond, truth] : guarded[i]) facts(cond, truth, i, narrowed);
            for (const auto& [v, x, nonzero] : narrowed) {
                const Interval now = r[v].c[0], both{std::max(now.lo, x.lo), std::min(now.hi, x.hi)};
                if (!(both.lo <= both.hi) || (nonzero && now.lo == 0 && now.hi == 0)) {
                    unreachable = true;  // (never computed where the parameters are within their bounds)
                    continue;
                }
                saved.push_back({v, r[v]});
                r[v].c[0] = both;
                r[v].nonzero = r[v].nonzero || nonzero;
            }
            scan_one(i, in, needs, beyond);
            for (size_t k = saved.size(); k-- > 0;) r[saved[k].first] = std::move(saved[k].second);
        }
        unreachable = false;
        if (needs_out) *needs_out = std::move(needs);
    }

    // Range::rounded and Range::tol of instruction i (a running bound of float's rounding: Higham, "Accuracy and
    // Stability of Numerical Algorithms", ch. 3 — each rounding relative, each difference adding its operands').
    void rounding(size_t i, Range& x) {
        const Instr& in = f.body[i];
        double tol = 0;
        bool rounded = false;
        for (ValueId a : in.args) {
            tol = std::max(tol, r[a].tol);
            rounded = rounded || r[a].rounded;
        }
        auto mag = [&](size_t k) { return magnitude_finite(r[in.args[k]]); };
        switch (in.op) {
            case Op::Const:  // a fold's rounding in double: 0.3 − 0.1 folds to 0.19999999999999998 (not so 1, ½: a float's)
                x.tol = 0;
                for (double v : in.data)
                    if (std::isfinite(v) && std::fabs(v) <= limits::kFloatMax && double(float(v)) != v)
                        x.tol = std::max(x.tol, std::fabs(v) * 0x1p-50);
                x.rounded = false;
                return;
            case Op::Param:
            case Op::Global:
            case Op::Input:
                x.tol = 0;
                x.rounded = false;
                return;
            case Op::Copy:
            case Op::Neg:
            case Op::Select:
            case Op::If:
            case Op::Switch:
            case Op::Index:
            case Op::Element:
            case Op::At:
            case Op::Extract:
            case Op::Construct:
            case Op::Row:
            case Op::Column:
            case Op::Transpose:
            case Op::Compare:
            case Op::And:
            case Op::Or:
                break;  // no rounding of their own
            case Op::Add:
            case Op::Sub:
                // A sum of rounded operands is off by their roundings, whatever its own size.
                tol = r[in.args[0]].tol + r[in.args[1]].tol + (rounded ? kFloatSlack * (mag(0) + mag(1)) : 0);
                rounded = true;
                break;
            case Op::Mul:
            case Op::Hadamard:
                tol = r[in.args[0]].tol * mag(1) + r[in.args[1]].tol * mag(0);
                rounded = true;
                break;
            case Op::Div: {
                const Interval d = comp(in.args[1], 0);
                const double least = contains_zero(d) ? 0 : std::min(std::fabs(d.lo), std::fabs(d.hi));
                tol = r[in.args[0]].tol == 0 ? 0 : least > 0 ? r[in.args[0]].tol / least : kInf;
                rounded = true;
                break;
            }
            case Op::Builtin: {
                std::string_view n = iqc::builtin(in.aux).name;
                if (n == "max" || n == "clamp") {
                    // At least each operand's (clamp: its lower limit's) float value, exactly: max(0, R̂⋅V̂) is never
                    // below 0, whatever the dot product's rounding.
                    double floor_ = -kInf, lo = kInf;
                    for (size_t k = n == "clamp" ? 1 : 0; k < (n == "clamp" ? size_t(2) : in.args.size()); ++k)
                        for (const auto& c : r[in.args[k]].c) floor_ = std::max(floor_, c.lo - r[in.args[k]].tol);
                    for (const auto& c : x.c) lo = std::min(lo, c.lo);
                    if (std::isfinite(lo) && std::isfinite(floor_)) tol = std::min(tol, std::max(0.0, lo - floor_));
                    break;
                }
                if (n == "abs" || n == "min" || n == "sign") break;
                rounded = true;
                // A smooth function of a value with an error: the error times a slope (bounded roughly by the
                // result's size); none where the arguments are exact.
                if (tol > 0) tol = tol + kFloatSlack * magnitude_finite(x);
                break;
            }
            default:
                rounded = true;
                if (tol > 0) tol = tol + kFloatSlack * magnitude_finite(x);
                break;
        }
        // A value whose float sign is exact (|x|, x·x, v⋅v, ‖v‖, e^x, √x) is never below 0, nor below its lower end by
        // more than that end.
        bool nonnegative = in.op == Op::Builtin && (std::string_view(iqc::builtin(in.aux).name) == "abs" ||
                                                    std::string_view(iqc::builtin(in.aux).name) == "length" ||
                                                    std::string_view(iqc::builtin(in.aux).name) == "exp" ||
                                                    std::string_view(iqc::builtin(in.aux).name) == "sqrt");
        nonnegative = nonnegative || ((in.op == Op::Mul || in.op == Op::Dot) && in.args.size() == 2 && in.args[0] == in.args[1] &&
                                      !in.type.is_matrix());
        if (nonnegative)
            for (const auto& c : x.c) tol = std::min(tol, std::max(0.0, c.lo));
        x.tol = std::isfinite(tol) ? tol : kInf;
        x.rounded = rounded;
    }

    // One instruction of scan: its guard, range and warnings.
    void scan_one(size_t i, const Instr& in, std::vector<int>& needs, std::vector<bool>& beyond) {
        {
            if (in.op == Op::Builtin) {
                std::string n = iqc::builtin(in.aux).name;
                auto arg = [&](size_t k) { return r[in.args[k]]; };
                auto any = [&](const Range& x, auto pred) {
                    for (const auto& c : x.c)
                        if (pred(c)) return true;
                    return false;
                };
                Range x = arg(0);
                // Guards where the shader's float value may leave the domain (x.tol: its rounding), warnings where
                // the real value does (beyond the rounding: √(s s − 0.49) if s ≥ 0.7 is −5.6e-17 at worst).
                const double tol = x.tol;
                if (n == "acos" || n == "asin") {
                    if (any(x, [&](Interval c) { return c.lo < -1 + tol || c.hi > 1 - tol; })) {
                        needs[i] = kClampUnit;
                        if (x.known && any(x, [&](Interval c) { return c.lo < -1 - tol || c.hi > 1 + tol; }))
                            warn(in, fmt::format("{} of a value outside [-1, 1]: with the parameters' bounds {}", n,
                                                   ranges_over(x.c[0])));
                    }
                } else if (n == "sqrt") {
                    if (any(x, [&](Interval c) { return c.lo < tol; })) {
                        needs[i] = kNonNegative;
                        if (x.known && any(x, [&](Interval c) { return c.lo < -tol; }))
                            warn(in, fmt::format("square root of a value that can be negative: {}", ranges_over(x.c[0])));
                    }
                } else if (n == "log" || n == "ln") {
                    if (x.known && any(x, [&](Interval c) { return c.lo <= 0; }))
                        warn(in, fmt::format("logarithm of a value that can be 0 or negative: {}", ranges_over(x.c[0])));
                } else if (n == "pow") {
                    // 0 to a negative power is ∞ (and the guard makes a negative base 0): s^(-0.5) with s ∈ [0, 1] drew
                    // nothing at s = 0, unwarned, where 1/√s was warned of (a trial's, stop 52). One warning of the two.
                    const Range y = arg(1);
                    const bool negative_power = x.known && y.known && any(x, [&](Interval c) { return c.lo <= 0; }) &&
                                                any(y, [](Interval c) { return c.lo < 0; });
                    if (any(x, [&](Interval c) { return c.lo < tol; })) {
                        needs[i] = kPowBase;
                        if (x.known && !negative_power && any(x, [&](Interval c) { return c.lo < -tol; }))
                            warn(in, fmt::format("a power of a base that can be negative: {}", ranges_over(x.c[0])));
                    }
                    if (negative_power)
                        warn(in, fmt::format("a power with {} of a base that can be 0 or below (∞ there: a negative base is taken "
                                             "as 0): the base {}",
                                             y.c[0].lo == y.c[0].hi ? fmt::format("the negative exponent {:.4g}", y.c[0].lo)
                                                                    : "an exponent that can be negative, " + fmt_interval(y.c[0]),
                                             ranges_over(x.c[0]).substr(3)));
                } else if (n == "normalize") {
                    bool zero = true;
                    for (const auto& c : x.c) zero &= contains_zero(c);
                    if (zero) needs[i] = kNormalize;  // 0 / 0: the zero vector instead of NaN
                    if (x.known && zero) warn(in, "normalize of a vector that can be zero");
                } else if (n == "exp") {
                    // e^x is ∞ in a 32-bit float past x = ln(3.4e38) ≈ 88.72 (iqc eval, in double, still has a number).
                    if (x.known && any(x, [](Interval c) { return c.hi > kExpOverflow; }))
                        warn(in, fmt::format("exp of a value that can exceed {:.4g}: a shader's 32-bit float overflows to ∞ "
                                               "there; {}", kExpOverflow, ranges_over(x.c[0])));
                } else if (n == "acosh") {
                    // acosh is defined from 1 on, atanh strictly inside (-1, 1): NaN or ±∞ elsewhere, in a shader too.
                    if (x.known && any(x, [](Interval c) { return c.lo < 1; }))
                        warn(in, fmt::format("acosh of a value that can be below 1 (NaN there): {}", ranges_over(x.c[0])));
                } else if (n == "atanh") {
                    if (x.known && any(x, [](Interval c) { return c.lo <= -1 || c.hi >= 1; }))
                        warn(in, fmt::format("atanh of a value that can reach ±1 or beyond (±∞ or NaN there): {}",
                                               ranges_over(x.c[0])));
                } else if (n == "mod") {
                    Range y = arg(1);
                    if (y.known && !y.nonzero && any(y, [](Interval c) { return contains_zero(c); }))
                        warn(in, fmt::format("mod by a value that can be 0: {}", ranges_over(y.c[0])));
                } else if (n == "atan2") {
                    Range y = arg(0), xx = arg(1);
                    if (any(y, [](Interval c) { return contains_zero(c); }) && any(xx, [](Interval c) { return contains_zero(c); }))
                        needs[i] = kAtan2;
                }
            }
            // v / ‖v‖ where v can be 0: the zero vector instead of NaN (the same guard as normalize).
            if (in.op == Op::Div && in.type.is_vector()) {
                const Instr& den = f.body[in.args[1]];
                if (den.op == Op::Builtin && std::string(iqc::builtin(den.aux).name) == "length" && den.args[0] == in.args[0] &&
                    contains_zero(r[in.args[1]].c[0]))
                    needs[i] = kDivLength;
            }
            r[i] = eval(i);
            rounding(i, r[i]);
            // In 32-bit floats a nonzero value below the smallest normal (1.2e-38) may be 0 (GPUs flush denormals):
            // e^-100, 1e-20·1e-20. Its range takes 0 in, so a division by it is a division by a value that can be 0.
            if (in.type.kind != Type::Integer && in.op != Op::Compare)
                for (auto& c : r[i].c) {
                    if (c.lo > 0 && c.lo < limits::kFloatMinNormal) c.lo = 0, underflows[i] = 1;
                    if (c.hi < 0 && c.hi > -limits::kFloatMinNormal) c.hi = 0, underflows[i] = 1;
                }
            // A value of constants and parameters that is beyond the largest float wherever it is (10^40): the
            // shader computes ∞ where iqc eval, in double, prints a number.
            // Said once, where it starts (a folded constant keeps the span of what it was folded from).
            if (r[i].known && in.type.kind != Type::Integer && !r[i].c.empty()) {
                for (const auto& c : r[i].c)
                    beyond[i] = beyond[i] || (std::min(std::fabs(c.lo), std::fabs(c.hi)) > kFloatMax && c.lo * c.hi > 0 &&
                                              std::isfinite(c.lo) && std::isfinite(c.hi));
                bool inherited = false;
                for (ValueId arg : in.args) inherited |= beyond[arg];
                if (beyond[i] && !inherited && in.span.valid())
                    warn(in, fmt::format("this value is beyond the largest 32-bit float (3.4e38): a shader computes ∞; {}",
                                           ranges_over(r[i].c[0])));
                // Nonzero but below the smallest normal float wherever it is (a product of 1e-20 and 1e-20): a shader
                // may compute 0. Said where it starts.
                bool tiny = underflows[i] != 0;
                for (const auto& c : r[i].c) tiny = tiny && std::max(std::fabs(c.lo), std::fabs(c.hi)) < limits::kFloatMinNormal;
                bool tiny_inherited = false;
                for (ValueId arg : in.args) tiny_inherited |= underflows[arg] && r[arg].known;
                if (tiny && !tiny_inherited && in.span.valid())
                    warn(in, fmt::format("this value is below the smallest normal 32-bit float ({:.2g}): a shader may compute 0; {}",
                                           limits::kFloatMinNormal, ranges_over(r[i].c[0])));
            }
            // A guarded operation's result is in range.
            if (needs[i] == kNonNegative)
                for (auto& c : r[i].c) c.lo = std::max(c.lo, 0.0);
        }
    }

    // The warnings of a loop's body (a rolled ∑, ir/Lower.cpp), analysed with the index over its range and the
    // captures' ranges: the body alone knows nothing of its parameters, so `w_i / ∑_j w_j` over 40 elements,
    // whose divisor the loop captures, went unwarned where 3 elements (unrolled) warned. The states change from
    // trip to trip: nothing is assumed of them.
    void loop_warnings(const Instr& loop) {
        const Function& body = m.functions[size_t(loop.aux)];
        const size_t states = body.outputs.size();
        std::vector<Range> args;
        Range k = all_unknown(Type::integer());
        const Instr& hi = f.body[loop.args[0]];
        if (!loop.data.empty() && hi.op == Op::Const && hi.data.size() == 1 && hi.data[0] >= loop.data[0]) {
            k.known = true;
            k.c = {{loop.data[0], std::floor(hi.data[0] + 0.5)}};
        }
        args.push_back(k);
        for (size_t a = 1; a < loop.args.size(); ++a)
            args.push_back(a <= states ? all_unknown(f.body[loop.args[a]].type) : r[loop.args[a]]);
        Analyzer sub{m, body, {}, {}};
        sub.params = &args;
        sub.depth = depth + 1;
        sub.work = work;
        sub.quiet = quiet;
        sub.scan(nullptr);
        if (!unreachable)
            for (auto& issue : sub.issues) issues.push_back(std::move(issue));
    }

    // A call's result with its arguments' ranges, and the callee's warnings there (Analyzer::depth). A warning in
    // another file than the call (the standard library's code) is said at the call, naming the function.
    Range call(size_t i) {
        const Instr& in = f.body[i];
        const Function& callee = m.functions[size_t(in.aux)];
        if (!callee.param_bounds.empty() || callee.body.empty() || depth >= 8 || !work || *work < long(callee.body.size()))
            return all_unknown(in.type);
        *work -= long(callee.body.size());
        std::vector<Range> args;
        for (ValueId a : in.args) args.push_back(r[a]);
        Analyzer sub{m, callee, {}, {}};
        sub.params = &args;
        sub.depth = depth + 1;
        sub.work = work;
        sub.quiet = quiet;
        sub.scan(nullptr);
        const bool said = !quiet && !unreachable && !(source_spans && !in.span.valid()) && (i >= live.size() || live[i]);
        for (auto& issue : sub.issues) {
            if (!said) break;
            if (in.span.valid() && issue.span.file != in.span.file) {
                issue.message = fmt::format("in '{}': {}", callee.name, issue.message);
                issue.span = in.span;
            }
            issues.push_back(std::move(issue));
        }
        Range x = sub.r[callee.result];
        if (x.c.size() != size_t(std::max(1, in.type.components()))) return all_unknown(in.type);
        return x;
    }

    Range eval(size_t i) {
        const Instr& in = f.body[i];
        Range x = all_unknown(in.type);
        x.known = known(in);
        size_t comps = size_t(std::max(1, in.type.components()));
        switch (in.op) {
            case Op::Const:
                x.known = true;
                x.c.clear();
                for (double v : in.data) x.c.push_back({v, v});
                if (x.c.empty()) x.c.push_back({0, 0});
                return x;
            case Op::Param:
                if (params) return size_t(in.aux) < params->size() ? (*params)[size_t(in.aux)] : all_unknown(in.type);
                if (size_t(in.aux) >= f.param_bounds.size()) return all_unknown(in.type);  // the renderer's input
                return from_bounds(in.type, f.param_bounds[size_t(in.aux)], nullptr);
            case Op::Global: {
                const Global& g = m.globals[size_t(in.aux)];
                if (g.kind == Global::Kind::Prepared) return all_unknown(in.type);
                ValueBounds b = g.bounds;
                b.input = false;
                return from_bounds(in.type, b, g.kind == Global::Kind::Constant ? &g.value : nullptr);
            }
            case Op::Index: return r[in.args[0]];  // the array's range is the hull of its elements
            case Op::Element:  // (w_i's bounds hold for each element: ∑_j w_j over w_i ∈ [0.1, 1] was unknown)
                return r[in.args[0]].c.size() == comps ? r[in.args[0]] : x;
            case Op::At:
                if (f.body[in.args[0]].type.is_array() && r[in.args[0]].c.size() == comps) return r[in.args[0]];
                return x;
            case Op::If:
                for (size_t k = 0; k < comps; ++k) x.c[k] = hull(comp(in.args[1], k), comp(in.args[2], k));
                x.known = r[in.args[1]].known && r[in.args[2]].known;
                return x;
            case Op::Switch:
                for (size_t k = 0; k < comps; ++k) {
                    x.c[k] = comp(in.args[1], k);
                    for (size_t a = 2; a < in.args.size(); ++a) x.c[k] = hull(x.c[k], comp(in.args[a], k));
                }
                x.known = false;
                return x;
            case Op::Copy: return r[in.args[0]];
            case Op::Member:
                if (in.aux == 0 && f.body[in.args[0]].op == Op::Loop)
                    if (auto s = accumulated(f.body[in.args[0]])) return *s;
                return all_unknown(in.type);
            case Op::Loop:
                if (i >= live.size() || live[i]) loop_warnings(in);  // (a loop the stable pass replaced: not)
                return all_unknown(in.type);
            case Op::Input:
                return all_unknown(in.type);
            case Op::Call:
                return call(i);
            case Op::Add:
            case Op::Sub:
                for (size_t k = 0; k < comps; ++k)
                    x.c[k] = in.op == Op::Add ? add(comp(in.args[0], k), comp(in.args[1], k))
                                              : add(comp(in.args[0], k), neg(comp(in.args[1], k)));
                return x;
            case Op::Neg:
                for (size_t k = 0; k < comps; ++k) x.c[k] = neg(comp(in.args[0], k));
                x.unit = r[in.args[0]].unit;
                return x;
            case Op::Mul:
            case Op::Hadamard: {
                const Type &a = f.body[in.args[0]].type, &b = f.body[in.args[1]].type;
                if (in.args[0] == in.args[1] && !in.type.is_matrix()) {  // a square is never negative
                    for (size_t k = 0; k < comps; ++k) {
                        Interval v = comp(in.args[0], k);
                        double lo = contains_zero(v) ? 0 : std::min(v.lo * v.lo, v.hi * v.hi);
                        x.c[k] = {lo, std::max(v.lo * v.lo, v.hi * v.hi)};
                    }
                    return x;
                }
                if ((a.is_scalar() || b.is_scalar() || in.op == Op::Hadamard) && !in.type.is_matrix())
                    for (size_t k = 0; k < comps; ++k) x.c[k] = mul(comp(in.args[0], k), comp(in.args[1], k));
                return x;
            }
            case Op::Div: {
                Interval d = comp(in.args[1], 0);
                if (contains_zero(d)) {  // (exact: 1/(s − 0.1) if s > 0.1 divides by [1.4e-17, 0.9], not by 0)
                    if (r[in.args[1]].known && !r[in.args[1]].nonzero)
                        warn(in, fmt::format("division by a value that can be 0{}: with the parameters' bounds {}",
                                             underflows[in.args[1]] ? fmt::format(" (it can fall below the smallest normal 32-bit "
                                                                                  "float, {:.2g}, which a shader may flush to 0)",
                                                                                  limits::kFloatMinNormal)
                                                                    : "",
                                             ranges_over(d)));
                    return all_unknown(in.type);
                }
                Interval inv = {1 / d.hi, 1 / d.lo};
                for (size_t k = 0; k < comps; ++k) x.c[k] = mul(comp(in.args[0], k), inv);
                // v / ‖v‖ is a unit vector.
                const Instr& den = f.body[in.args[1]];
                if (in.type.is_vector() && den.op == Op::Builtin && std::string(iqc::builtin(den.aux).name) == "length" &&
                    den.args[0] == in.args[0])
                    x.unit = true;
                return x;
            }
            case Op::Dot: {
                if (r[in.args[0]].unit && r[in.args[1]].unit) {
                    x.c = {{-1, 1}};
                    return x;
                }
                if (in.args[0] == in.args[1]) {  // v⋅v = ‖v‖² ≥ 0
                    double lo = 0, hi = 0;
                    for (size_t k = 0; k < r[in.args[0]].c.size(); ++k) {
                        Interval v = comp(in.args[0], k);
                        lo += contains_zero(v) ? 0 : std::min(v.lo * v.lo, v.hi * v.hi);
                        hi += std::max(v.lo * v.lo, v.hi * v.hi);
                    }
                    x.c = {{lo, hi}};
                    return x;
                }
                Interval s{0, 0};
                for (size_t k = 0; k < r[in.args[0]].c.size(); ++k) s = add(s, mul(comp(in.args[0], k), comp(in.args[1], k)));
                x.c = {s};
                return x;
            }
            case Op::Construct: {
                x.c.clear();
                for (ValueId a : in.args)
                    for (const auto& c : r[a].c) x.c.push_back(c);
                if (x.c.size() != comps) x.c.assign(comps, unknown());
                return x;
            }
            case Op::Extract:
                x.c = {comp(in.args[0], size_t(in.aux))};
                return x;
            case Op::Select:
                for (size_t k = 0; k < comps; ++k) x.c[k] = hull(comp(in.args[1], k), comp(in.args[2], k));
                x.unit = r[in.args[1]].unit && r[in.args[2]].unit;
                return x;
            case Op::Builtin: return builtin(in);
            default: return x;
        }
    }
};

}  // namespace

std::vector<RangeIssue> analyze_ranges(Module& m, int fn, bool guard) {
    Function& f = m.functions[size_t(fn)];
    Analyzer a{m, f, {}, {}};
    long work = 200000;  // instructions of callees analysed at their calls (Analyzer::call)
    a.work = &work;
    std::vector<int> needs;  // per instruction: 0 none, else the guard kind
    a.scan(&needs);
    if (!guard) return a.issues;
    // Rewrite with guards.
    Function g = f;
    g.body.clear();
    std::vector<ValueId> map(f.body.size());
    auto emit = [&](Instr in) { return g.add(std::move(in)); };
    auto konst = [&](const Type& t, double v) {
        Instr c;
        c.op = Op::Const;
        c.type = t.is_scalar() ? Type::scalar() : t;
        c.data.assign(size_t(std::max(1, t.components())), v);
        return emit(std::move(c));
    };
    auto call = [&](const char* name, std::vector<ValueId> args, const Type& t, Span span) {
        Instr b;
        b.op = Op::Builtin;
        b.aux = *find_builtin(name);
        b.type = t;
        b.args = std::move(args);
        b.span = span;
        return emit(std::move(b));
    };
    for (size_t i = 0; i < f.body.size(); ++i) {
        Instr in = f.body[i];
        for (ValueId& x : in.args) x = map[x];
        const Type at = in.args.empty() ? in.type : g.body[in.args[0]].type;  // a copy: g.body grows below
        switch (needs[i]) {
            case kClampUnit: in.args[0] = call("clamp", {in.args[0], konst(at, -1), konst(at, 1)}, at, in.span); break;
            case kNonNegative:
            case kPowBase: in.args[0] = call("max", {in.args[0], konst(at, 0)}, at, in.span); break;
            case kDivLength: in.args[1] = call("max", {in.args[1], konst(Type::scalar(), 1e-30)}, Type::scalar(), in.span); break;
            case kNormalize: {
                // normalize(v) -> v / max(‖v‖, 1e-30)
                ValueId len = call("length", {in.args[0]}, Type::scalar(), in.span);
                ValueId safe = call("max", {len, konst(Type::scalar(), 1e-30)}, Type::scalar(), in.span);
                in.op = Op::Div;
                in.aux = 0;
                in.args = {in.args[0], safe};
                break;
            }
            case kAtan2: {
                // atan2(0, 0) = 0: select(y = 0 and x = 0, 0, atan2(y, x)) (scalars)
                if (!in.type.is_scalar()) break;
                ValueId y = in.args[0], x = in.args[1], zero = konst(Type::scalar(), 0);
                Instr cy{Op::Compare, Type::boolean(), {y, zero}, {}, int(CompareKind::Eq), "", "", in.span};
                Instr cx{Op::Compare, Type::boolean(), {x, zero}, {}, int(CompareKind::Eq), "", "", in.span};
                ValueId a1 = emit(cy), a2 = emit(cx);
                Instr both{Op::And, Type::boolean(), {a1, a2}, {}, 0, "", "", in.span};
                ValueId both_v = emit(both);
                std::string name = in.name, source = in.source;
                in.name.clear();
                in.source.clear();
                ValueId at2 = emit(in);
                Instr sel{Op::Select, Type::scalar(), {both_v, zero, at2}, {}, 0, name, source, in.span};
                map[i] = emit(sel);
                continue;
            }
            default: break;
        }
        map[i] = emit(std::move(in));
    }
    g.result = map[f.result];
    for (auto& [n, v] : g.outputs) v = map[v];
    f = std::move(g);
    return a.issues;
}

std::vector<RangeIssue> analyze_ranges(Module& m, bool guard) {
    std::vector<RangeIssue> all;
    for (size_t fi = 0; fi < m.functions.size(); ++fi)
        for (auto& issue : analyze_ranges(m, int(fi), guard)) {
            // One warning of a kind at a place: an unrolled sum's copies of one operation each warned, with ranges
            // that differ (a trial's ∑_i ∑_j 1/(w_i - w_j) said it twice at one caret).
            auto kind = [](const std::string& s) { return s.substr(0, s.find(':')); };
            bool seen = false;
            for (const auto& o : all) seen |= o.span.file == issue.span.file && o.span.begin == issue.span.begin &&
                                               o.span.end == issue.span.end && kind(o.message) == kind(issue.message);
            if (!seen) all.push_back(std::move(issue));
        }
    std::stable_sort(all.begin(), all.end(), [](const RangeIssue& a, const RangeIssue& b) {
        return a.span.file != b.span.file ? a.span.file < b.span.file : a.span.begin < b.span.begin;
    });
    return all;
}

}  // namespace iqc::ir
