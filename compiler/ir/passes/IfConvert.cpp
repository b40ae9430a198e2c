#include "ir/passes/IfConvert.h"

#include <algorithm>
#include <cmath>

#include "ir/Builder.h"
#include "ir/Schedule.h"

namespace iqc::ir {

namespace {

constexpr int kUnsafe = 1 << 20;

// What computing `in` speculatively costs: 0 for values that are free to read, kUnsafe for what must not run
// on another case's values (or whose cost is unknown here).
int instr_cost(const Function& f, const Instr& in) {
    if (!speculatable(f.body, in)) return kUnsafe;
    switch (in.op) {
        // Reading and moving components: no arithmetic (a driver flattens a branch of only these itself).
        case Op::Param: case Op::Const: case Op::Global: case Op::Input: case Op::Copy:
        case Op::Construct: case Op::Extract: case Op::Row: case Op::Column: case Op::Element: return 0;
        default: return 1;
    }
}

bool selectable(const Type& t) { return t.is_scalar() || t.is_vector() || t.kind == Type::Bool; }

// What computing a call of function `fi` speculatively costs: its instructions' costs, calls in it costed the
// same way (to `depth` levels; deeper: kUnsafe), kUnsafe where any of them is not safe to compute on another
// case's values. Every instruction of the body counts, live or not (dead code elimination runs later).
int callee_cost(const Module& m, int fi, int depth = 4) {
    if (fi < 0 || size_t(fi) >= m.functions.size() || depth == 0) return kUnsafe;
    const Function& g = m.functions[size_t(fi)];
    long long c = 0;
    for (const Instr& in : g.body) {
        if (in.op == Op::If || in.op == Op::Switch) return kUnsafe;  // lazy inside: not costed here
        c += in.op == Op::Call ? callee_cost(m, in.aux, depth - 1) : instr_cost(g, in);
        if (c >= kUnsafe) return kUnsafe;
    }
    return int(c);
}

}  // namespace

int convert_cheap_choices(const Module& m, Function& f) {
    bool any = false;
    for (const Instr& in : f.body) any |= in.op == Op::If || in.op == Op::Switch;
    if (!any) return 0;
    Schedule s = schedule(f);
    std::vector<std::vector<int>> children(s.regions.size());
    for (size_t r = 1; r < s.regions.size(); ++r) children[size_t(s.regions[r].parent)].push_back(int(r));
    // The cost of region r with the regions nested in it (memoised: every region has one parent).
    // With `calls`, a call costs its callee's instructions (callee_cost); else it is not safe.
    std::vector<int> memo(s.regions.size(), -1), memo_calls(s.regions.size(), -1);
    auto cost = [&](auto& self, int r, bool calls = false) -> int {
        std::vector<int>& mm = calls ? memo_calls : memo;
        if (mm[size_t(r)] >= 0) return mm[size_t(r)];
        long long c = 0;
        for (ValueId i : s.regions[size_t(r)].instrs) {
            const Instr& in = f.body[i];
            c += calls && in.op == Op::Call ? callee_cost(m, in.aux) : instr_cost(f, in);
        }
        for (int k : children[size_t(r)]) c += self(self, k, calls);
        return mm[size_t(r)] = int(std::min<long long>(c, kUnsafe));
    };
    // Which choices only feed calls' arguments.
    std::vector<char> only_arguments(f.body.size(), 1);
    for (size_t i = 0; i < f.body.size(); ++i) {
        if (!s.live(ValueId(i))) continue;
        for (ValueId a : f.body[i].args)
            if (f.body[i].op != Op::Call) only_arguments[a] = 0;
    }
    only_arguments[f.result] = 0;
    for (const auto& [name, o] : f.outputs) only_arguments[o] = 0;
    std::vector<char> convert(f.body.size(), 0);
    int converted = 0;
    // The finite-difference normal's dispatch (iqc_distance_of's result: each instance's distance, the runtime
    // passing only instances' ids): with few instances whose distances are cheap, every instance's distance and
    // a chain of selects, the widest case innermost untested (no default: no other id comes).
    ValueId dispatch = ValueId(-1);
    if (f.name == names::kDistanceOf && f.body[f.result].op == Op::Switch) {
        const Instr& in = f.body[f.result];
        int total = 0;
        for (size_t k = 2; k < in.args.size() && total <= kMaxDispatchCost; ++k) {
            int r = s.arms[f.result][k];
            total += r < 0 ? 0 : cost(cost, r, true);
        }
        if (switch_cases(in) >= 2 && switch_cases(in) <= kMaxArms && selectable(in.type) && total <= kMaxDispatchCost)
            dispatch = f.result, convert[f.result] = 1, ++converted;
    }
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        if ((in.op != Op::If && in.op != Op::Switch) || !s.live(ValueId(i)) || !selectable(in.type) || !only_arguments[i] ||
            ValueId(i) == dispatch)
            continue;
        if (in.op == Op::Switch && (switch_cases(in) == 0 || switch_cases(in) + 1 > kMaxArms)) continue;
        int total = 0;
        bool cheap = true;
        for (size_t k = 1; k < in.args.size() && cheap; ++k) {
            int r = s.arms[i][k];
            int c = r < 0 ? 0 : cost(cost, r);
            cheap = c <= kMaxArmCost;
            total += c;
        }
        // Arms that only read values (`if (l == 0) position = light_1_position;`) are left as they are: every
        // driver flattens such a branch itself, and the chain of ifs reads better than nested selects.
        if (cheap && total > 0 && total <= kMaxTotalCost) convert[i] = 1, ++converted;
    }
    if (converted == 0) return 0;
    std::vector<Instr> old;
    old.swap(f.body);
    std::vector<ValueId> map(old.size());
    Builder b(m, f);
    for (size_t i = 0; i < old.size(); ++i) {
        const Instr& in = old[i];
        if (!convert[i]) {
            Instr copy = in;
            for (ValueId& a : copy.args) a = map[a];
            map[i] = f.add(std::move(copy));
            continue;
        }
        ValueId v;
        if (in.op == Op::If) {
            v = b.op(Op::Select, {map[in.args[0]], map[in.args[1]], map[in.args[2]]});
        } else {
            // The cases are disjoint: their order in the chain does not matter; the default is the innermost.
            ValueId sel = map[in.args[0]];
            int cases = switch_cases(in);
            auto width = [&](int k) { return in.data[size_t(2 * k + 1)] - in.data[size_t(2 * k)]; };
            // The dispatch's widest case (a group's range of ids, whose test takes two comparisons) stands
            // innermost, where the default was, untested.
            int untested = -1;
            if (ValueId(i) == dispatch) {
                untested = cases - 1;
                for (int k = 0; k < cases; ++k)
                    if (width(k) > width(untested)) untested = k;
            }
            v = map[in.args[untested >= 0 ? size_t(untested) + 2 : 1]];
            for (int k = cases; k-- > 0;) {
                if (k == untested) continue;
                long long lo = std::llround(in.data[size_t(2 * k)]), hi = std::llround(in.data[size_t(2 * k + 1)]);
                ValueId cond = hi == lo + 1 ? b.compare(CompareKind::Eq, sel, b.integer(lo))
                                            : b.op(Op::And, {b.compare(CompareKind::Ge, sel, b.integer(lo)),
                                                             b.compare(CompareKind::Lt, sel, b.integer(hi))});
                v = b.op(Op::Select, {cond, map[in.args[size_t(k) + 2]], v});
            }
        }
        f.body[v].name = in.name;
        f.body[v].source = in.source;
        f.body[v].span = in.span;
        map[i] = v;
    }
    f.result = map[f.result];
    for (auto& [name, o] : f.outputs) o = map[o];
    return converted;
}

int convert_cheap_choices(Module& m) {
    int n = 0;
    for (Function& f : m.functions) n += convert_cheap_choices(m, f);
    return n;
}

}  // namespace iqc::ir
