#include "ir/CaseSplit.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The search itself (case_split_bound): one per function and box.
class CaseSplit {
public:
    int passes_left() const { return passes_left_; }
    // `zero_cases`: a sign of a query coordinate also has the case x = 0 exactly (outcome 3), where parameter 0
    // is not the query point but values of it that may hold still on a volume of p (a blend's distances).
    CaseSplit(const Module& m, const Function& f, const CaseScore& score, const CaseSplitOptions& o)
        : m_(m), f_(f), score_(score), query_point_(o.query_point), zero_cases_(o.zero_cases), loop_trips_(o.loop_trips),
          work_(o.work), floor_(o.floor), target_(o.target) {}

    double bound(const std::vector<std::vector<Interval>>& params, int passes) {
        params_ = &params;
        passes_left_ = passes;
        std::vector<Choice> choices;
        return explore(choices);
    }

private:
    struct Choice {
        ValueId at;
        int comp;     // a sign's component (a comparison: 0)
        int outcome;  // a comparison: 1 or 0; a sign: 1 or -1 (strict), 2 or -2 (x ≥ 0, x ≤ 0), 3 (x = 0)
    };
    const Module& m_;
    const Function& f_;
    const CaseScore& score_;
    bool query_point_;
    bool zero_cases_;
    int loop_trips_;
    long* work_;
    double floor_;
    double target_;
    const std::vector<std::vector<Interval>>* params_ = nullptr;
    // Per value: its narrowed components (empty: none), and the state of the current pass.
    std::vector<std::vector<Interval>> narrowed_;
    std::vector<Bounds>* r_ = nullptr;
    bool changed_ = false, empty_ = false;
    size_t at_ = 0;  // the value the pass has reached
    int passes_left_ = 0;
    std::vector<Bounds> values_;  // one pass's values
    IntervalScratch scratch_;     // and its callees' buffers

    // a ∩ b; empty marks the case impossible (within rounding in the ends, which leaves a point).
    Interval meet(Interval a, Interval b) {
        Interval x{std::max(a.lo, b.lo), std::min(a.hi, b.hi)};
        if (x.lo > x.hi) {
            if (x.lo > x.hi + 1e-9 * (1 + std::fabs(x.lo) + std::fabs(x.hi))) empty_ = true;
            x.lo = x.hi = 0.5 * (x.lo + x.hi);
        }
        return x;
    }

    // What comparison `target` is where comparison `chosen` of the same two operands (in either order) came
    // out `outcome`: 1, 0, or -1 when it does not say (a ≥ b leaves a ≤ b open: they may be equal).
    static int implies(const Instr& chosen, bool outcome, const Instr& target) {
        if (chosen.op != Op::Compare || chosen.args.size() != 2 || target.args.size() != 2) return -1;
        auto mirror = [](CompareKind k) {
            switch (k) {
                case CompareKind::Lt: return CompareKind::Gt;
                case CompareKind::Le: return CompareKind::Ge;
                case CompareKind::Gt: return CompareKind::Lt;
                case CompareKind::Ge: return CompareKind::Le;
                default: return k;
            }
        };
        CompareKind t = CompareKind(target.aux);
        if (chosen.args[0] == target.args[1] && chosen.args[1] == target.args[0]) t = mirror(t);
        else if (chosen.args[0] != target.args[0] || chosen.args[1] != target.args[1]) return -1;
        // The relation of a to b that holds: <, ≤, >, ≥.
        CompareKind rel = CompareKind(chosen.aux);
        if (!outcome) {
            switch (rel) {
                case CompareKind::Lt: rel = CompareKind::Ge; break;
                case CompareKind::Le: rel = CompareKind::Gt; break;
                case CompareKind::Gt: rel = CompareKind::Le; break;
                case CompareKind::Ge: rel = CompareKind::Lt; break;
                default: return -1;
            }
        }
        using K = CompareKind;
        switch (rel) {
            case K::Lt: return t == K::Lt || t == K::Le ? 1 : t == K::Gt || t == K::Ge ? 0 : -1;
            case K::Gt: return t == K::Gt || t == K::Ge ? 1 : t == K::Lt || t == K::Le ? 0 : -1;
            case K::Le: return t == K::Le ? 1 : t == K::Gt ? 0 : -1;
            case K::Ge: return t == K::Ge ? 1 : t == K::Lt ? 0 : -1;
            default: return -1;
        }
    }

