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

}  // namespace

int convert_cheap_choices(const Module& m, Function& f) {
    bool any = false;
    for (const Instr& in : f.body) any |= in.op == Op::If || in.op == Op::Switch;
    if (!any) return 0;
    Schedule s = schedule(f);
    std::vector<std::vector<int>> children(s.regions.size());
    for (size_t r = 1; r < s.regions.size(); ++r) children[size_t(s.regions[r].parent)].push_back(int(r));
    // The cost of region r with the regions nested in it (memoised: every region has one parent).
    std::vector<int> memo(s.regions.size(), -1);
    auto cost = [&](auto& self, int r) -> int {
        if (memo[size_t(r)] >= 0) return memo[size_t(r)];
        long long c = 0;
        for (ValueId i : s.regions[size_t(r)].instrs) c += instr_cost(f, f.body[i]);
        for (int k : children[size_t(r)]) c += self(self, k);
        return memo[size_t(r)] = int(std::min<long long>(c, kUnsafe));
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
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        if ((in.op != Op::If && in.op != Op::Switch) || !s.live(ValueId(i)) || !selectable(in.type) || !only_arguments[i]) continue;
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
            v = map[in.args[1]];
            for (int k = switch_cases(in); k-- > 0;) {
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
