#include "ir/passes/IntervalExtension.h"

#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <string_view>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

constexpr double kBig = 1e30;  // "unbounded" in 32-bit floats without ∞ - ∞ = NaN

// One value of the source function, as the extension knows it: exact (the same value, re-emitted), or an
// interval per scalar component (booleans: lo "certainly true", hi "possibly true"), or unknown.
struct IV {
    bool exact = false;
    ValueId whole = 0;              // exact: the value in the new function
    std::vector<ValueId> lo, hi;    // not exact: per component (row-major), scalar ℝ (or boolean) values
    std::string bad;                // not empty: unknown, and why
};

class Extender {
public:
    Extender(Builder& b, const Module& m) : b_(b), m_(m) {}

    std::vector<ValueId> continuity;  // conditions that hold where the function cannot jump in the box

    IV run(int fn, const std::vector<IV>& params) {
        const Function& f = m_.functions[size_t(fn)];
        std::vector<IV> v(f.body.size());
        for (size_t i = 0; i < f.body.size(); ++i) v[i] = instr(f, f.body[i], v, params);
        return v[f.result];
    }

    // The components of x, as scalar values of the new function.
    ValueId comp(const IV& x, const Type& t, size_t k, bool high) {
        if (!x.exact) return (high ? x.hi : x.lo)[x.lo.size() == 1 ? 0 : k];
        if (t.is_scalar() || t.kind == Type::Bool) return x.whole;
        const Instr& w = b_.function().body[x.whole];
        if (w.op == Op::Const && k < w.data.size()) return num(w.data[k]);
        return b_.op(Op::Extract, {x.whole}, int(k));
    }

private:
    Builder& b_;
    const Module& m_;

    ValueId num(double x) { return b_.scalar(x); }
    // The value of a scalar constant of the new function, if v is one.
    std::optional<double> constant(ValueId v) const {
        const Instr& in = b_.function().body[v];
        if (in.op == Op::Const && in.data.size() == 1) return in.data[0];
        return std::nullopt;
    }
    ValueId add(ValueId a, ValueId c) {
        if (auto x = constant(a); x && *x == 0) return c;
        if (auto x = constant(c); x && *x == 0) return a;
        return b_.op(Op::Add, {a, c});
    }
    ValueId sub(ValueId a, ValueId c) { return b_.op(Op::Sub, {a, c}); }
    ValueId mul(ValueId a, ValueId c) { return b_.op(Op::Mul, {a, c}); }
    ValueId neg(ValueId a) { return b_.op(Op::Neg, {a}); }
    ValueId fmin(ValueId a, ValueId c) { return b_.builtin("min", {a, c}); }
    ValueId fmax(ValueId a, ValueId c) { return b_.builtin("max", {a, c}); }
    ValueId call1(const char* n, ValueId a) { return b_.builtin(n, {a}); }
    ValueId sel(ValueId c, ValueId a, ValueId e) { return b_.op(Op::Select, {c, a, e}); }
    ValueId cmp(CompareKind k, ValueId a, ValueId c) { return b_.compare(k, a, c); }
    ValueId both(ValueId a, ValueId c) { return b_.op(Op::And, {a, c}); }
    ValueId either(ValueId a, ValueId c) { return b_.op(Op::Or, {a, c}); }