    // Whether v is the query point (parameter 0, when it is the query point p: a cut's u = T(p) can be 0 on a
    // whole slab of p) itself, a copy of it, a nonzero multiple of it, it plus a constant, or one of its components.
    bool is_query_coordinate(ValueId v) const {
        if (!query_point_) return false;
        const Instr& in = f_.body[v];
        if (in.op == Op::Param) return in.aux == 0;
        if (in.op == Op::Copy || in.op == Op::Extract || in.op == Op::Neg) return is_query_coordinate(in.args[0]);
        if ((in.op == Op::Mul || in.op == Op::Div) && in.type.kind == Type::Scalar) {  // c·x, x/c (c ≠ 0): x's zeros
            auto nonzero = [&](ValueId c) {
                const Instr& k = f_.body[c];
                return k.op == Op::Const && k.data.size() == 1 && k.data[0] != 0 && std::isfinite(k.data[0]);
            };
            if (nonzero(in.args[1])) return is_query_coordinate(in.args[0]);
            if (in.op == Op::Mul && nonzero(in.args[0])) return is_query_coordinate(in.args[1]);
        }
        // x ± c, the plane x = ∓c, in a blend's arguments (where the branches of Quilez's smooth minima meet at
        // a - b = 0 with a and b offsets of the leaves); for p itself the splits it adds cost more than they gain
        // (the capped cylinder's bound 1.41 → 2 with the same budget).
        if (zero_cases_ && (in.op == Op::Add || in.op == Op::Sub) && in.type.kind == Type::Scalar) {
            auto constant = [&](ValueId c) { return f_.body[c].op == Op::Const && f_.body[c].data.size() == 1; };
            if (constant(in.args[1])) return is_query_coordinate(in.args[0]);
            if (constant(in.args[0])) return is_query_coordinate(in.args[1]);
        }
        return false;
    }

    static bool tighter(Interval want, Interval have) { return want.lo > have.lo || want.hi < have.hi; }

    // Narrows component k of value v to `want` (intersected), then what v was computed from.
    void narrow(ValueId v, size_t k, Interval want, int depth) {
        if (empty_ || std::isnan(want.lo) || std::isnan(want.hi)) return;
        Bounds& b = (*r_)[v];
        if (k >= b.c.size()) return;
        Interval have = b.c[k];
        if (!tighter(want, have)) return;
        Interval next = meet(have, want);
        if (empty_) return;
        b.c[k] = next;
        if (narrowed_[v].empty()) narrowed_[v] = b.c;
        narrowed_[v][k] = next;
        if (v < at_) changed_ = true;  // values computed from v this pass saw less
        if (depth <= 0) return;
        const Instr& in = f_.body[v];
        auto arg = [&](size_t i) -> Bounds& { return (*r_)[in.args[i]]; };
        auto comp = [&](size_t i, size_t kk) { return arg(i).c.size() == 1 ? arg(i).c[0] : arg(i).c[kk]; };
        auto narrow_arg = [&](size_t i, Interval w) { narrow(in.args[i], arg(i).c.size() == 1 ? 0 : k, w, depth - 1); };
        switch (in.op) {
            case Op::Copy: narrow(in.args[0], k, next, depth - 1); break;
            case Op::Extract: narrow(in.args[0], size_t(in.aux), next, depth - 1); break;
            case Op::Construct: {
                size_t off = 0;
                for (size_t i = 0; i < in.args.size(); ++i) {
                    size_t n = arg(i).c.size();
                    if (k < off + n) {
                        narrow(in.args[i], k - off, next, depth - 1);
                        break;
                    }
                    off += n;
                }
                break;
            }
            case Op::Neg: narrow_arg(0, iv::neg(next)); break;
            case Op::Add:  // x = a + b: a ∈ x - b, b ∈ x - a
                if (in.type.components() != f_.body[in.args[0]].type.components() ||
                    in.type.components() != f_.body[in.args[1]].type.components())
                    break;  // a broadcast scalar
                narrow_arg(0, iv::add(next, iv::neg(comp(1, k))));
                narrow_arg(1, iv::add(next, iv::neg(comp(0, k))));
                break;
            case Op::Sub:  // x = a - b: a ∈ x + b, b ∈ a - x
                if (in.type.components() != f_.body[in.args[0]].type.components() ||
                    in.type.components() != f_.body[in.args[1]].type.components())
                    break;
                narrow_arg(0, iv::add(next, comp(1, k)));
                narrow_arg(1, iv::add(comp(0, k), iv::neg(next)));
                break;
            case Op::Builtin: {
                std::string_view name = builtins()[size_t(in.aux)].name;
                if ((name == "min" || name == "max") && in.args.size() == 2) {
                    bool is_max = name == "max";
                    for (size_t i = 0; i < 2; ++i) {
                        // max: every operand is at most x; the other below x's bottom makes this one the max.
                        Interval other = comp(1 - i, k);
                        Interval w = is_max ? Interval{-kInf, next.hi} : Interval{next.lo, kInf};
                        if (is_max && other.hi < next.lo) w.lo = next.lo;
                        if (!is_max && other.lo > next.hi) w.hi = next.hi;
                        if (f_.body[in.args[i]].type.components() == in.type.components() || arg(i).c.size() == 1)
                            narrow_arg(i, w);
                    }
                } else if (name == "abs") {
                    Interval a = comp(0, k);
                    Interval w{-next.hi, next.hi};
                    if (a.lo >= 0) w = next;
                    else if (a.hi <= 0) w = iv::neg(next);
                    narrow_arg(0, w);
                }
                break;
            }
            default: break;
        }
    }

