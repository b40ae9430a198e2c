#include "ir/passes/MergeCalls.h"

#include <map>
#include <tuple>

#include "ir/Builder.h"

namespace iqc::ir {

int merge_switch_calls(Module& m) {
    int merged = 0;
    for (Function& f : m.functions) {
        // Only functions with a switch of two distinct calls to one function are rebuilt.
        bool any = false;
        for (const Instr& in : f.body) {
            if (in.op != Op::Switch) continue;
            std::map<int, ValueId> first_call;
            for (size_t k = 2; k < in.args.size(); ++k) {
                const Instr& v = f.body[in.args[k]];
                if (v.op != Op::Call) continue;
                auto [it, fresh] = first_call.emplace(v.aux, in.args[k]);
                any |= !fresh && it->second != in.args[k];
            }
        }
        if (!any) continue;
        std::vector<Instr> old = std::move(f.body);
        f.body.clear();
        f.body.reserve(old.size());
        std::vector<ValueId> map(old.size());
        Builder b(m, f);
        for (size_t i = 0; i < old.size(); ++i) {
            const Instr& in = old[i];
            if (in.op == Op::Switch) {
                // The cases' calls grouped by callee, in case order.
                int n = switch_cases(in);
                std::map<int, std::vector<int>> groups;
                for (int k = 0; k < n; ++k) {
                    const Instr& v = old[in.args[size_t(k) + 2]];
                    if (v.op == Op::Call) groups[v.aux].push_back(k);
                }
                std::vector<ValueId> value(static_cast<size_t>(n));
                for (int k = 0; k < n; ++k) value[size_t(k)] = map[in.args[size_t(k) + 2]];
                bool changed = false;
                for (const auto& [callee, cases] : groups) {
                    bool distinct = false;  // two cases may share one call already
                    for (int k : cases) distinct |= in.args[size_t(k) + 2] != in.args[size_t(cases[0]) + 2];
                    if (!distinct) continue;
                    const Instr& first = old[in.args[size_t(cases[0]) + 2]];
                    // An array argument that differs between the cases (each instance's own sequence, x_i ∈ ℝ³)
                    // would be switched whole: a local copy of the array per evaluation, which llvmpipe runs as
                    // stores and loads of every element (a trial's three instances with 300-vector sequences in
                    // uniform blocks: 71 s a frame at 160x90 against 62 ms with constants). Those calls stay apart.
                    bool array_differs = false;
                    for (size_t a = 0; a < first.args.size(); ++a) {
                        if (!old[first.args[a]].type.is_array()) continue;
                        for (int k : cases) array_differs |= old[in.args[size_t(k) + 2]].args[a] != first.args[a];
                    }
                    if (array_differs) continue;
                    std::vector<ValueId> args;
                    for (size_t a = 0; a < first.args.size(); ++a) {
                        bool same = true;
                        for (int k : cases) same &= old[in.args[size_t(k) + 2]].args[a] == first.args[a];
                        if (same) {
                            args.push_back(map[first.args[a]]);
                            continue;
                        }
                        std::vector<std::tuple<long long, long long, ValueId>> arg_cases;
                        // One case's argument is the default (outside these cases the value is not used), so the
                        // cases that pass it need no case of their own: the first case's, or, where computing it
                        // for another id could read a table out of its range (a group's `k_d[id - 1]` where the
                        // merged call runs for every id: the backend computes a switch's default first), the first
                        // argument that is safe; where none is, zero, and every case has its own.
                        ValueId fallback = first.args[a];
                        bool found = speculatable_expression(old, fallback, [](ValueId) { return false; });
                        for (size_t j = 0; j < cases.size() && !found; ++j) {
                            fallback = old[in.args[size_t(cases[j]) + 2]].args[a];
                            found = speculatable_expression(old, fallback, [](ValueId) { return false; });
                        }
                        const Type& at = old[first.args[a]].type;
                        ValueId dflt;
                        if (found) {
                            dflt = map[fallback];
                        } else if (!at.is_array() && at.kind != Type::Tuple) {
                            dflt = b.constant(at, std::vector<double>(size_t(std::max(1, at.components())), 0.0));
                        } else {
                            dflt = map[first.args[a]];
                        }
                        for (int k : cases)
                            if (map[old[in.args[size_t(k) + 2]].args[a]] != dflt)
                                arg_cases.push_back({(long long)in.data[size_t(2 * k)], (long long)in.data[size_t(2 * k + 1)],
                                                     map[old[in.args[size_t(k) + 2]].args[a]]});
                        args.push_back(b.switch_(map[in.args[0]], dflt, std::move(arg_cases)));
                    }
                    ValueId call = b.call(callee, std::move(args));
                    f.body[call].name = first.name;
                    f.body[call].source = first.source;
                    f.body[call].span = first.span;
                    for (int k : cases) value[size_t(k)] = call;
                    merged += int(cases.size()) - 1;
                    changed = true;
                }
                if (changed) {
                    std::vector<std::tuple<long long, long long, ValueId>> cs;
                    for (int k = 0; k < n; ++k)
                        cs.push_back({(long long)in.data[size_t(2 * k)], (long long)in.data[size_t(2 * k + 1)], value[size_t(k)]});
                    ValueId s = b.switch_(map[in.args[0]], map[in.args[1]], std::move(cs));
                    f.body[s].name = in.name;
                    f.body[s].source = in.source;
                    f.body[s].span = in.span;
                    map[i] = s;
                    continue;
                }
            }
            Instr copy = in;
            for (ValueId& a : copy.args) a = map[a];
            map[i] = f.add(std::move(copy));
        }
        f.result = map[f.result];
        for (auto& [name, v] : f.outputs) v = map[v];
    }
    return merged;
}

}  // namespace iqc::ir