    static IV unknown(std::string why) {
        IV x;
        x.bad = std::move(why);
        return x;
    }
    static IV pair(ValueId lo, ValueId hi) {
        IV x;
        x.lo = {lo};
        x.hi = {hi};
        return x;
    }
    // Scalar interval products: the extremes of the four end products (Moore).
    std::pair<ValueId, ValueId> product(ValueId al, ValueId ah, bool a_exact, ValueId bl, ValueId bh, bool b_exact) {
        if (a_exact && b_exact) {
            ValueId p = mul(al, bl);
            return {p, p};
        }
        if (a_exact || b_exact) {  // s·[l, h]: the ends, in the order s's sign gives
            ValueId s = a_exact ? al : bl;
            ValueId l = a_exact ? bl : al, h = a_exact ? bh : ah;
            if (auto c = constant(s)) {  // a constant's sign is known here (Jacobians are full of 0 and 1)
                if (*c == 0) return {num(0), num(0)};
                if (*c == 1) return {l, h};
                return *c > 0 ? std::pair{mul(s, l), mul(s, h)} : std::pair{mul(s, h), mul(s, l)};
            }
            ValueId p = mul(s, l), q = mul(s, h);
            return {fmin(p, q), fmax(p, q)};
        }
        ValueId p1 = mul(al, bl), p2 = mul(al, bh), p3 = mul(ah, bl), p4 = mul(ah, bh);
        return {fmin(fmin(p1, p2), fmin(p3, p4)), fmax(fmax(p1, p2), fmax(p3, p4))};
    }
    // x² of [l, h]: never negative.
    std::pair<ValueId, ValueId> square(ValueId l, ValueId h) {
        ValueId l2 = mul(l, l), h2 = mul(h, h);
        ValueId lo = sel(cmp(CompareKind::Ge, l, num(0)), l2, sel(cmp(CompareKind::Le, h, num(0)), h2, num(0)));
        return {lo, fmax(l2, h2)};
    }
    // The argument of a function with jumps, widened by 10⁻⁵ of its magnitude (and 10⁻⁶): in 32-bit floats a
    // point's own evaluation may land across a jump that the interval's ends do not reach (a hash such as
    // fract(43758.5 sin x) amplifies sin's rounding a hundredfold), and a step there changes the value by a
    // whole step. A new user's trial found a segment called clear across such a jump.
    std::pair<ValueId, ValueId> widened(ValueId l, ValueId h) {
        ValueId w = add(mul(add(call1("abs", l), call1("abs", h)), num(1e-5)), num(1e-6));
        return {sub(l, w), add(h, w)};
    }
    // 1/[l, h], unbounded where the interval holds 0.
    std::pair<ValueId, ValueId> reciprocal(ValueId l, ValueId h) {
        ValueId apart = either(cmp(CompareKind::Gt, l, num(0)), cmp(CompareKind::Lt, h, num(0)));
        ValueId rl = b_.op(Op::Div, {num(1), h}), rh = b_.op(Op::Div, {num(1), l});
        return {sel(apart, rl, num(-kBig)), sel(apart, rh, num(kBig))};
    }

    // v/‖v‖ per component, tight: v_k/√(v_k² + R²), R² the other components' squares, increases with v_k and
    // its magnitude falls as R grows, so each end comes from one end of v_k and one end of R. A product of v's
    // intervals with 1/‖v‖'s forgets that the result is a unit vector: near a face of a box SDF (‖v‖ small)
    // it bounded the components of the gradient by 10 and more, and segment tracing took sphere-tracing steps.
    // (0/0 is 0, as the point code's max(‖v‖, 1e-30) makes it.)
    IV unit_vector(const IV& v, const Type& t) {
        size_t n = size_t(std::max(1, t.components()));
        std::vector<std::pair<ValueId, ValueId>> sq;
        for (size_t k = 0; k < n; ++k) sq.push_back(square(comp(v, t, k, false), comp(v, t, k, true)));
        return each(t, [&](size_t k) {
            ValueId r_lo = num(0), r_hi = num(0);
            for (size_t j = 0; j < n; ++j)
                if (j != k) {
                    r_lo = add(r_lo, sq[j].first);
                    r_hi = add(r_hi, sq[j].second);
                }
            ValueId l = comp(v, t, k, false), h = comp(v, t, k, true);
            auto end = [&](ValueId x, ValueId r2) { return b_.op(Op::Div, {x, fmax(call1("sqrt", add(mul(x, x), r2)), num(1e-30))}); };
            ValueId top = end(h, sel(cmp(CompareKind::Ge, h, num(0)), r_lo, r_hi));
            ValueId bottom = end(l, sel(cmp(CompareKind::Ge, l, num(0)), r_hi, r_lo));
            return std::pair{fmax(bottom, num(-1)), fmin(top, num(1))};
        });
    }

