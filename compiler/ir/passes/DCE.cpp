#include "ir/passes/DCE.h"

#include <functional>

namespace iqc::ir {

int eliminate_dead_code(Function& f) {
    size_t n = f.body.size();
    if (n == 0) return 0;
    std::vector<bool> live(n, false);
    live[f.result] = true;
    for (const auto& [name, v] : f.outputs) live[v] = true;
    // Parameters stay: they are the function's interface (and the emitter names them).
    for (size_t i = 0; i < n; ++i)
        if (f.body[i].op == Op::Param) live[i] = true;
    for (size_t i = n; i-- > 0;)
        if (live[i])
            for (ValueId a : f.body[i].args) live[a] = true;
    std::vector<ValueId> map(n, ValueId(-1));
    std::vector<Instr> body;
    for (size_t i = 0; i < n; ++i) {
        if (!live[i]) continue;
        Instr in = std::move(f.body[i]);
        for (ValueId& a : in.args) a = map[a];
        map[i] = ValueId(body.size());
        body.push_back(std::move(in));
    }
    int removed = int(n - body.size());
    f.body = std::move(body);
    f.result = map[f.result];
    for (auto& [name, v] : f.outputs) v = map[v];
    return removed;
}

int eliminate_dead_code(Module& m) {
    int removed = 0;
    for (auto& f : m.functions) removed += eliminate_dead_code(f);
    bool any_entry = false;
    for (const auto& f : m.functions) any_entry |= f.entry;
    if (!any_entry) return removed;
    std::vector<bool> fn_live(m.functions.size(), false), g_live(m.globals.size(), false);
    std::function<void(int)> reach = [&](int fi) {
        if (fn_live[size_t(fi)]) return;
        fn_live[size_t(fi)] = true;
        for (const Instr& in : m.functions[size_t(fi)].body) {
            if (in.op == Op::Call || in.op == Op::Loop) reach(in.aux);
            if (in.op == Op::Global) g_live[size_t(in.aux)] = true;
        }
    };
    for (size_t i = 0; i < m.functions.size(); ++i)
        if (m.functions[i].entry) reach(int(i));
    // Prepared globals are computed by iqc_prepare, which stays while any of them is read (and computes only
    // those).
    int prep = m.find(names::kPrepare);
    if (prep >= 0 && !fn_live[size_t(prep)]) {
        Function& p = m.functions[size_t(prep)];
        std::vector<std::pair<std::string, ValueId>> kept;
        const auto index = m.global_index();
        for (const auto& o : p.outputs)
            if (auto g = index.find(o.first); g != index.end() && g_live[size_t(g->second)]) kept.push_back(o);
        if (!kept.empty()) {
            p.outputs = std::move(kept);
            p.result = p.outputs[0].second;
            removed += eliminate_dead_code(p);
            reach(prep);
        }
    }
    std::vector<int> fmap(m.functions.size(), -1), gmap(m.globals.size(), -1);
    std::vector<Function> fns;
    for (size_t i = 0; i < m.functions.size(); ++i)
        if (fn_live[i]) {
            fmap[i] = int(fns.size());
            fns.push_back(std::move(m.functions[i]));
        }
    std::vector<Global> gs;
    for (size_t i = 0; i < m.globals.size(); ++i)
        if (g_live[i]) {
            gmap[i] = int(gs.size());
            gs.push_back(std::move(m.globals[i]));
        }
    for (auto& f : fns)
        for (Instr& in : f.body) {
            if (in.op == Op::Call || in.op == Op::Loop) in.aux = fmap[size_t(in.aux)];
            if (in.op == Op::Global) in.aux = gmap[size_t(in.aux)];
        }
    m.functions = std::move(fns);
    m.globals = std::move(gs);
    return removed;
}

}  // namespace iqc::ir