    // A comparison or a sign's component not decided by the intervals: where the next split goes.
    struct Open {
        ValueId at = ValueId(-1);
        int comp = 0;
        std::vector<int> outcomes;  // the cases with room (a comparison: 1, 0; a sign: 1, -1 or 2, -2; 3)
    };

    // Applies the case's choices to value i (a comparison or a sign) once its rule has run: its value, and
    // what the choice implies of its operands. Records in `open` the first undecided one no choice covers.
    void decide(size_t i, std::vector<Bounds>& r, const std::vector<Choice>& choices, Open& open) {
        const Instr& in = f_.body[i];
        Bounds& b = r[i];
        auto choice = [&](int comp) -> const Choice* {
            for (const Choice& x : choices)
                if (x.at == ValueId(i) && x.comp == comp) return &x;
            return nullptr;
        };
        // (Not a comparison of a value that may be NaN: both a < b and a ≥ b are false there, a third case.)
        if (in.op == Op::Compare && b.c.size() == 1 && b.c[0].lo < b.c[0].hi && r[in.args[0]].c.size() == 1 &&
            r[in.args[1]].c.size() == 1 && !r[in.args[0]].nan && !r[in.args[1]].nan) {
            const Choice* c = choice(0);
            int implied = -1;
            for (const Choice& x : choices)
                if (implied < 0 && x.at != ValueId(i)) implied = implies(f_.body[x.at], x.outcome == 1, in);
            CompareKind kind = CompareKind(in.aux);
            if (!c && implied >= 0) {
                b.c[0] = {double(implied), double(implied)};
            } else if (!c) {
                if (open.at == ValueId(-1) && kind != CompareKind::Eq && kind != CompareKind::Ne) {
                    open = {ValueId(i), 0, {}};
                    for (int o : {1, 0}) {
                        bool below = (kind == CompareKind::Lt || kind == CompareKind::Le) == (o == 1);
                        bool strict = (kind == CompareKind::Lt || kind == CompareKind::Gt) == (o == 1);
                        Interval lo = r[below ? in.args[0] : in.args[1]].c[0], hi = r[below ? in.args[1] : in.args[0]].c[0];
                        if (strict ? lo.lo < hi.hi : lo.lo <= hi.hi) open.outcomes.push_back(o);
                    }
                }
            } else {
                b.c[0] = {double(c->outcome), double(c->outcome)};
                // a ≤ b (and a < b, closed): a ≤ b's top, b ≥ a's bottom. A strict case needs room: a < b is
                // impossible where a's bottom is not below b's top.
                bool below = (kind == CompareKind::Lt || kind == CompareKind::Le) == (c->outcome == 1);
                bool strict = (kind == CompareKind::Lt || kind == CompareKind::Gt) == (c->outcome == 1);
                ValueId lo_v = below ? in.args[0] : in.args[1], hi_v = below ? in.args[1] : in.args[0];
                if (strict && !(r[lo_v].c[0].lo < r[hi_v].c[0].hi)) {
                    empty_ = true;
                    return;
                }
                narrow(lo_v, 0, {-kInf, r[hi_v].c[0].hi}, 12);
                narrow(hi_v, 0, {r[lo_v].c[0].lo, kInf}, 12);
            }
            return;
        }
        if (in.op == Op::Builtin && builtins()[size_t(in.aux)].name == std::string_view("sign") && in.args.size() == 1 &&
            r[in.args[0]].c.size() == b.c.size() && !r[in.args[0]].nan) {
            // sign(x) of a query-point coordinate: x > 0 or x < 0. x = 0 is a plane there: no volume, and the
            // bound of a gradient is wanted only almost everywhere (a continuous field's Lipschitz constant is the
            // essential supremum of ‖∇D‖, Rademacher's theorem). Elsewhere x = 0 may be a region (max(p₁, 0), or
            // a cut's u = T(p)): the cases are the closed halves x ≥ 0 (outcome 2) and x ≤ 0 (-2), each sign the
            // interval of what its half allows ([0, 1] where x can be 0).
            for (size_t k = 0; k < b.c.size() && !empty_; ++k) {
                if (!(b.c[k].lo < b.c[k].hi)) continue;
                const Choice* c = choice(int(k));
                Interval x = r[in.args[0]].c[k];
                bool plane = is_query_coordinate(in.args[0]);
                if (!c) {
                    if (open.at != ValueId(-1)) continue;
                    open = {ValueId(i), int(k), {}};
                    if (x.hi > 0) open.outcomes.push_back(plane ? 1 : 2);
                    if (x.lo < 0) open.outcomes.push_back(plane ? -1 : -2);
                    if (plane && zero_cases_ && x.lo <= 0 && x.hi >= 0) open.outcomes.push_back(3);
                    continue;
                }
                int o = c->outcome;
                bool room = o == 1 ? x.hi > 0 : o == -1 ? x.lo < 0 : o == 2 || o == 3 ? x.hi >= 0 : x.lo <= 0;
                if (o == 3) room &= x.lo <= 0;
                if (!room) {
                    empty_ = true;
                    return;
                }
                narrow(in.args[0], k, o == 3 ? Interval{0, 0} : o > 0 ? Interval{0, kInf} : Interval{-kInf, 0}, 12);
                if (empty_) return;
                Interval n = r[in.args[0]].c[k];
                if (o == 3) b.c[k] = {0, 0};
                else if (o == 1 || o == -1) b.c[k] = {double(o), double(o)};
                else b.c[k] = {n.lo > 0 ? 1.0 : n.lo >= 0 ? 0.0 : -1.0, n.hi < 0 ? -1.0 : n.hi <= 0 ? 0.0 : 1.0};
            }
            b.norm = std::min(b.norm, b.norm_from_components());
        }
    }