    // Whether divisor (in f) is ‖v‖ or max(‖v‖, c): v / divisor is then v's unit vector.
    static bool is_norm_of(const Function& f, ValueId divisor, ValueId v) {
        const Instr* d = &f.body[divisor];
        if (d->op == Op::Builtin && std::string_view(builtin(d->aux).name) == "max" && d->args.size() == 2) {
            for (int s = 0; s < 2; ++s)
                if (f.body[d->args[size_t(1 - s)]].op == Op::Const) {
                    const Instr& c = f.body[d->args[size_t(1 - s)]];
                    if (c.data.size() == 1 && c.data[0] > 0 && c.data[0] <= 1e-20) return is_norm_of(f, d->args[size_t(s)], v);
                }
            return false;
        }
        return d->op == Op::Builtin && std::string_view(builtin(d->aux).name) == "length" && d->args.size() == 1 && d->args[0] == v;
    }

    // An interval per component from per-component rules over the operands.
    template <class Rule>
    IV each(const Type& t, Rule rule) {
        IV x;
        size_t n = size_t(std::max(1, t.components()));
        for (size_t k = 0; k < n; ++k) {
            auto [l, h] = rule(k);
            x.lo.push_back(l);
            x.hi.push_back(h);
        }
        return x;
    }

    // (rows, cols) of a value as a matrix product sees it: a vector is a column, a scalar 1×1.
    static std::pair<int, int> shape(const Type& t) {
        if (t.is_matrix()) return {t.rows, t.cols};
        if (t.is_vector()) return {t.rows, 1};
        return {1, 1};
    }

