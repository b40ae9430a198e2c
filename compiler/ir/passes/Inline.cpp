#include "ir/passes/Inline.h"

namespace iqc::ir {

namespace {

struct Inliner {
    const Module& m;
    bool only_marked;
    int inlined = 0;
    const std::function<bool(const Function&)>* keep = nullptr;
    bool float_arguments = false;  // constant arguments of calls the backend keeps, rounded to float

    bool wanted(const Instr& in) const {
        if (in.op != Op::Call) return false;
        const Function& callee = m.functions[size_t(in.aux)];
        if (keep && (*keep)(callee)) return false;
        return !only_marked || callee.inline_hint;
    }

    // Appends callee's body to `out` with its parameters bound to `args`; returns the result's new id.
    ValueId into(const Function& callee, const std::vector<ValueId>& args, Function& out) {
        ++inlined;
        std::vector<ValueId> map(callee.body.size());
        for (size_t i = 0; i < callee.body.size(); ++i) {
            const Instr& in = callee.body[i];
            if (in.op == Op::Param) {
                map[i] = args[size_t(in.aux)];
                // The shader passes a constant argument to a function it keeps (not a building block) as a
                // float literal: 10000000.49 as 10000000, whose sine differs by 0.4.
                if (float_arguments && !callee.inline_hint && map[i] < out.body.size()) {
                    const Instr& a = out.body[map[i]];
                    if (a.op == Op::Const && a.type.kind != Type::Integer && a.type.elem != Type::Integer) {
                        Instr r = a;
                        bool changed = false;
                        for (double& x : r.data) {
                            const double f = double(float(x));
                            changed |= f != x;
                            x = f;
                        }
                        if (changed) {
                            r.name.clear();
                            map[i] = out.add(std::move(r));
                        }
                    }
                }
                continue;
            }
            std::vector<ValueId> a;
            for (ValueId x : in.args) a.push_back(map[x]);
            if (wanted(in)) {
                map[i] = into(m.functions[size_t(in.aux)], a, out);
                continue;
            }
            Instr c = in;
            c.args = std::move(a);
            // A scene building block's names (q, bound) stay readable in the function it joins; other
            // inlined values keep none (the caller's names stay readable).
            if (!callee.inline_hint) c.name.clear();
            map[i] = out.add(std::move(c));
        }
        return map[callee.result];
    }
};

}  // namespace

static Function inline_some(const Module& m, const Function& f, const std::function<bool(const Function&)>* keep, bool only_marked,
                            bool float_arguments = false);

Function inline_calls(const Module& m, const Function& f, bool only_marked) {
    return inline_some(m, f, nullptr, only_marked);
}

Function inline_calls_except(const Module& m, const Function& f, const std::function<bool(const Function&)>& keep) {
    return inline_some(m, f, &keep, false);
}

Function inline_calls_as_emitted(const Module& m, const Function& f) { return inline_some(m, f, nullptr, false, true); }

static Function inline_some(const Module& m, const Function& f, const std::function<bool(const Function&)>* keep, bool only_marked,
                            bool float_arguments) {
    Inliner il{m, only_marked};
    il.keep = keep;
    il.float_arguments = float_arguments;
    Function out = f;
    out.body.clear();
    out.outputs.clear();
    std::vector<ValueId> map(f.body.size());
    for (size_t i = 0; i < f.body.size(); ++i) {
        const Instr& in = f.body[i];
        std::vector<ValueId> a;
        for (ValueId x : in.args) a.push_back(map[x]);
        if (il.wanted(in)) {
            size_t first = out.body.size();
            map[i] = il.into(m.functions[size_t(in.aux)], a, out);
            Instr& r = out.body[map[i]];
            if (!in.name.empty() && map[i] >= first && r.op != Op::Param && (r.name.empty() || m.functions[size_t(in.aux)].inline_hint)) {
                r.name = in.name;  // the call's name goes to the value it computed
                r.source = in.source;
            } else if (!in.name.empty()) {  // keep the caller's named statement
                Instr cp;
                cp.op = Op::Copy;
                cp.type = in.type;
                cp.args = {map[i]};
                cp.name = in.name;
                cp.source = in.source;
                cp.span = in.span;
                map[i] = out.add(std::move(cp));
            }
            continue;
        }
        Instr c = in;
        c.args = std::move(a);
        map[i] = out.add(std::move(c));
    }
    out.result = f.body.empty() ? 0 : map[f.result];
    for (const auto& [n, v] : f.outputs) out.outputs.push_back({n, map[v]});
    return out;
}

int inline_marked(Module& m) {
    int total = 0;
    for (size_t i = 0; i < m.functions.size(); ++i) {
        bool any = false;
        for (const Instr& in : m.functions[i].body) any |= in.op == Op::Call && m.functions[size_t(in.aux)].inline_hint;
        if (!any) continue;
        Function g = inline_calls(m, m.functions[i], true);
        for (const Instr& in : m.functions[i].body) total += in.op == Op::Call && m.functions[size_t(in.aux)].inline_hint;
        m.functions[i] = std::move(g);
    }
    return total;
}

}  // namespace iqc::ir