    // One pass of intervals over the function with the case's choices; the result's norm bound, 0 for a case
    // that cannot happen. `open` receives the first comparison or sign left undecided that no choice covers.
    double pass(const std::vector<Choice>& choices, Open& open) {
        empty_ = false;
        double last = kInf;
        for (int round = 0; round < 3; ++round) {
            changed_ = false;
            open = {};
            IntervalHook hook = [&](size_t i, std::vector<Bounds>& r) {
                r_ = &r;
                at_ = i;
                Bounds& b = r[i];
                if (!narrowed_[i].empty() && narrowed_[i].size() == b.c.size()) {
                    for (size_t k = 0; k < b.c.size() && !empty_; ++k) b.c[k] = meet(b.c[k], narrowed_[i][k]);
                    b.norm = std::min(b.norm, b.norm_from_components());
                }
                if (!empty_) decide(i, r, choices, open);
                return !empty_;
            };
            interval_analysis(scratch_, values_, m_, f_, *params_, hook, loop_trips_, work_);
            r_ = nullptr;
            --passes_left_;
            if (empty_) return floor_;
            last = score_(values_[f_.result]);
            if (!changed_) return last;
        }
        // Still narrowing after three rounds: the last pass's values hold, only not the tightest.
        return last;
    }

    // The bound over the case `choices`: one pass, then, while passes are left, the cases of the first
    // undecided comparison or sign (the largest of their bounds, if below this case's).
    double explore(std::vector<Choice>& choices) {
        narrowed_.assign(f_.body.size(), {});
        Open open;
        double here = pass(choices, open);
        if (!(here > floor_) || open.at == ValueId(-1) || passes_left_ < 2) return here;
        double worst = floor_;
        for (int outcome : open.outcomes) {
            choices.push_back({open.at, open.comp, outcome});
            worst = std::max(worst, explore(choices));
            choices.pop_back();
            if (!(worst < here)) return here;  // no better than the hull
            if (worst >= target_) return worst;  // a case reaches the target: the caller needs no more
        }
        return worst;
    }
};

}  // namespace

double case_split_bound(const Module& m, const Function& f, const std::vector<std::vector<Interval>>& params,
                        const CaseScore& score, int passes, const CaseSplitOptions& options, int* passes_left) {
    CaseSplit cs(m, f, score, options);
    double r = cs.bound(params, passes);
    if (passes_left) *passes_left = cs.passes_left();
    return r;
}

}  // namespace iqc::ir