    IV builtin_rule(const Instr& in, const std::vector<const IV*>& a, const std::vector<Type>& ts) {
        std::string n = builtin(in.aux).name;
        auto lo = [&](size_t i, size_t k) { return comp(*a[i], ts[i], ts[i].components() == 1 ? 0 : k, false); };
        auto hi = [&](size_t i, size_t k) { return comp(*a[i], ts[i], ts[i].components() == 1 ? 0 : k, true); };
        auto monotone = [&](const char* fname) {
            return each(in.type, [&](size_t k) { return std::pair{call1(fname, lo(0, k)), call1(fname, hi(0, k))}; });
        };
        if (n == "floor" || n == "ceil" || n == "round" || n == "sign")  // monotone, with jumps
            return each(in.type, [&](size_t k) {
                auto [wl, wh] = widened(lo(0, k), hi(0, k));
                ValueId l = call1(n.c_str(), wl), h = call1(n.c_str(), wh);
                continuity.push_back(cmp(CompareKind::Eq, l, h));  // the same step at both ends: none between
                return std::pair{l, h};
            });
        if (n == "exp" || n == "tanh" || n == "sinh" || (n == "atan" && in.args.size() == 1)) return monotone(n.c_str());
        if (n == "sqrt")
            return each(in.type, [&](size_t k) {
                return std::pair{call1("sqrt", fmax(lo(0, k), num(0))), call1("sqrt", fmax(hi(0, k), num(0)))};
            });
        if (n == "log" || n == "ln")
            return each(in.type, [&](size_t k) {
                ValueId l = lo(0, k), h = hi(0, k);
                ValueId pos = cmp(CompareKind::Gt, l, num(0));
                return std::pair{sel(pos, call1("log", l), num(-kBig)), sel(cmp(CompareKind::Gt, h, num(0)), call1("log", h), num(-kBig))};
            });
        if (n == "asin" || n == "acos")
            return each(in.type, [&](size_t k) {
                ValueId l = call1(n.c_str(), b_.builtin("clamp", {lo(0, k), num(-1), num(1)}));
                ValueId h = call1(n.c_str(), b_.builtin("clamp", {hi(0, k), num(-1), num(1)}));
                return std::pair{fmin(l, h), fmax(l, h)};  // acos decreases
            });
        if (n == "cosh")
            return each(in.type, [&](size_t k) {
                ValueId l = lo(0, k), h = hi(0, k);
                ValueId cl = call1("cosh", l), ch = call1("cosh", h);
                ValueId holds0 = both(cmp(CompareKind::Le, l, num(0)), cmp(CompareKind::Ge, h, num(0)));
                return std::pair{sel(holds0, num(1), fmin(cl, ch)), fmax(cl, ch)};
            });
        if (n == "abs")  // [max(0, l, -h), max(-l, h)]
            return each(in.type, [&](size_t k) {
                ValueId l = lo(0, k), h = hi(0, k);
                return std::pair{fmax(num(0), fmax(l, neg(h))), fmax(neg(l), h)};
            });
        if (n == "sin" || n == "cos")
            // The ends, and ±1 where the interval holds a crest or a trough: sin's crests lie at π/2 + 2πn, so
            // [l, h] holds one when ⌊(h - π/2)/2π⌋ > ⌊(l - π/2)/2π⌋ (an interval 2π wide always does).
            return each(in.type, [&](size_t k) {
                ValueId l = lo(0, k), h = hi(0, k);
                ValueId fl = call1(n.c_str(), l), fh = call1(n.c_str(), h);
                double crest = n == "sin" ? M_PI / 2 : 0, trough = n == "sin" ? -M_PI / 2 : M_PI;
                auto holds = [&](double at) {
                    auto turns = [&](ValueId x) { return call1("floor", mul(sub(x, num(at)), num(0.5 / M_PI))); };
                    return cmp(CompareKind::Gt, turns(h), turns(l));
                };
                return std::pair{sel(holds(trough), num(-1), fmin(fl, fh)), sel(holds(crest), num(1), fmax(fl, fh))};
            });
        if (n == "min" || n == "max")
            return each(in.type, [&](size_t k) {
                return n == "min" ? std::pair{fmin(lo(0, k), lo(1, k)), fmin(hi(0, k), hi(1, k))}
                                  : std::pair{fmax(lo(0, k), lo(1, k)), fmax(hi(0, k), hi(1, k))};
            });
        if (n == "clamp")  // min(max(v, a), b), monotone in each argument
            return each(in.type, [&](size_t k) {
                return std::pair{fmin(fmax(lo(0, k), lo(1, k)), lo(2, k)), fmin(fmax(hi(0, k), hi(1, k)), hi(2, k))};
            });
        if (n == "step")  // step(e, x): 0 below the edge, 1 from it on: increasing in x, decreasing in e
            return each(in.type, [&](size_t k) {
                auto [wl, wh] = widened(lo(1, k), hi(1, k));
                ValueId l = b_.builtin("step", {hi(0, k), wl}), h = b_.builtin("step", {lo(0, k), wh});
                continuity.push_back(cmp(CompareKind::Eq, l, h));
                return std::pair{l, h};
            });
        if (n == "smoothstep") {  // monotone in x between exact edges (either way round); else [0, 1]
            if (!a[0]->exact || !a[1]->exact)
                return each(in.type, [&](size_t) { return std::pair{num(0), num(1)}; });
            return each(in.type, [&](size_t k) {
                ValueId l = b_.builtin("smoothstep", {lo(0, k), lo(1, k), lo(2, k)});
                ValueId h = b_.builtin("smoothstep", {lo(0, k), lo(1, k), hi(2, k)});
                return std::pair{fmin(l, h), fmax(l, h)};
            });
        }
        if (n == "mix")  // u + t(v - u)
            return each(in.type, [&](size_t k) {
                ValueId dl = sub(lo(1, k), hi(0, k)), dh = sub(hi(1, k), lo(0, k));
                auto [pl, ph] = product(lo(2, k), hi(2, k), a[2]->exact, dl, dh, false);
                return std::pair{add(lo(0, k), pl), add(hi(0, k), ph)};
            });
        if (n == "fract")  // the ends where no integer lies between them, else [0, 1]
            return each(in.type, [&](size_t k) {
                auto [l, h] = widened(lo(0, k), hi(0, k));
                ValueId same = cmp(CompareKind::Eq, call1("floor", l), call1("floor", h));
                continuity.push_back(same);
                return std::pair{sel(same, call1("fract", l), num(0)), sel(same, call1("fract", h), num(1))};
            });
        if (n == "mod" && a[1]->exact)  // x - m⌊x/m⌋ with m > 0: the ends within one period, else [0, m]
            return each(in.type, [&](size_t k) {
                auto [l, h] = widened(lo(0, k), hi(0, k));
                ValueId md = lo(1, k);
                ValueId same = both(cmp(CompareKind::Gt, md, num(0)),
                                    cmp(CompareKind::Eq, call1("floor", b_.op(Op::Div, {l, md})), call1("floor", b_.op(Op::Div, {h, md}))));
                ValueId full_lo = fmin(num(0), md), full_hi = fmax(num(0), md);
                continuity.push_back(same);
                return std::pair{sel(same, b_.builtin("mod", {l, md}), full_lo), sel(same, b_.builtin("mod", {h, md}), full_hi)};
            });
        if (n == "pow" && a[1]->exact)  // b^e for b ≥ 0 is monotone in b (either way): the ends; a negative base: unknown
            return each(in.type, [&](size_t k) {
                ValueId l = lo(0, k), h = hi(0, k), e = lo(1, k);
                ValueId pl = b_.builtin("pow", {fmax(l, num(0)), e}), ph = b_.builtin("pow", {fmax(h, num(0)), e});
                ValueId ok = cmp(CompareKind::Ge, l, num(0));
                return std::pair{sel(ok, fmin(pl, ph), num(-kBig)), sel(ok, fmax(pl, ph), num(kBig))};
            });
        // ‖v‖ of the first argument: √(Σ v_k²), each square never negative.
        auto norm = [&]() {
            ValueId s_lo = num(0), s_hi = num(0);
            for (size_t k = 0; k < size_t(ts[0].components()); ++k) {
                auto [l2, h2] = square(lo(0, k), hi(0, k));
                s_lo = add(s_lo, l2);
                s_hi = add(s_hi, h2);
            }
            return std::pair{call1("sqrt", s_lo), call1("sqrt", s_hi)};
        };
        if (n == "length") {
            auto [l, h] = norm();
            return pair(l, h);
        }
        if (n == "normalize") return unit_vector(*a[0], ts[0]);  // v / ‖v‖
        if (n == "atan" || n == "atan2") return each(in.type, [&](size_t) { return std::pair{num(-M_PI), num(M_PI)}; });
        return unknown(fmt::format("no interval rule for {}", n));
    }

