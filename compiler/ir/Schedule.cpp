#include "ir/Schedule.h"

namespace iqc::ir {

namespace {

// The nearest region enclosing both a and b (-1 stands for "no use yet").
int common_region(const Schedule& s, const std::vector<int>& depth, int a, int b) {
    if (a < 0) return b;
    if (b < 0) return a;
    while (depth[size_t(a)] > depth[size_t(b)]) a = s.regions[size_t(a)].parent;
    while (depth[size_t(b)] > depth[size_t(a)]) b = s.regions[size_t(b)].parent;
    while (a != b) {
        a = s.regions[size_t(a)].parent;
        b = s.regions[size_t(b)].parent;
    }
    return a;
}

}  // namespace

Schedule schedule(const Function& f, const std::vector<ValueId>& roots) {
    Schedule s;
    size_t n = f.body.size();
    s.regions.push_back({});
    s.region_of.assign(n, -1);
    s.arms.assign(n, {});
    std::vector<int> depth = {0};
    for (ValueId r : roots)
        if (r < n) s.region_of[r] = 0;
    // Users come after what they use: walking backwards, every use of an instruction is known before it.
    for (size_t i = n; i-- > 0;) {
        int region = s.region_of[i];
        if (region < 0) continue;
        const Instr& in = f.body[i];
        bool lazy = in.op == Op::If || in.op == Op::Switch;
        if (lazy) s.arms[i].assign(in.args.size(), -1);
        for (size_t k = 0; k < in.args.size(); ++k) {
            int demand = region;
            if (lazy && is_arm(in, k)) {
                Schedule::Region arm;
                arm.parent = region;
                arm.owner = ValueId(i);
                arm.operand = int(k);
                s.regions.push_back(std::move(arm));
                depth.push_back(depth[size_t(region)] + 1);
                demand = int(s.regions.size() - 1);
                s.arms[i][k] = demand;
            }
            ValueId a = in.args[k];
            s.region_of[a] = common_region(s, depth, s.region_of[a], demand);
        }
    }
    for (size_t i = 0; i < n; ++i)
        if (s.region_of[i] >= 0) s.regions[size_t(s.region_of[i])].instrs.push_back(ValueId(i));
    return s;
}

Schedule schedule(const Function& f) {
    std::vector<ValueId> roots = {f.result};
    for (const auto& [name, v] : f.outputs) roots.push_back(v);
    return schedule(f, roots);
}

}  // namespace iqc::ir