    IV instr(const Function& f, const Instr& in, std::vector<IV>& v, const std::vector<IV>& params) {
        if (in.op == Op::Param) {
            if (size_t(in.aux) < params.size()) return params[size_t(in.aux)];
            return unknown("a parameter without a value");
        }
        std::vector<const IV*> a;
        std::vector<Type> ts;
        bool exact = true;
        for (ValueId x : in.args) {
            if (!v[x].bad.empty() && in.op != Op::Select && in.op != Op::If && in.op != Op::Switch) return v[x];
            a.push_back(&v[x]);
            ts.push_back(f.body[x].type);
            exact = exact && v[x].exact;
        }
        if (exact) {  // re-emitted as it is, on the exact operands (a call, a loop and its members too)
            Instr cp = in;
            for (size_t k = 0; k < cp.args.size(); ++k) cp.args[k] = a[k]->whole;
            cp.name.clear();
            cp.source.clear();
            IV x;
            x.exact = true;
            x.whole = b_.function().add(std::move(cp));
            return x;
        }
        if (in.op == Op::Call) {
            std::vector<IV> args;
            for (const IV* x : a) args.push_back(*x);
            return run(in.aux, args);
        }
        auto lo = [&](size_t i, size_t k) { return comp(*a[i], ts[i], ts[i].components() == 1 ? 0 : k, false); };
        auto hi = [&](size_t i, size_t k) { return comp(*a[i], ts[i], ts[i].components() == 1 ? 0 : k, true); };
        if (in.op == Op::Loop) return unknown("a loop (a recurrence) whose values depend on the box");
        if (in.type.kind == Type::Integer || in.type.is_array() || in.type.kind == Type::Tuple)
            return unknown(fmt::format("{} of a {} that depends on the box", op_name(in.op), in.type.str()));
        switch (in.op) {
            case Op::Copy: return *a[0];
            case Op::Add:
            case Op::Sub:
                return each(in.type, [&](size_t k) {
                    return in.op == Op::Add ? std::pair{add(lo(0, k), lo(1, k)), add(hi(0, k), hi(1, k))}
                                            : std::pair{sub(lo(0, k), hi(1, k)), sub(hi(0, k), lo(1, k))};
                });
            case Op::Neg: return each(in.type, [&](size_t k) { return std::pair{neg(hi(0, k)), neg(lo(0, k))}; });
            case Op::Hadamard:
                return each(in.type, [&](size_t k) {
                    if (in.args[0] == in.args[1]) return square(lo(0, k), hi(0, k));
                    return product(lo(0, k), hi(0, k), a[0]->exact, lo(1, k), hi(1, k), a[1]->exact);
                });
            case Op::Mul: {
                if (ts[0].is_scalar() || ts[1].is_scalar()) {
                    size_t s = ts[0].is_scalar() ? 0 : 1;
                    return each(in.type, [&](size_t k) {
                        if (in.args[0] == in.args[1]) return square(lo(0, 0), hi(0, 0));
                        return product(lo(s, 0), hi(s, 0), a[s]->exact, lo(1 - s, k), hi(1 - s, k), a[1 - s]->exact);
                    });
                }
                const int ac = shape(ts[0]).second, br = shape(ts[1]).first, bc = shape(ts[1]).second;
                if (ac != br) return unknown("a product of mismatched shapes");
                return each(in.type, [&](size_t k) {
                    size_t i = k / size_t(bc), j = k % size_t(bc);
                    ValueId sl = num(0), sh = num(0);
                    for (size_t q = 0; q < size_t(ac); ++q) {
                        size_t ka = i * size_t(ac) + q, kb = q * size_t(bc) + j;
                        auto [pl, ph] = product(lo(0, ka), hi(0, ka), a[0]->exact, lo(1, kb), hi(1, kb), a[1]->exact);
                        sl = add(sl, pl);
                        sh = add(sh, ph);
                    }
                    return std::pair{sl, sh};
                });
            }
            case Op::Div: {
                if (!ts[0].is_scalar() && ts[1].is_scalar() && is_norm_of(f, in.args[1], in.args[0])) return unit_vector(*a[0], ts[0]);
                if (a[1]->exact)
                    return each(in.type, [&](size_t k) {
                        ValueId p = b_.op(Op::Div, {lo(0, k), lo(1, 0)}), q = b_.op(Op::Div, {hi(0, k), lo(1, 0)});
                        return std::pair{fmin(p, q), fmax(p, q)};
                    });
                const auto rec = reciprocal(lo(1, 0), hi(1, 0));
                const ValueId rl = rec.first, rh = rec.second;
                return each(in.type, [&](size_t k) { return product(lo(0, k), hi(0, k), a[0]->exact, rl, rh, false); });
            }
            case Op::Dot: {
                ValueId sl = num(0), sh = num(0);
                for (size_t k = 0; k < size_t(ts[0].components()); ++k) {
                    auto [pl, ph] = in.args[0] == in.args[1] ? square(lo(0, k), hi(0, k))
                                                             : product(lo(0, k), hi(0, k), a[0]->exact, lo(1, k), hi(1, k), a[1]->exact);
                    sl = add(sl, pl);
                    sh = add(sh, ph);
                }
                return pair(sl, sh);
            }
            case Op::Cross:
                return each(in.type, [&](size_t k) {
                    size_t i = (k + 1) % 3, j = (k + 2) % 3;
                    auto [pl, ph] = product(lo(0, i), hi(0, i), a[0]->exact, lo(1, j), hi(1, j), a[1]->exact);
                    auto [ql, qh] = product(lo(0, j), hi(0, j), a[0]->exact, lo(1, i), hi(1, i), a[1]->exact);
                    return std::pair{sub(pl, qh), sub(ph, ql)};
                });
            case Op::Transpose: {
                const int r = shape(ts[0]).first, c = shape(ts[0]).second;
                return each(in.type, [&](size_t k) {
                    size_t i = k / size_t(r), j = k % size_t(r);  // result (c × r): element (i, j) is source (j, i)
                    size_t src = j * size_t(c) + i;
                    return std::pair{lo(0, src), hi(0, src)};
                });
            }
            case Op::Construct: {
                IV x;
                for (size_t i = 0; i < a.size(); ++i)
                    for (size_t k = 0; k < size_t(std::max(1, ts[i].components())); ++k) {
                        x.lo.push_back(lo(i, k));
                        x.hi.push_back(hi(i, k));
                    }
                return x;
            }
            case Op::Extract: return pair(lo(0, size_t(in.aux)), hi(0, size_t(in.aux)));
            case Op::Row: {
                size_t c = size_t(ts[0].cols);
                return each(in.type, [&](size_t k) { return std::pair{lo(0, size_t(in.aux) * c + k), hi(0, size_t(in.aux) * c + k)}; });
            }
            case Op::Column: {
                size_t c = size_t(ts[0].cols);
                return each(in.type, [&](size_t k) { return std::pair{lo(0, k * c + size_t(in.aux)), hi(0, k * c + size_t(in.aux))}; });
            }
            case Op::Builtin: return builtin_rule(in, a, ts);
            case Op::Compare: {
                // (certainly, possibly): a < b certainly when a's top is below b's bottom, possibly when a's
                // bottom is.
                ValueId al = lo(0, 0), ah = hi(0, 0), bl = lo(1, 0), bh = hi(1, 0);
                switch (CompareKind(in.aux)) {
                    case CompareKind::Lt: return pair(cmp(CompareKind::Lt, ah, bl), cmp(CompareKind::Lt, al, bh));
                    case CompareKind::Le: return pair(cmp(CompareKind::Le, ah, bl), cmp(CompareKind::Le, al, bh));
                    case CompareKind::Gt: return pair(cmp(CompareKind::Gt, al, bh), cmp(CompareKind::Gt, ah, bl));
                    case CompareKind::Ge: return pair(cmp(CompareKind::Ge, al, bh), cmp(CompareKind::Ge, ah, bl));
                    case CompareKind::Eq:
                    case CompareKind::Ne: {
                        ValueId apart = either(cmp(CompareKind::Lt, ah, bl), cmp(CompareKind::Lt, bh, al));
                        ValueId same = both(both(cmp(CompareKind::Eq, al, ah), cmp(CompareKind::Eq, bl, bh)), cmp(CompareKind::Eq, al, bl));
                        ValueId yes = b_.constant(Type::boolean(), {1}), no = b_.constant(Type::boolean(), {0});
                        ValueId not_apart = sel(apart, no, yes), not_same = sel(same, no, yes);
                        if (CompareKind(in.aux) == CompareKind::Eq) return pair(same, not_apart);
                        return pair(apart, not_same);
                    }
                }
                return unknown("a comparison");
            }
            case Op::And: return pair(both(lo(0, 0), lo(1, 0)), both(hi(0, 0), hi(1, 0)));
            case Op::Or: return pair(either(lo(0, 0), lo(1, 0)), either(hi(0, 0), hi(1, 0)));
            case Op::Select:
            case Op::If: {
                // A decided condition takes its arm; an undecided one the hull of both.
                const IV& c = *a[0];
                const IV& x = *a[1];
                const IV& y = *a[2];
                if (!c.bad.empty()) return c;
                if (c.exact) {
                    if (!x.bad.empty() || !y.bad.empty()) {
                        // Only a constant condition can leave the unknown arm out.
                        const Instr& ci = b_.function().body[c.whole];
                        if (ci.op == Op::Const) return (ci.data[0] != 0 ? x : y);
                        return !x.bad.empty() ? x : y;
                    }
                    return each(in.type, [&](size_t k) {
                        return std::pair{sel(c.whole, lo(1, k), lo(2, k)), sel(c.whole, hi(1, k), hi(2, k))};
                    });
                }
                if (!x.bad.empty()) return x;
                if (!y.bad.empty()) return y;
                ValueId sure = c.lo[0], maybe = c.hi[0];
                continuity.push_back(sel(maybe, sure, b_.constant(Type::boolean(), {1})));  // decided either way
                if (in.type.kind == Type::Bool)
                    return pair(sel(sure, lo(1, 0), sel(maybe, both(lo(1, 0), lo(2, 0)), lo(2, 0))),
                                sel(sure, hi(1, 0), sel(maybe, either(hi(1, 0), hi(2, 0)), hi(2, 0))));
                return each(in.type, [&](size_t k) {
                    return std::pair{sel(sure, lo(1, k), sel(maybe, fmin(lo(1, k), lo(2, k)), lo(2, k))),
                                     sel(sure, hi(1, k), sel(maybe, fmax(hi(1, k), hi(2, k)), hi(2, k)))};
                });
            }
            case Op::Switch: {
                // Only a selector the extension knows exactly: a constant picks its case, another value switches
                // each component's ends.
                const IV& s = *a[0];
                if (!s.exact) return unknown("a switch on a value that depends on the box");
                const Instr& si = b_.function().body[s.whole];
                if (si.op == Op::Const) {
                    double sv = si.data[0];
                    for (int c = 0; c < switch_cases(in); ++c)
                        if (sv >= in.data[size_t(2 * c)] && sv < in.data[size_t(2 * c + 1)]) return *a[size_t(2 + c)];
                    return *a[1];
                }
                for (size_t i = 1; i < a.size(); ++i)
                    if (!a[i]->bad.empty()) return *a[i];
                return each(in.type, [&](size_t k) {
                    auto ends = [&](bool high) {
                        Instr sw;
                        sw.op = Op::Switch;
                        sw.type = Type::scalar();
                        sw.data = in.data;
                        sw.args.push_back(s.whole);
                        for (size_t i = 1; i < a.size(); ++i) sw.args.push_back(high ? hi(i, k) : lo(i, k));
                        return b_.function().add(std::move(sw));
                    };
                    return std::pair{ends(false), ends(true)};
                });
            }
            default:
                return unknown(fmt::format("{} of a value that depends on the box", op_name(in.op)));
        }
    }
};

}  // namespace

IntervalCode emit_interval_extension(Builder& b, const Module& m, int fn, int wrt, ValueId lo, ValueId hi,
                                     const std::vector<ValueId>& args) {
    const Function& f = m.functions[size_t(fn)];
    std::vector<IV> params(f.params.size());
    for (size_t j = 0; j < f.params.size(); ++j) {
        if (int(j) == wrt) continue;
        params[j].exact = true;
        params[j].whole = args.at(j);
    }
    Extender x(b, m);
    const Type& pt = f.params.at(size_t(wrt)).type;
    for (size_t k = 0; k < size_t(std::max(1, pt.components())); ++k) {
        params[size_t(wrt)].lo.push_back(pt.is_scalar() ? lo : b.op(Op::Extract, {lo}, int(k)));
        params[size_t(wrt)].hi.push_back(pt.is_scalar() ? hi : b.op(Op::Extract, {hi}, int(k)));
    }
    IV r = x.run(fn, params);
    IntervalCode out;
    for (ValueId c : x.continuity) out.continuous = out.continuous == ValueId(-1) ? c : b.op(Op::And, {out.continuous, c});
    if (!r.bad.empty()) {
        out.why = r.bad;
        return out;
    }
    const Type& t = f.result_type();
    if (r.exact) {
        out.ok = true;
        out.lo = out.hi = r.whole;
        return out;
    }
    size_t n = size_t(std::max(1, t.components()));
    std::vector<ValueId> l, h;
    for (size_t k = 0; k < n; ++k) {
        l.push_back(x.comp(r, t, k, false));
        h.push_back(x.comp(r, t, k, true));
    }
    out.ok = true;
    out.lo = t.is_scalar() ? l[0] : b.construct(t, l);
    out.hi = t.is_scalar() ? h[0] : b.construct(t, h);
    return out;
}

}  // namespace iqc::ir
